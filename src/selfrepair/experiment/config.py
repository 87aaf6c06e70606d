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
    backend = "python"           # the planner backend of its missions: auto | numba | python

    [[strategies]]
    name = "lpg-adapt"           # needs the pddl extra
    time_limit = 5               # seconds per LPG-adapt call
    seed = 0                     # LPG's seed

Validation uses pydantic; every problem becomes a :class:`~selfrepair.errors.ConfigError` that
names the file, the key (as a dotted path such as ``strategies[1].tables``), its line when it can
be found in the text, and what was expected. Integers are strict (``repeats = true`` or
``seed = 1.0`` is refused, not read as 1), numbers refuse booleans, lists of routes are not empty,
clearance weights lie in ``[0, MAX_CLEARANCE_WEIGHT]`` (:mod:`selfrepair.limits`), and a file that
is not UTF-8, nests too deep or has an integer of thousands of digits is a ``ConfigError`` with its
line. A leading UTF-8 byte-order mark is ignored.
"""

from __future__ import annotations

import re
import tomllib
from fractions import Fraction
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from selfrepair.errors import ConfigError, InputError
from selfrepair.execution.faults import Clock, Detection, Persistence
from selfrepair.geometry import parse_cell, parse_pose
from selfrepair.limits import MAX_CLEARANCE_WEIGHT, MAX_FILE_BYTES
from selfrepair.repair.replacement import DEFERRING, RecursionMode
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import get_domain, load_plugin
from selfrepair.textio import read_text, strip_bom, text_lines
from selfrepair.world.routes import MAX_ROUTES

__all__ = [
    "FAULT_PROFILES",
    "DStarLiteStrategy",
    "ExperimentConfig",
    "FaultsConfig",
    "GeneratedMaze",
    "LookaheadStrategy",
    "LpgAdaptStrategy",
    "MazeConfig",
    "PlannerConfig",
    "ReplacementStrategy",
    "ReplanStrategy",
    "RouteConfig",
    "StrategyConfig",
    "config_error",
    "find_line",
    "load_config",
    "parse_config",
    "read_experiment_text",
    "read_toml",
]

FAULT_PROFILES = ("paper", "singles", "doubles", "all")
"""Named fault-set profiles; see :func:`selfrepair.experiment.faultsets.fault_profile`."""

PAPER_ONLY = frozenset({"paper"})
"""Profiles defined for the four-wheel robot only."""

DEFAULT_DOMAIN = "four-wheel"
"""The robot of an experiment file that names none."""

# Strict numbers: TOML has real booleans and floats, and ``true`` or ``1.0`` where an integer is
# expected is a mistake to report, not a 1 to guess (pydantic's lax mode would take both).
Int = Annotated[int, Field(strict=True)]
Float = Annotated[float, Field(strict=True)]  # strict floats still take integers, not booleans


class _Frozen(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", strict=False)


def _non_empty(value: tuple[Any, ...]) -> tuple[Any, ...]:
    if not value:
        raise ValueError("expected a non-empty list")
    return value


NonEmpty = AfterValidator(_non_empty)
"""Marks a list option that must hold at least one item: ``Annotated[tuple[X, ...], NonEmpty]``
(an empty list in a configuration is an error naming the key, not an empty sweep)."""


class GeneratedMaze(_Frozen):
    """Options of :func:`selfrepair.world.mazegen.generate_maze`."""

    width: Annotated[Int, Field(ge=5, le=1024)]
    height: Annotated[Int, Field(ge=5, le=1024)]
    corridor: Annotated[Int, Field(ge=1, le=64)] = 1
    braid: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.0
    seed: Int = 0


class RouteConfig(_Frozen):
    """One explicit route: a start pose ``"X,Y,H"`` and a goal cell ``"X,Y"``."""

    start: str
    goal: str
    name: str | None = None

    @field_validator("start")
    @classmethod
    def _pose(cls, value: str) -> str:
        return str(_reraise(parse_pose, value))

    @field_validator("goal")
    @classmethod
    def _cell(cls, value: str) -> str:
        x, y = _reraise(parse_cell, value)
        return f"{x},{y}"


class MazeConfig(_Frozen):
    """Where a maze comes from (exactly one of ``bundled``, ``file``, ``generate``) and its routes.

    ``routes`` is ``"bundled"`` (the bundled maze's route file), a number of random routes (drawn
    from the experiment seed), or a list of explicit routes.
    """

    bundled: str | None = None
    file: str | None = None
    generate: GeneratedMaze | None = None
    routes: (
        Literal["bundled"]
        | Annotated[Int, Field(ge=1, le=MAX_ROUTES)]
        | Annotated[tuple[RouteConfig, ...], Field(min_length=1)]
    ) = "bundled"

    @model_validator(mode="after")
    def _one_source(self) -> MazeConfig:
        given = [k for k in ("bundled", "file", "generate") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "expected exactly one of 'bundled', 'file' or 'generate', got "
                + (", ".join(repr(k) for k in given) or "none")
            )
        if self.routes == "bundled" and self.bundled is None:
            raise ValueError(
                'routes = "bundled" needs a bundled maze; give a number of random routes or a '
                "list of {start, goal} tables"
            )
        return self


class FaultsConfig(_Frozen):
    """Which fault sets, when they appear (``at``, in steps or ticks per ``clock``), how long they
    last (``persistence`` with ``duration`` or ``probability``) and how they are detected."""

    sets: Literal["paper", "singles", "doubles", "all"] | tuple[str, ...] = "paper"
    at: Annotated[tuple[Annotated[Int, Field(ge=0)], ...], NonEmpty] = (0,)
    clock: Clock = Clock.STEP
    detection: Annotated[tuple[Detection, ...], NonEmpty] = (Detection.NOW,)
    persistence: Persistence = Persistence.PERMANENT
    duration: Annotated[Int, Field(ge=1)] | None = None
    probability: Annotated[Float, Field(ge=0.0, le=1.0)] | None = None

    @model_validator(mode="after")
    def _persistence_options(self) -> FaultsConfig:
        if self.persistence is Persistence.TRANSIENT and self.duration is None:
            raise ValueError("persistence = \"transient\" needs a 'duration' (>= 1)")
        if self.persistence is Persistence.INTERMITTENT and self.probability is None:
            raise ValueError("persistence = \"intermittent\" needs a 'probability' in [0, 1]")
        return self

    @field_validator("sets")
    @classmethod
    def _sets(cls, value: str | tuple[str, ...], info: ValidationInfo) -> str | tuple[str, ...]:
        domain = _domain(info)
        if isinstance(value, str):
            if value in PAPER_ONLY and domain.name != "four-wheel":
                raise ValueError(
                    f'the "{value}" profile is defined for the four-wheel robot; for '
                    f"{domain.name!r} use singles, doubles, all or a list of fault sets"
                )
            return value
        if not value:
            raise ValueError("expected at least one fault set")
        return tuple(domain.format_faults(_reraise(domain.parse_faults, text)) for text in value)



MazeNames = Annotated[tuple[str, ...], Field(min_length=1)] | None
"""A strategy's ``mazes``: the labels of the experiment's mazes it runs on (all when absent)."""


class PlannerConfig(_Frozen):
    """Planner options shared by every strategy unless a strategy overrides the weights."""

    clearance_weights: tuple[str, ...] = ("0",)
    clearance_radius: Annotated[Int, Field(ge=0, le=64)] = 2

    @field_validator("clearance_weights", mode="before")
    @classmethod
    def _weights(cls, value: Any) -> Any:
        return _weights(value)


class _StrategyEntry(_Frozen):
    """What every strategy entry has: its own clearance weights (else the planner's) and the
    labels of the mazes it runs on (else all)."""

    clearance_weights: tuple[str, ...] | None = None
    mazes: MazeNames = None

    @field_validator("clearance_weights", mode="before")
    @classmethod
    def _weights(cls, value: Any) -> Any:
        return _weights(value)


class ReplanStrategy(_StrategyEntry):
    """The baseline: replan from scratch at every faulty encounter, with the planner ``backend``
    (``auto``: the compiled kernels when numba is installed; ``python``: the pure-Python search,
    to compare with pure-Python strategies such as D* Lite)."""

    name: Literal["replan"]
    backend: Literal["auto", "numba", "python"] = "auto"


class ReplacementStrategy(_StrategyEntry):
    """Replacement tables with recursion mode; one variant per table, mode and ``rewrite``
    value (``true``: whole-plan rewriting, ``[false, true]``: both; default per encounter)."""

    name: Literal["replacement"]
    tables: Annotated[tuple[str, ...], NonEmpty] = ("handwritten",)
    recursion: Annotated[tuple[RecursionMode, ...], NonEmpty] = (RecursionMode.GUARDED,)
    rewrite: tuple[bool, ...] = (False,)

    @field_validator("rewrite", mode="before")
    @classmethod
    def _rewrite(cls, value: Any) -> Any:
        if isinstance(value, bool):
            return (value,)
        if isinstance(value, list | tuple) and not value:
            raise ValueError("expected true, false or a non-empty list of them")
        if isinstance(value, list | tuple) and not all(isinstance(v, bool) for v in value):
            raise ValueError(f"expected true, false or a list of them, got {value!r}")
        return value


    @model_validator(mode="after")
    def _rewrite_modes(self) -> ReplacementStrategy:
        deferring = [str(m) for m in self.recursion if m in DEFERRING]
        if any(self.rewrite) and deferring:
            raise ValueError(
                f"rewrite is not available with {', '.join(deferring)} recursion (its "
                "replacements may keep faulty actions for later); list those modes in a "
                "strategy without rewrite"
            )
        return self


class LookaheadStrategy(ReplacementStrategy):
    """Replace a window of ``window`` actions after the faulty one and, when the fault is known
    ahead, ``before`` actions before it; one variant per (window, before) pair."""

    name: Literal["lookahead"]  # type: ignore[assignment]
    window: tuple[Annotated[Int, Field(ge=0, le=64)], ...] = (3,)
    before: tuple[Annotated[Int, Field(ge=0, le=64)], ...] = (0,)

    @field_validator("rewrite")
    @classmethod
    def _no_rewrite(cls, value: tuple[bool, ...]) -> tuple[bool, ...]:
        if any(value):
            raise ValueError("rewrite applies to the replacement strategy only")
        return value


class DStarLiteStrategy(_StrategyEntry):
    """D* Lite, incremental replanning (pure Python), keeping its search between repairs."""

    name: Literal["dstar-lite"]


class LpgAdaptStrategy(_StrategyEntry):
    """Plan repair with LPG-adapt (``pddl`` extra, four-wheel robot): ``time_limit`` seconds per
    call, LPG's ``seed``; LPG's failures and time-outs fall back to replanning."""

    name: Literal["lpg-adapt"]
    time_limit: Annotated[Float, Field(gt=0, le=3600)] = 5.0
    seed: Annotated[Int, Field(ge=0, lt=2**31)] = 0

    @field_validator("name")
    @classmethod
    def _runnable(cls, value: str, info: ValidationInfo) -> str:
        """Refuse the strategy before any mission runs where it cannot run (extra, robot)."""
        from selfrepair.baselines.adapt import check_lpg_adapt
        from selfrepair.errors import ProblemError

        try:
            check_lpg_adapt(_domain(info).name)
        except ProblemError as exc:
            raise ValueError(str(exc)) from None
        return value


StrategyConfig = Annotated[
    ReplanStrategy | ReplacementStrategy | LookaheadStrategy | DStarLiteStrategy | LpgAdaptStrategy,
    Field(discriminator="name"),
]


class ExperimentConfig(_Frozen):
    """A whole experiment: the cross product of mazes x routes x fault settings x strategies x
    clearance weights x repeats, for the robot ``domain`` (a name in the domain registry).
    ``source`` is the file it was read from (for error messages and for resolving relative
    paths). ``crossover``: the experiment command also estimates the maze size where
    replacement's repair compute per mission falls below 1/10 of the replanner's
    (:mod:`selfrepair.experiment.scale`); it does not change any mission. ``timing_repeats``:
    warm timing runs per mission (the command line's ``--repeats`` overrides it)."""

    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")]
    description: str = ""
    domain: str = DEFAULT_DOMAIN
    plugins: tuple[str, ...] = ()
    seed: Int = 0
    repeats: Annotated[Int, Field(ge=1, le=1000)] = 1
    crossover: bool = False
    timing_repeats: Annotated[Int, Field(ge=1, le=1000)] = 1
    mazes: Annotated[tuple[MazeConfig, ...], Field(min_length=1)]
    faults: FaultsConfig = FaultsConfig()
    planner: PlannerConfig = PlannerConfig()
    strategies: Annotated[tuple[StrategyConfig, ...], Field(min_length=1)]
    source: str = "<string>"

    @property
    def base_dir(self) -> Path:
        """The directory relative paths in the file are resolved against."""
        return Path(self.source).parent if not self.source.startswith("<") else Path.cwd()


def _weights(value: Any) -> Any:
    """Clearance weights as canonical exact strings (``0.5`` -> ``"1/2"``), each from 0 to
    :data:`~selfrepair.limits.MAX_CLEARANCE_WEIGHT`."""
    if value is None:
        return None
    if not isinstance(value, list | tuple):
        raise ValueError("expected a list of non-negative numbers such as [0, 1, 2.5]")
    if not value:
        raise ValueError("expected a non-empty list")
    out = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, int | float | str):
            raise ValueError(f"expected a non-negative number, got {item!r}")
        try:
            weight = Fraction(str(item))
        except (ValueError, ZeroDivisionError):
            raise ValueError(f"expected a non-negative number, got {item!r}") from None
        if weight < 0:
            raise ValueError(f"expected a non-negative number, got {item!r}")
        if weight > MAX_CLEARANCE_WEIGHT:
            raise ValueError(f"expected a weight of at most {MAX_CLEARANCE_WEIGHT:,}, got {item!r}")
        out.append(str(weight))
    return tuple(out)


def _domain(info: ValidationInfo) -> Domain[Any, Any]:
    context = info.context or {}
    domain = context.get("domain")
    return domain if isinstance(domain, Domain) else get_domain(DEFAULT_DOMAIN)


def _reraise(parser: Any, text: str) -> Any:
    """Run a robot-model parser, turning its InputError into a plain ValueError for pydantic."""
    try:
        return parser(text)
    except InputError as exc:
        raise ValueError(exc.reason) from None


# --- loading -----------------------------------------------------------------------------------


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


def read_toml(text: str, *, source: str = "<string>") -> dict[str, Any]:
    """TOML ``text`` (a byte-order mark dropped) as a dict; every syntax problem is a
    :class:`ConfigError` with its line and column where known."""
    text = strip_bom(text)
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise ConfigError(
            "invalid TOML: arrays or inline tables nested too deep (an experiment needs 3 levels)",
            source=source,
        ) from None
    except tomllib.TOMLDecodeError as exc:
        where = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        reason = re.sub(r"\s*\(at (line \d+, column \d+|end of document)\)", "", str(exc))
        line, column = (int(where.group(1)), int(where.group(2))) if where else (None, None)
        raise ConfigError(
            f"invalid TOML: {reason}", source=source, line=line, column=column
        ) from None
    except ValueError:  # an integer beyond Python's 4300-digit conversion limit
        long = re.search(r"[0-9_]{4300,}", text)
        line = None if long is None else text.count("\n", 0, long.start()) + 1
        raise ConfigError(
            "invalid TOML: expected an integer of at most 4300 digits", source=source, line=line
        ) from None


def parse_config(text: str, *, source: str = "<string>") -> ExperimentConfig:
    """Parse and validate experiment TOML text; ``source`` names it in errors."""
    text = strip_bom(text)
    data = read_toml(text, source=source)
    if "source" in data:
        raise ConfigError("unknown key 'source' (it is set by the loader)", source=source)
    _load_plugins(data, text, source)
    domain = _config_domain(data, text, source)
    try:
        return ExperimentConfig.model_validate(
            {**data, "source": source}, context={"domain": domain}
        )
    except ValidationError as exc:
        raise config_error(exc, text, source) from None


def _load_plugins(data: dict[str, Any], text: str, source: str) -> None:
    """Run the plug-in files the experiment names (key ``plugins``, paths relative to the file)
    so that the domain it names can be found."""
    plugins = data.get("plugins", [])
    line = find_line(text, ("plugins",))
    if not isinstance(plugins, list) or not all(isinstance(p, str) for p in plugins):
        raise ConfigError(
            f"key 'plugins': expected a list of file paths, got {plugins!r}",
            source=source,
            line=line,
        )
    base = Path(source).parent if not source.startswith("<") else Path.cwd()
    for plugin in plugins:
        try:
            load_plugin(base / plugin)
        except InputError as exc:
            raise ConfigError(f"key 'plugins': {exc}", source=source, line=line) from None


def _config_domain(data: dict[str, Any], text: str, source: str) -> Domain[Any, Any]:
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


_TYPE_MISMATCH = ("literal_error", "int_type", "int_parsing", "string_type", "float_type")


def _most_telling(errors: list[Any]) -> Any:
    """For a value that may take several forms (``routes`` is "bundled", a count or a list),
    pydantic reports one error per form. The telling one went deepest into the value, and among
    those, one whose form matched the value's type; otherwise the first error."""

    def rank(error: Any) -> tuple[int, bool]:
        mismatch = error["type"] in _TYPE_MISMATCH or error["type"].endswith("_type")
        return len(error["loc"]), not mismatch

    return max(errors, key=rank)


def config_error(exc: ValidationError, text: str, source: str) -> ConfigError:
    """The most telling validation problem as a ConfigError naming key, line and expectation."""
    error = _most_telling(exc.errors())
    loc = _clean_loc(error["loc"])
    key = _dotted(loc) or "<top level>"
    message = error["msg"].removeprefix("Value error, ")
    if error["type"] == "extra_forbidden":
        message = "unknown key"
    elif error["type"] == "missing":
        message = "missing required key"
    elif error["type"] == "union_tag_invalid":
        loc = (*loc, "name")
        key = _dotted(loc)
        expected = error.get("ctx", {}).get("expected_tags", "")
        message = f"expected a strategy name, one of {expected}"
        got = error.get("input", {}).get("name") if isinstance(error.get("input"), dict) else None
        return ConfigError(
            f"key {key!r}: {message} (got {got!r})", source=source, line=find_line(text, loc)
        )
    elif error["type"] in ("tuple_type", "list_type"):
        message = "expected a list"
    elif error["type"] == "too_short":
        message = f"expected a list of at least {error['ctx']['min_length']} item(s), got none"
    else:
        message = message.replace("Input should be", "expected")
    got = error.get("input")
    if (
        error["type"] not in ("missing", "extra_forbidden")
        and not isinstance(got, dict | list)
        and "got " not in message
    ):
        message += f" (got {got!r})"
    return ConfigError(f"key {key!r}: {message}", source=source, line=find_line(text, loc))


def _clean_loc(loc: tuple[Any, ...]) -> tuple[str | int, ...]:
    """Drop pydantic's union-member tags (e.g. ``'replacement'``, ``'int'``) from a location."""
    out: list[str | int] = []
    for part in loc:
        if isinstance(part, str) and (
            part in ("replan", "replacement", "lookahead", "dstar-lite", "lpg-adapt")
            or "[" in part
            or part in ("int", "str", "tuple", "float", "constrained-int", "function-after")
        ):
            continue
        out.append(part)
    return tuple(out)


def _dotted(loc: tuple[str | int, ...]) -> str:
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text


_HEADER = re.compile(r"^\s*\[\[?\s*([A-Za-z0-9_.\-\"']+)\s*\]\]?")


def find_line(text: str, loc: tuple[str | int, ...]) -> int | None:
    """Best-effort 1-based line of the key at ``loc`` in TOML ``text`` (None when not found).

    Follows ``[[array]]`` headers by index and ``[table]`` headers by name, then looks for
    ``key =`` inside the section found so far.
    """
    lines = text_lines(text)
    start, end = 0, len(lines)
    found: int | None = None
    section = ""
    i = 0
    while i < len(loc):
        part = loc[i]
        nxt = loc[i + 1] if i + 1 < len(loc) else None
        if isinstance(part, int):
            i += 1
            continue
        name = f"{section}.{part}" if section else part
        if isinstance(nxt, int):
            hit = _nth_header(lines, name, nxt, start, end)
            if hit is not None:
                start, end, section, found = hit[0] + 1, hit[1], name, hit[0] + 1
                i += 2
                continue
        hit = _nth_header(lines, name, 0, start, end)
        if hit is not None:
            start, end, section, found = hit[0] + 1, hit[1], name, hit[0] + 1
            i += 1
            continue
        key_line = _key_line(lines, part, start, end)
        if key_line is None:
            return found
        return key_line + 1
    return found


def _nth_header(
    lines: list[str], name: str, index: int, start: int, end: int
) -> tuple[int, int] | None:
    """The (header line, section end) of the ``index``-th ``[name]``/``[[name]]`` header."""
    count = -1
    for n in range(start, end):
        match = _HEADER.match(lines[n])
        if match and match.group(1).strip("\"'") == name:
            count += 1
            if count == index:
                stop = next(
                    (m for m in range(n + 1, len(lines)) if _HEADER.match(lines[m])), len(lines)
                )
                return n, stop
    return None


def _key_line(lines: list[str], key: str, start: int, end: int) -> int | None:
    pattern = re.compile(rf"^\s*[\"']?{re.escape(key)}[\"']?\s*=|[{{,]\s*{re.escape(key)}\s*=")
    for n in range(start, end):
        if _HEADER.match(lines[n]) and n > start:
            break
        if pattern.search(lines[n]):
            return n
    return None
