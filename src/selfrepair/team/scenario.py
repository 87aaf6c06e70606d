"""Team scenarios: TOML files read into a checked :class:`~selfrepair.team.model.TeamScenario`.

A scenario file (format in docs/team.md)::

    name = "three-robots"
    maze = "wide-short"          # a bundled maze or a maze file (relative to this file)
    domain = "four-wheel"        # the robot: a name in the domain registry (default four-wheel)
    plugins = []                 # Python files that register robots (paths relative to this file)
    table = "handwritten"        # the robots' own table (default: the robot's default table)
    seed = 0                     # draws random robots and tasks when they are given as counts
    detection = "now"            # how robots learn wheel faults: now (sensed) | on-use (failures)

    [[robots]]
    name = "r1"
    start = "1,1,E"
    gripper = true               # default true

    [[tasks]]
    item = "i1"
    pickup = "5,2"
    dropoff = "20,13"

    [[faults]]
    kind = "immobilised"         # immobilised | wheels | gripper | blocked
    robot = "r1"
    trigger = "pick"             # tick (default) | pick: 'at' ticks after the robot's first pick
    at = 3
    persistence = "permanent"    # permanent | transient (then duration = ticks) | intermittent
                                 # (wheels and immobilised; then probability = per robot step)

    [world]                      # a changing world (docs/dynamic.md): world events
    events = "5,3@10; 7,2@4..20" # the text of --events: X,Y@T | X,Y@T..U | -X,Y@T
    sensing = "range"            # range (cells within 'range' seen) | bump
    range = 2

``robots = 4`` and ``tasks = 6`` (counts) draw robots and tasks from ``seed`` instead
(:mod:`selfrepair.team.randomteam`); ``grippers = "mixed"`` then leaves every third robot
without a gripper.

The file is read by the same machinery as experiment files (:mod:`selfrepair.tomlfile`): the
pydantic models below refuse a key of the wrong type or an unknown key with one
:class:`~selfrepair.errors.ConfigError` naming the file, the line and what was expected; the robot
is found by :mod:`selfrepair.robots.fromfile`; then :func:`~selfrepair.team.check.check_scenario`
refuses what cannot run.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import AfterValidator, Field, ValidationInfo, field_validator, model_validator

from selfrepair.errors import ConfigError, InputError, ProblemError
from selfrepair.execution.faults import Detection, Persistence
from selfrepair.geometry import parse_cell, parse_pose
from selfrepair.limits import DEFAULT_SENSING_RANGE
from selfrepair.robots.domain import Domain, SomeDomain
from selfrepair.robots.fromfile import DEFAULT_DOMAIN, file_domain, load_plugins
from selfrepair.robots.registry import get_domain
from selfrepair.team.check import check_scenario
from selfrepair.team.grid import components, grid_distances
from selfrepair.team.model import (
    NAME_PATTERN,
    RobotSpec,
    Task,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    Trigger,
)
from selfrepair.team.randomteam import (
    DEFAULT_LIMITS,
    GripperMix,
    Limits,
    draw_tasks,
    random_scenario,
)
from selfrepair.team.result import TeamOptions
from selfrepair.team.robottable import robot_table
from selfrepair.textio import read_text, strip_bom
from selfrepair.tomlfile import Frozen, Int, find_line, read_toml, validate
from selfrepair.world.events import Sensing, WorldSchedule, parse_events
from selfrepair.world.maze import Maze

__all__ = [
    "GripperMix",
    "Limits",
    "ScenarioFile",
    "check_scenario",
    "components",
    "grid_distances",
    "load_scenario",
    "parse_scenario",
    "random_scenario",
    "resolve_scenario",
    "scenario_digest",
    "scenario_names",
]


def _name(value: str) -> str:
    if not NAME_PATTERN.match(value):
        raise ValueError(
            f"expected a name (a letter, then up to 31 letters, digits, _ or -), got {value!r}"
        )
    return value


def _cell(value: str) -> str:
    try:
        x, y = parse_cell(value)
    except InputError as exc:
        raise ValueError(exc.reason) from None
    return f"{x},{y}"


def _pose(value: str) -> str:
    try:
        return str(parse_pose(value))
    except InputError as exc:
        raise ValueError(exc.reason) from None


Name = Annotated[str, AfterValidator(_name)]
CellText = Annotated[str, AfterValidator(_cell)]
"""A cell ``"X,Y"``, kept as its canonical text."""
Bool = Annotated[bool, Field(strict=True)]
Count = Annotated[Int, Field(ge=0)]


class RobotEntry(Frozen):
    """One ``[[robots]]`` table: name, start pose ``"X,Y,H"``, gripper (default true)."""

    name: Name
    start: Annotated[str, AfterValidator(_pose)]
    gripper: Bool = True

    def spec(self) -> RobotSpec:
        """The robot as the engine sees it."""
        return RobotSpec(self.name, parse_pose(self.start), self.gripper)


class TaskEntry(Frozen):
    """One ``[[tasks]]`` table: the item, its pickup cell and its drop-off cell."""

    item: Name
    pickup: CellText
    dropoff: CellText

    def task(self) -> Task:
        """The task as the engine sees it."""
        return Task(self.item, parse_cell(self.pickup), parse_cell(self.dropoff))


class FaultEntry(Frozen):
    """One ``[[faults]]`` table (see :class:`~selfrepair.team.model.TeamFault`)."""

    kind: TeamFaultKind
    robot: str = ""
    cells: tuple[CellText, ...] = ()
    wheel_faults: str = ""
    at: Count = 0
    trigger: Trigger = Trigger.TICK
    persistence: Persistence = Persistence.PERMANENT
    duration: Annotated[Int, Field(ge=1)] | None = None
    probability: Annotated[float, Field(ge=0.0, le=1.0)] | None = None

    @field_validator("wheel_faults")
    @classmethod
    def _wheels(cls, value: str, info: ValidationInfo) -> str:
        if not value:
            return value
        domain = _domain(info)
        try:
            return domain.format_faults(domain.parse_faults(value))
        except InputError as exc:
            raise ValueError(exc.reason) from None

    @model_validator(mode="after")
    def _fault(self) -> FaultEntry:
        if self.kind is TeamFaultKind.WHEELS and not self.wheel_faults:
            raise ValueError("a wheels fault needs 'wheel_faults'")
        try:
            self.fault()
        except ProblemError as exc:
            raise ValueError(str(exc)) from None
        return self

    def fault(self) -> TeamFault:
        """The fault as the engine sees it (raises ProblemError when its keys do not agree)."""
        return TeamFault(
            self.kind,
            robot=self.robot,
            cells=tuple(parse_cell(c) for c in self.cells),
            wheel_faults=self.wheel_faults if self.kind is TeamFaultKind.WHEELS else "",
            at=self.at,
            trigger=self.trigger,
            persistence=self.persistence,
            duration=self.duration,
            probability=self.probability,
        )


class WorldEntry(Frozen):
    """The ``[world]`` table: world events in the text form of ``--events``
    (:func:`~selfrepair.world.events.parse_events`) and how the robots sense them (the
    ``sensing`` and ``range`` keys of an experiment file's ``[world]``, one value each)."""

    events: str = ""
    sensing: Sensing = Sensing.RANGE
    range: Annotated[Int, Field(ge=0, le=64)] = DEFAULT_SENSING_RANGE

    def schedule(self, text: str, source: str) -> WorldSchedule:
        """The world schedule; a bad event is one :class:`ConfigError` at the line of
        ``events`` naming the event."""
        try:
            events = parse_events(self.events, source="events")
        except InputError as exc:
            raise ConfigError(
                f"key 'world.events' ({exc.source}): {exc.reason}",
                source=source,
                line=find_line(text, ("world", "events")),
            ) from None
        return WorldSchedule(events, self.sensing, self.range)


class ScenarioFile(Frozen):
    """A whole scenario file (see the module docstring); ``robots`` and ``tasks`` are lists of
    tables or counts to draw from ``seed``."""

    name: Annotated[str, Field(min_length=1)] | None = None
    maze: Annotated[str, Field(min_length=1)]
    domain: str = DEFAULT_DOMAIN
    plugins: tuple[str, ...] = ()
    table: Annotated[str, Field(min_length=1)] | None = None
    seed: Count = 0
    detection: Detection = Detection.NOW
    grippers: GripperMix = GripperMix.ALL
    robots: Count | tuple[RobotEntry, ...] = ()
    tasks: Count | tuple[TaskEntry, ...] = ()
    faults: tuple[FaultEntry, ...] = ()
    world: WorldEntry | None = None


def _domain(info: ValidationInfo) -> SomeDomain:
    domain = (info.context or {}).get("domain")
    return domain if isinstance(domain, Domain) else get_domain(DEFAULT_DOMAIN)


# --- reading -----------------------------------------------------------------------------------


def scenario_names() -> tuple[str, ...]:
    """The bundled scenarios (package data ``data/team/*.toml``)."""
    from importlib import resources

    folder = resources.files("selfrepair").joinpath("data", "team")
    return tuple(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))


