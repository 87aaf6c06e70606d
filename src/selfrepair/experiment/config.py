"""Experiment configuration: a TOML file read into a validated, frozen :class:`ExperimentConfig`.

The file format is described in ``docs/experiments.md``; in short::

    name = "paper"
    seed = 2024                  # base seed; every mission's seed derives from it
    repeats = 1                  # seeds per mission

    domain = "four-wheel"        # the robot: a name in the domain registry (default four-wheel)
    plugins = []                 # Python files that register robots (paths relative to this file)

    [[mazes]]
    bundled = "narrow-short"     # or file = "x.maze" / generate = {width=.., height=.., ...}
    routes = "bundled"           # or a count of random routes, or [{start="1,1,E", goal="9,9"}]

    [faults]
    sets = "paper"               # paper | singles | doubles | all | ["FL:F", "FL:F,RR:B"]
    at = [0]                     # step index at which the faults appear (0: from the start)
    detection = ["now"]          # now | on-use

    [planner]
    clearance_weights = [0]
    clearance_radius = 2

    [[strategies]]
    name = "replacement"         # replan | replacement | lookahead | dstar-lite | lpg-adapt
    tables = ["handwritten"]
    recursion = ["guarded"]
    rewrite = [false, true]      # per encounter, and whole-plan rewriting (default false)
    mazes = ["narrow-short"]     # optional, any strategy: run it on these mazes only

    [[strategies]]
    name = "replan"
    backend = "python"           # (replan, dstar-lite) the planner backend: auto | numba | python

    [[strategies]]
    name = "lpg-adapt"           # needs the pddl extra
    time_limit = 5               # seconds per LPG-adapt call
    seed = 0                     # LPG's seed
    optional = true              # left out (reason printed) where it cannot run, not refused

The schema is :mod:`selfrepair.experiment.schema`, the robot and its plug-ins are found by
:mod:`selfrepair.robots.fromfile`, and the TOML reading and error mapping are shared with team
scenarios (:mod:`selfrepair.tomlfile`). Validation uses pydantic; every problem becomes a
:class:`~selfrepair.errors.ConfigError` that names the file, the key (as a dotted path such as
``strategies[1].tables``), its line when it can be found in the text, and what was expected.
Integers are strict (``repeats = true`` or ``seed = 1.0`` is refused, not read as 1), numbers
refuse booleans, lists of routes are not empty, clearance weights lie in ``[0,
MAX_CLEARANCE_WEIGHT]`` (:mod:`selfrepair.limits`), and a file that is not UTF-8, nests too deep or
has an integer of thousands of digits is a ``ConfigError`` with its line. A leading UTF-8 byte-
order mark is ignored.
"""

from __future__ import annotations

from pathlib import Path

from pydantic import ValidationError

from selfrepair.errors import ConfigError
from selfrepair.experiment.schema import STRATEGY_TAGS, ExperimentConfig
from selfrepair.limits import MAX_FILE_BYTES
from selfrepair.robots.fromfile import file_domain, load_plugins
from selfrepair.textio import read_text, strip_bom
from selfrepair.tomlfile import find_line, read_toml, validate, validation_error

__all__ = [
    "config_error",
    "find_line",
    "load_config",
    "parse_config",
    "read_experiment_text",
    "read_toml",
]


def load_config(
    path: str | Path, *, max_file_bytes: int | None = MAX_FILE_BYTES
) -> ExperimentConfig:
    """Read and validate an experiment TOML file (refused unread if over ``max_file_bytes``)."""
    text, source = read_experiment_text(path, max_file_bytes=max_file_bytes)
    return parse_config(text, source=source)


def read_experiment_text(
    path: str | Path, *, max_file_bytes: int | None = MAX_FILE_BYTES
) -> tuple[str, str]:
    """The text of the experiment file ``path`` and its absolute path as the error source (a
    file over ``max_file_bytes`` is refused unread)."""
    file = Path(path)
    text = read_text(
        file,
        what="experiment file",
        error=ConfigError,
        max_bytes=max_file_bytes,
        limit="max_file_bytes",
    )
    return text, str(file.resolve())


def parse_config(text: str, *, source: str = "<string>") -> ExperimentConfig:
    """Parse and validate experiment TOML text; ``source`` names it in errors."""
    text = strip_bom(text)
    data = read_toml(text, source=source)
    if "source" in data:
        raise ConfigError("unknown key 'source' (it is set by the loader)", source=source)
    load_plugins(data, text, source)
    domain = file_domain(data, text, source)
    return validate(
        ExperimentConfig,
        {**data, "source": source},
        text=text,
        source=source,
        context={"domain": domain},
        tags=STRATEGY_TAGS,
        tag_name="strategy name",
    )


def config_error(exc: ValidationError, text: str, source: str) -> ConfigError:
    """The most telling problem of an experiment file's validation as a ConfigError naming key,
    line and expectation (:func:`selfrepair.tomlfile.validation_error` with the strategy tags)."""
    return validation_error(exc, text, source, tags=STRATEGY_TAGS, tag_name="strategy name")
