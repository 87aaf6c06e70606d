"""The robot a file names: its plug-in files run, its domain looked up, before the rest of the
file is validated (validators need the robot to read fault texts). Experiment files
(:mod:`selfrepair.experiment.config`) and team scenarios (:mod:`selfrepair.team.scenario`) both
name their robot with the keys ``plugins`` and ``domain``.

Both steps raise a :class:`~selfrepair.errors.ConfigError` naming the file, the line of the key
(``plugins`` or ``domain``) and what was expected.
"""

from __future__ import annotations

from collections.abc import Mapping

from selfrepair.errors import ConfigError, InputError
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.registry import get_domain, load_plugin
from selfrepair.textio import source_dir
from selfrepair.tomlfile import find_line

__all__ = ["DEFAULT_DOMAIN", "file_domain", "load_plugins"]

DEFAULT_DOMAIN = "four-wheel"
"""The robot of a file that names none."""


def load_plugins(data: Mapping[str, object], text: str, source: str) -> None:
    """Run the plug-in files the file names (key ``plugins``, paths relative to the file) so
    that the domain it names can be found."""
    plugins = data.get("plugins", [])
    line = find_line(text, ("plugins",))
    if not isinstance(plugins, list) or not all(isinstance(p, str) for p in plugins):
        raise ConfigError(
            f"key 'plugins': expected a list of file paths, got {plugins!r}",
            source=source,
            line=line,
        )
    base = source_dir(source)
    for plugin in plugins:
        try:
            load_plugin(base / plugin)
        except InputError as exc:
            raise ConfigError(f"key 'plugins': {exc}", source=source, line=line) from None


def file_domain(data: Mapping[str, object], text: str, source: str) -> SomeDomain:
    """The robot the file names (key ``domain``, default four-wheel), looked up in the registry."""
    name = data.get("domain", DEFAULT_DOMAIN)
    line = find_line(text, ("domain",))
    if not isinstance(name, str):
        raise ConfigError(
            f"key 'domain': expected a domain name, got {name!r}", source=source, line=line
        )
    try:
        return get_domain(name)
    except InputError as exc:
        raise ConfigError(f"key 'domain': {exc.reason}", source=source, line=line) from None