def resolve_scenario(spec: str, *, limits: Limits = DEFAULT_LIMITS) -> TeamScenario:
    """A bundled scenario by name, or a scenario file."""
    if "/" not in spec and not spec.endswith(".toml") and spec in scenario_names():
        from importlib import resources

        path = resources.files("selfrepair").joinpath("data", "team", f"{spec}.toml")
        text = path.read_text(encoding="utf-8")
        return parse_scenario(text, source=f"<bundled:{spec}>", limits=limits)
    return load_scenario(spec, limits=limits)


def load_scenario(path: str | Path, *, limits: Limits = DEFAULT_LIMITS) -> TeamScenario:
    """Read and check a scenario file."""
    file = Path(path)
    text = read_text(
        file, what="scenario file", max_bytes=limits.max_file_bytes, limit="max_file_bytes"
    )
    return parse_scenario(text, source=str(file), base_dir=file.parent, limits=limits)


def scenario_digest(text: str) -> str:
    """The SHA-256 of a scenario file's text (a byte-order mark dropped), as traces record it."""
    return hashlib.sha256(strip_bom(text).encode("utf-8")).hexdigest()


def parse_scenario(
    text: str,
    *,
    source: str = "<scenario>",
    base_dir: Path | None = None,
    limits: Limits = DEFAULT_LIMITS,
) -> TeamScenario:
    """Parse and check scenario TOML ``text`` (``base_dir`` resolves a relative maze or table
    file, the folder of ``source`` a plug-in file)."""
    text = strip_bom(text)
    data = read_toml(text, source=source)
    load_plugins(data, text, source)
    domain = file_domain(data, text, source)
    entry = validate(ScenarioFile, data, text=text, source=source, context={"domain": domain})
    maze = _maze(entry.maze, base_dir, limits.max_cells, text, source)
    rng = np.random.default_rng(entry.seed)

    def fail(exc: InputError, key: str) -> ConfigError:
        return ConfigError(exc.reason, source=source, line=find_line(text, (key,)))

    if isinstance(entry.robots, int):
        count_tasks = entry.tasks if isinstance(entry.tasks, int) else 0
        try:
            drawn = random_scenario(
                maze, entry.robots, count_tasks, rng, grippers=entry.grippers, domain=domain,
                limits=limits,
            )  # fmt: skip
        except InputError as exc:
            raise fail(exc, "robots") from None
        robots = drawn.robots
        listed = () if isinstance(entry.tasks, int) else tuple(t.task() for t in entry.tasks)
        tasks = drawn.tasks if isinstance(entry.tasks, int) else listed
    else:
        robots = tuple(r.spec() for r in entry.robots)
        if isinstance(entry.tasks, int):
            try:
                taken = {r.start.cell for r in robots}
                tasks = draw_tasks(maze, entry.tasks, rng, taken, limits.max_tasks)
            except InputError as exc:
                raise fail(exc, "tasks") from None
        else:
            tasks = tuple(t.task() for t in entry.tasks)
    name = entry.name or (Path(source).stem if not source.startswith("<") else "scenario")
    table = "" if entry.table is None else _table(entry.table, base_dir)
    world = WorldSchedule() if entry.world is None else entry.world.schedule(text, source)
    scenario = TeamScenario(
        maze, robots, tasks, tuple(f.fault() for f in entry.faults), domain, name, source,
        table=table, digest=scenario_digest(text), detection=entry.detection, world=world,
    )  # fmt: skip
    check_scenario(scenario, text=text, limits=limits)
    if table:
        try:
            robot_table(scenario, TeamOptions())
        except (InputError, ProblemError) as exc:
            reason = exc.reason if isinstance(exc, InputError) else str(exc)
            raise ConfigError(
                f"key 'table': {reason}", source=source, line=find_line(text, ("table",))
            ) from None
    return scenario


def _maze(value: str, base_dir: Path | None, max_cells: int | None, text: str, source: str) -> Maze:
    from selfrepair.world.bundled import maze_names, resolve_maze

    if value in maze_names() or base_dir is None or Path(value).is_absolute():
        return resolve_maze(value, max_cells=max_cells)
    return resolve_maze(str(base_dir / value), max_cells=max_cells)


def _table(value: str, base_dir: Path | None) -> str:
    """A table name as given, or a table file's path resolved against the scenario's folder."""
    if "/" in value or value.endswith(".json"):
        path = Path(value)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        return str(path)
    return value
