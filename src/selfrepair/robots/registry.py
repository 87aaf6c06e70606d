"""Domains by name: for table files, traces, experiment configs and the command line.

Library functions take :class:`~selfrepair.robots.domain.Domain` values; a name is looked up only
where text names a robot. Three sources, in this order:

1. domains registered in this process with :func:`register_domain`;
2. the built-in domains (``four-wheel``, ``three-action``), imported on first use;
3. installed plug-ins: an entry point in the group ``selfrepair.domains`` whose object is a
   ``Domain`` (e.g. ``omni = "mypackage.robots:OMNI"`` under
   ``[project.entry-points."selfrepair.domains"]``), so the command line finds a third-party robot
   without any code change here.

Built-ins and plug-ins are named here as ``"module:attribute"`` strings and imported by name, so
that the generic layers (tables, repair) that look domains up never import a concrete robot.

A robot defined in a plain Python file (not an installed package) is a *plug-in file*:
:func:`load_plugin` runs it once per process, and the file registers its domain with
:func:`register_domain`. The command line's ``--plugin FILE`` and an experiment file's
``plugins = [...]`` key do exactly that (an experiment's worker processes load the same files before
they run a mission). The registry remembers which plug-in file (resolved path and SHA-256 of its
content) registered each domain, :func:`plugin_file`, so that results and traces can name the
exact robot however it was loaded.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import sys
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path

from selfrepair.errors import InputError, ProblemError
from selfrepair.robots.domain import Domain, SomeDomain, check_domain

__all__ = [
    "ENTRY_POINT_GROUP",
    "PluginFile",
    "domain_names",
    "get_domain",
    "load_plugin",
    "load_recorded_plugin",
    "plugin_file",
    "register_domain",
]

ENTRY_POINT_GROUP = "selfrepair.domains"

_BUILTIN = {
    "four-wheel": "selfrepair.robots.four_wheel:FOUR_WHEEL",
    "three-action": "selfrepair.robots.three_action:THREE_ACTION",
}
_REGISTERED: dict[str, SomeDomain] = {}


def register_domain(domain: SomeDomain, *, replace: bool = False) -> SomeDomain:
    """Make ``domain`` known by its name (after :func:`check_domain`); returns it.

    A second domain under a name already in use raises :class:`ProblemError` unless ``replace``.
    """
    check_domain(domain)
    current = _REGISTERED.get(domain.name)
    taken = domain.name in _BUILTIN or (current is not None and current is not domain)
    if taken and not replace:
        raise ProblemError(
            f"a domain named {domain.name!r} is already registered; pass replace=True to replace it"
        )
    _REGISTERED[domain.name] = domain
    return domain


def get_domain(name: str) -> SomeDomain:
    """The domain called ``name``; an unknown name raises :class:`InputError` listing the known
    ones."""
    domain = _REGISTERED.get(name)
    if domain is not None:
        return domain
    target = _BUILTIN.get(name) or _plugins().get(name)
    if target is None:
        raise InputError(
            f"expected a domain name ({', '.join(domain_names())}), got {name!r}",
            source="<domain>",
        )
    domain = _load(name, target)
    _REGISTERED[name] = domain
    return domain


def domain_names() -> tuple[str, ...]:
    """Every domain name that :func:`get_domain` accepts, sorted."""
    return tuple(sorted({*_BUILTIN, *_REGISTERED, *_plugins()}))


def _plugins() -> dict[str, str]:
    return {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP)}


def _load(name: str, target: str) -> SomeDomain:
    module_name, _, attribute = target.partition(":")
    try:
        value = getattr(importlib.import_module(module_name), attribute)
    except (ImportError, AttributeError) as exc:
        raise ProblemError(f"domain {name!r}: cannot load {target!r}: {exc}") from None
    if not isinstance(value, Domain) or value.name != name:
        raise ProblemError(f"domain {name!r}: {target!r} is not a Domain named {name!r}")
    check_domain(value)
    return value


@dataclass(frozen=True, slots=True)
class PluginFile:
    """The plug-in file that registered a domain: its resolved path and the SHA-256 of the
    content that was run."""

    path: str
    sha256: str


_ORIGINS: dict[str, PluginFile] = {}
"""Domain name -> the plug-in file whose run registered it."""


def plugin_file(name: str) -> PluginFile | None:
    """The plug-in file that registered domain ``name`` in this process (``None`` for a built-in
    domain, an installed entry point, or one registered from imported code)."""
    return _ORIGINS.get(name)


_PLUGINS: dict[str, str] = {}
"""Plug-in files run in this process: resolved path -> SHA-256 of the content that was run."""
_RUN: set[str] = set()
"""The SHA-256 of every plug-in content run in this process (a copy of a file is not run twice)."""


def load_plugin(path: str | Path) -> str:
    """Run the plug-in file ``path`` (a Python file that registers one or more domains) unless
    this process already ran it, or a file with the same content; returns the SHA-256 of its
    content.

    Raises :class:`InputError` naming the file when it cannot be read or fails while running, and
    when the same path is asked for again after its content changed (a process keeps the robot
    it started with).
    """
    file = Path(path)
    try:
        data = file.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read plug-in file: {exc.strerror}", source=str(file)) from None
    digest = hashlib.sha256(data).hexdigest()
    key = str(file.resolve())
    done = _PLUGINS.get(key)
    if done is not None:
        if done != digest:
            raise InputError(
                "the plug-in file changed since this process loaded it", source=str(file)
            )
        return digest
    if digest in _RUN:
        _PLUGINS[key] = digest
        return digest
    name = f"selfrepair_plugin_{digest[:16]}"
    spec = importlib.util.spec_from_file_location(name, file)
    if spec is None or spec.loader is None:
        raise InputError("expected a Python file (.py)", source=str(file))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    before = dict(_REGISTERED)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the file is the user's code: any failure is bad input
        del sys.modules[name]
        raise InputError(
            f"the plug-in file failed: {type(exc).__name__}: {exc}", source=str(file)
        ) from None
    _PLUGINS[key] = digest
    _RUN.add(digest)
    origin = PluginFile(key, digest)
    for registered, domain in _REGISTERED.items():
        if before.get(registered) is not domain:
            _ORIGINS[registered] = origin
    return digest


def load_recorded_plugin(name: str, recorded: PluginFile, what: str) -> None:
    """Make domain ``name`` known as a file (``what``: ``"trace"``, ...) recorded it: from the
    plug-in file ``recorded`` when the domain is not registered yet and that file still has the
    recorded content. Raises :class:`InputError` (one line, naming the ``--plugin`` flag to pass)
    when the file cannot be read or changed, and when this process has ``name`` from a plug-in
    file of other content (the file would be read against another robot). A domain registered
    from code (an entry point, an import) is taken as it is."""
    flag = f"pass --plugin FILE with the {name} robot the {what} was written with"
    digest = recorded.sha256
    loaded = plugin_file(name)
    if loaded is not None:
        if loaded.sha256 != digest:
            raise InputError(
                f"the {what}'s robot {name!r} comes from plug-in content {digest[:12]} "
                f"({recorded.path}), but this process loaded {name!r} from {loaded.path} "
                f"(content {loaded.sha256[:12]}): {flag}"
            )
        return
    if name in domain_names():
        return
    path = Path(recorded.path)
    try:
        found = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        raise InputError(
            f"the {what}'s robot {name!r} comes from the plug-in file {path}, which cannot be "
            f"read here: {flag}"
        ) from None
    if found != digest:
        raise InputError(
            f"the {what}'s robot {name!r} comes from the plug-in file {path}, which changed "
            f"since the {what} was written (content {digest[:12]}, now {found[:12]}): {flag}"
        )
    load_plugin(path)
