"""Team scenarios: read from TOML, drawn at random (seeded), and checked before anything runs.

A scenario file (format in docs/team.md)::

    name = "three-robots"
    maze = "wide-short"          # a bundled maze or a maze file (relative to this file)
    seed = 0                     # draws random robots and tasks when they are given as counts

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
    persistence = "permanent"    # permanent | transient (then duration = ticks)

``robots = 4`` and ``tasks = 6`` (counts) draw robots and tasks from ``seed`` instead;
``grippers = "mixed"`` then leaves every third robot without a gripper.

:func:`check_scenario` refuses, with one :class:`~selfrepair.errors.InputError` naming the file and
line, everything that cannot run: a robot or task on a wall or off the maze, two robots on one
cell, more robots than free cells, a task no robot with a gripper can reach (or whose drop-off
cannot be reached from its pickup), an unknown robot in a fault.
"""

from __future__ import annotations

import re
import tomllib
from collections import deque
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from selfrepair.errors import InputError
from selfrepair.execution.faults import Persistence
from selfrepair.geometry import Cell, Heading, Pose, parse_cell, parse_pose
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES, MAX_ROBOTS, MAX_TASKS, check_limit
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import get_domain
from selfrepair.team.model import (
    NAME_PATTERN,
    RobotSpec,
    Task,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    Trigger,
)
from selfrepair.textio import read_text, strip_bom
from selfrepair.world.maze import Maze

__all__ = [
    "GripperMix",
    "Limits",
    "check_scenario",
    "components",
    "grid_distances",
    "load_scenario",
    "parse_scenario",
    "random_scenario",
    "resolve_scenario",
    "scenario_names",
]


@dataclass(frozen=True, slots=True)
class Limits:
    """How many robots, tasks and maze cells a scenario may have, and how big its file may be
    (:mod:`selfrepair.limits`; ``None`` turns a check off). The commands set them with
    ``--max-robots``, ``--max-tasks``, ``--max-cells`` and ``--max-file-bytes``."""

    max_robots: int | None = MAX_ROBOTS
    max_tasks: int | None = MAX_TASKS
    max_cells: int | None = MAX_CELLS
    max_file_bytes: int | None = MAX_FILE_BYTES


class GripperMix(StrEnum):
    """Equipment of randomly drawn robots: every robot has a gripper (``all``), or every third
    robot (the 3rd, 6th, ...) has none (``mixed``)."""

    ALL = "all"
    MIXED = "mixed"


def has_gripper(mix: GripperMix, index: int) -> bool:
    """Whether robot number ``index`` (0-based) of a random team has a gripper."""
    return mix is GripperMix.ALL or index % 3 != 2


# --- reading -----------------------------------------------------------------------------------


def scenario_names() -> tuple[str, ...]:
    """The bundled scenarios (package data ``data/team/*.toml``)."""
    from importlib import resources

    folder = resources.files("selfrepair").joinpath("data", "team")
    return tuple(sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml")))


def resolve_scenario(spec: str, *, limits: Limits = Limits()) -> TeamScenario:
    """A bundled scenario by name, or a scenario file."""
    if "/" not in spec and not spec.endswith(".toml") and spec in scenario_names():
        from importlib import resources

        path = resources.files("selfrepair").joinpath("data", "team", f"{spec}.toml")
        text = path.read_text(encoding="utf-8")
        return parse_scenario(text, source=f"<bundled:{spec}>", limits=limits)
    return load_scenario(spec, limits=limits)


def load_scenario(path: str | Path, *, limits: Limits = Limits()) -> TeamScenario:
    """Read and check a scenario file."""
    file = Path(path)
    text = read_text(
        file, what="scenario file", max_bytes=limits.max_file_bytes, limit="max_file_bytes"
    )
    return parse_scenario(text, source=str(file), base_dir=file.parent, limits=limits)


_KEYS = frozenset({"name", "maze", "domain", "seed", "robots", "tasks", "faults", "grippers"})


def parse_scenario(
    text: str,
    *,
    source: str = "<scenario>",
    base_dir: Path | None = None,
    limits: Limits = Limits(),
) -> TeamScenario:
    """Parse and check scenario TOML ``text`` (``base_dir`` resolves a relative maze file)."""
    text = strip_bom(text)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        where = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        reason = re.sub(r"\s*\(at (line \d+, column \d+|end of document)\)", "", str(exc))
        line, column = (int(where.group(1)), int(where.group(2))) if where else (None, None)
        raise InputError(
            f"invalid TOML: {reason}", source=source, line=line, column=column
        ) from None
    reader = _Reader(text, source)
    for key in data:
        if key not in _KEYS:
            raise reader.fail(
                f"unknown key {key!r}; expected one of {', '.join(sorted(_KEYS))}", key
            )
    maze = reader.maze(data.get("maze"), base_dir, limits.max_cells)
    domain = reader.domain(data.get("domain", "four-wheel"))
    seed = reader.integer(data, "seed", 0)
    mix = reader.member(GripperMix, data.get("grippers", GripperMix.ALL.value), "grippers")
    rng = np.random.default_rng(seed)
    robots_data, tasks_data = data.get("robots", []), data.get("tasks", [])
    if isinstance(robots_data, int) and not isinstance(robots_data, bool):
        count_tasks = tasks_data if isinstance(tasks_data, int) else 0
        drawn = reader.random(maze, robots_data, count_tasks, rng, mix, domain, limits)
        robots = drawn.robots
        tasks = drawn.tasks if isinstance(tasks_data, int) else reader.tasks(tasks_data)
    else:
        robots = reader.robots(robots_data)
        if isinstance(tasks_data, int) and not isinstance(tasks_data, bool):
            tasks = reader.random_tasks(maze, robots, tasks_data, rng, limits)
        else:
            tasks = reader.tasks(tasks_data)
    faults = reader.faults(data.get("faults", []), domain)
    name = str(data.get("name", Path(source).stem if not source.startswith("<") else "scenario"))
    scenario = TeamScenario(maze, robots, tasks, faults, domain, name, source)
    check_scenario(scenario, text=text, limits=limits)
    return scenario


class _Reader:
    """Typed access to a scenario's keys; every failure names the file and the key's line."""

    def __init__(self, text: str, source: str) -> None:
        self.text, self.source = text, source

    def fail(self, what: str, *needles: str) -> InputError:
        return InputError(what, source=self.source, line=find_line(self.text, *needles))

    def integer(self, data: Mapping[str, Any], key: str, default: int) -> int:
        value = data.get(key, default)
        if type(value) is not int or value < 0:
            raise self.fail(f"key {key!r}: expected a non-negative integer, got {value!r}", key)
        return value

    def member(self, kind: type[Any], value: Any, key: str) -> Any:
        try:
            return kind(value)
        except ValueError:
            allowed = ", ".join(m.value for m in kind)
            raise self.fail(f"key {key!r}: expected one of {allowed}, got {value!r}", key) from None

    def maze(self, value: Any, base_dir: Path | None, max_cells: int | None) -> Maze:
        if not isinstance(value, str) or not value:
            raise self.fail("key 'maze': expected a bundled maze name or a maze file", "maze")
        from selfrepair.world.bundled import maze_names, resolve_maze

        if value in maze_names() or base_dir is None or Path(value).is_absolute():
            return resolve_maze(value, max_cells=max_cells)
        return resolve_maze(str(base_dir / value), max_cells=max_cells)

    def domain(self, value: Any) -> Domain[Any, Any]:
        if not isinstance(value, str):
            raise self.fail(f"key 'domain': expected a domain name, got {value!r}", "domain")
        try:
            return get_domain(value)
        except InputError as exc:
            raise self.fail(f"key 'domain': {exc.reason}", "domain") from None

    def cell(self, value: Any, key: str, *context: str) -> Cell:
        try:
            return parse_cell(str(value))
        except InputError as exc:
            raise self.fail(f"key {key!r}: {exc.reason}", *context, key) from None

    def table(self, entry: Any, what: str, keys: Iterable[str]) -> Mapping[str, Any]:
        if not isinstance(entry, dict):
            raise self.fail(f"expected each of '{what}' to be a table, got {entry!r}", what)
        allowed = set(keys)
        for key in entry:
            if key not in allowed:
                raise self.fail(
                    f"'{what}': unknown key {key!r}; expected {', '.join(sorted(allowed))}", key
                )
        return entry

    def name(self, entry: Mapping[str, Any], key: str, what: str) -> str:
        value = entry.get(key)
        if not isinstance(value, str) or not NAME_PATTERN.match(value):
            raise self.fail(
                f"'{what}': expected {key!r} to be a name (a letter, then letters, digits, _ or "
                f"-), got {value!r}",
                *((f'"{value}"',) if isinstance(value, str) else (key,)),
            )
        return value

    def robots(self, value: Any) -> tuple[RobotSpec, ...]:
        if not isinstance(value, list):
            raise self.fail("key 'robots': expected a list of robots or a count", "robots")
        robots = []
        for entry in value:
            entry = self.table(entry, "robots", ("name", "start", "gripper"))
            name = self.name(entry, "name", "robots")
            try:
                start = parse_pose(str(entry.get("start", "")))
            except InputError as exc:
                raise self.fail(f"robot {name}: {exc.reason}", f'"{name}"') from None
            gripper = entry.get("gripper", True)
            if not isinstance(gripper, bool):
                raise self.fail(f"robot {name}: expected 'gripper' true or false", "gripper")
            robots.append(RobotSpec(name, start, gripper))
        return tuple(robots)

    def tasks(self, value: Any) -> tuple[Task, ...]:
        if not isinstance(value, list):
            raise self.fail("key 'tasks': expected a list of tasks or a count", "tasks")
        tasks = []
        for entry in value:
            entry = self.table(entry, "tasks", ("item", "pickup", "dropoff"))
            item = self.name(entry, "item", "tasks")
            pickup = self.cell(entry.get("pickup"), "pickup", f'"{item}"')
            dropoff = self.cell(entry.get("dropoff"), "dropoff", f'"{item}"')
            tasks.append(Task(item, pickup, dropoff))
        return tuple(tasks)

    def faults(self, value: Any, domain: Domain[Any, Any]) -> tuple[TeamFault, ...]:
        if not isinstance(value, list):
            raise self.fail("key 'faults': expected a list of [[faults]] tables", "faults")
        keys = (
            "kind",
            "robot",
            "cells",
            "wheel_faults",
            "at",
            "trigger",
            "persistence",
            "duration",
        )
        faults = []
        for entry in value:
            entry = self.table(entry, "faults", keys)
            kind = self.member(TeamFaultKind, entry.get("kind"), "kind")
            cells_value = entry.get("cells", [])
            if not isinstance(cells_value, list):
                raise self.fail("key 'cells': expected a list of \"X,Y\" cells", "cells")
            cells = tuple(self.cell(c, "cells") for c in cells_value)
            wheel = str(entry.get("wheel_faults", ""))
            if kind is TeamFaultKind.WHEELS:
                try:
                    wheel = domain.format_faults(domain.parse_faults(wheel))
                except InputError as exc:
                    raise self.fail(f"key 'wheel_faults': {exc.reason}", "wheel_faults") from None
                if not wheel:
                    raise self.fail("a wheels fault needs 'wheel_faults'", "wheels")
            try:
                fault = TeamFault(
                    kind,
                    robot=str(entry.get("robot", "")),
                    cells=cells,
                    wheel_faults=wheel,
                    at=self.integer(entry, "at", 0),
                    trigger=self.member(Trigger, entry.get("trigger", "tick"), "trigger"),
                    persistence=self.member(
                        Persistence, entry.get("persistence", "permanent"), "persistence"
                    ),
                    duration=entry.get("duration"),
                )
            except (InputError, ValueError) as exc:
                raise self.fail(str(exc), f'"{kind.value}"') from None
            faults.append(fault)
        return tuple(faults)

    def random(
        self,
        maze: Maze,
        robots: int,
        tasks: int,
        rng: np.random.Generator,
        mix: GripperMix,
        domain: Domain[Any, Any],
        limits: Limits,
    ) -> TeamScenario:
        try:
            return random_scenario(
                maze, robots, tasks, rng, grippers=mix, domain=domain, limits=limits
            )
        except InputError as exc:
            raise self.fail(exc.reason, "robots") from None

    def random_tasks(
        self,
        maze: Maze,
        robots: tuple[RobotSpec, ...],
        count: int,
        rng: np.random.Generator,
        limits: Limits,
    ) -> tuple[Task, ...]:
        taken = {r.start.cell for r in robots}
        try:
            return _draw_tasks(maze, count, rng, taken, limits.max_tasks)
        except InputError as exc:
            raise self.fail(exc.reason, "tasks") from None


def find_line(text: str, *needles: str) -> int | None:
    """The 1-based line of ``text`` that the needles point at, or ``None``: the first line that
    mentions the first needle (as ``key =``, a ``[[key]]`` header, or a quoted value such as
    ``'"i1"'``), then, within the same table, the line that mentions the next needle."""
    lines = [line.split("#", 1)[0] for line in text.splitlines()]
    if not needles:
        return None
    found = next((n for n, line in enumerate(lines) if _mentions(line, needles[0])), None)
    if found is None:
        return None
    start = next((n for n in range(found, -1, -1) if _HEADER.match(lines[n])), 0)
    stop = next((n for n in range(found + 1, len(lines)) if _HEADER.match(lines[n])), len(lines))
    for needle in needles[1:]:
        hit = next((n for n in range(start, stop) if _mentions(lines[n], needle)), None)
        if hit is not None:
            found = hit
    return found + 1


_HEADER = re.compile(r"^\s*\[")


def _mentions(line: str, needle: str) -> bool:
    if needle.startswith('"'):
        return needle in line
    return re.search(rf"(^|[\s{{,]){re.escape(needle)}\s*=", line) is not None or (
        re.search(rf"\[\[?\s*{re.escape(needle)}\s*\]\]?", line) is not None
    )


# --- checking ----------------------------------------------------------------------------------


def check_scenario(scenario: TeamScenario, *, text: str = "", limits: Limits | None = None) -> None:
    """Raise :class:`InputError` naming the file (and line, given the ``text``) for the first
    thing in ``scenario`` that cannot run (see the module docstring)."""
    maze, source = scenario.maze, scenario.source

    def fail(what: str, *needles: str) -> InputError:
        return InputError(what, source=source, line=find_line(text, *needles) if text else None)

    free = len(maze.free_cells())
    if len(scenario.robots) > free:
        raise fail(
            f"{len(scenario.robots)} robots do not fit: maze {maze.name or 'of the scenario'} "
            f"has {free} free cells",
            "robots",
        )
    if not scenario.robots:
        raise fail("expected at least one robot", "robots")
    if limits is not None:
        line = find_line(text, "robots") if text else None
        check_limit(
            len(scenario.robots), limits.max_robots, name="max_robots", what="robots",
            source=source, line=line,
        )  # fmt: skip
        line = find_line(text, "tasks") if text else None
        check_limit(
            len(scenario.tasks), limits.max_tasks, name="max_tasks", what="tasks",
            source=source, line=line,
        )  # fmt: skip
    _check_robots(scenario, maze, fail)
    _check_tasks(scenario, maze, fail)
    _check_faults(scenario, maze, fail)


def _check_robots(scenario: TeamScenario, maze: Maze, fail: Any) -> None:
    seen: dict[Cell, str] = {}
    names: set[str] = set()
    for robot in scenario.robots:
        if robot.name in names:
            raise fail(f"two robots are called {robot.name}", f'"{robot.name}"')
        names.add(robot.name)
        x, y = robot.start.cell
        if not maze.is_free(x, y):
            what = "a wall" if maze.in_bounds(x, y) else "off the maze"
            raise fail(f"robot {robot.name} starts at {x},{y}, which is {what}", f'"{robot.name}"')
        if robot.start.cell in seen:
            raise fail(
                f"robots {seen[robot.start.cell]} and {robot.name} both start at {x},{y}",
                f'"{robot.name}"',
            )
        seen[robot.start.cell] = robot.name


def _check_tasks(scenario: TeamScenario, maze: Maze, fail: Any) -> None:
    items: set[str] = set()
    pickups: dict[Cell, str] = {}
    comp = components(maze)
    reach = {comp[r.start.cell] for r in scenario.robots if r.gripper}
    for task in scenario.tasks:
        if task.item in items:
            raise fail(f"two tasks deliver item {task.item}", f'"{task.item}"')
        items.add(task.item)
        for what, (x, y) in (("pickup", task.pickup), ("dropoff", task.dropoff)):
            if not maze.is_free(x, y):
                where = "a wall" if maze.in_bounds(x, y) else "off the maze"
                raise fail(f"task {task.item}: {what} {x},{y} is {where}", f'"{task.item}"', what)
        if task.pickup == task.dropoff:
            raise fail(f"task {task.item}: pickup and dropoff are the same cell", f'"{task.item}"')
        if task.pickup in pickups:
            raise fail(
                f"items {pickups[task.pickup]} and {task.item} lie on the same cell",
                f'"{task.item}"',
            )
        pickups[task.pickup] = task.item
        x, y = task.pickup
        if comp[task.pickup] not in reach:
            raise fail(
                f"item {task.item} at {x},{y}: no robot with a gripper can reach it",
                f'"{task.item}"',
                "pickup",
            )
        if comp[task.dropoff] != comp[task.pickup]:
            bx, by = task.dropoff
            raise fail(
                f"item {task.item} cannot be brought from {x},{y} to {bx},{by}: no path",
                f'"{task.item}"',
                "dropoff",
            )


def _check_faults(scenario: TeamScenario, maze: Maze, fail: Any) -> None:
    names = {r.name for r in scenario.robots}
    for fault in scenario.faults:
        if fault.robot and fault.robot not in names:
            raise fail(
                f"a {fault.kind} fault names unknown robot {fault.robot!r}", f'"{fault.robot}"'
            )
        for x, y in fault.cells:
            if not maze.in_bounds(x, y):
                raise fail(f"blocked cell {x},{y} is off the maze", "cells")


# --- reachability ------------------------------------------------------------------------------


def components(maze: Maze) -> dict[Cell, int]:
    """The 4-connected component number of every free cell (a robot with healthy wheels can
    reach exactly the cells of its own component: a turn in place needs only its own cell)."""
    label: dict[Cell, int] = {}
    number = 0
    for cell in maze.free_cells():
        if cell in label:
            continue
        for reached in grid_distances(maze, cell):
            label[reached] = number
        number += 1
    return label


def grid_distances(
    maze: Maze, start: Cell, blocked: frozenset[Cell] = frozenset()
) -> dict[Cell, int]:
    """4-connected step distances from ``start`` over free cells not in ``blocked``."""
    distances = {start: 0}
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for nxt in ((x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y)):
            if nxt not in distances and nxt not in blocked and maze.is_free(*nxt):
                distances[nxt] = distances[(x, y)] + 1
                queue.append(nxt)
    return distances


# --- random scenarios --------------------------------------------------------------------------


def random_scenario(
    maze: Maze,
    robots: int,
    tasks: int,
    rng: np.random.Generator,
    *,
    grippers: GripperMix = GripperMix.ALL,
    domain: Domain[Any, Any] | None = None,
    name: str = "random",
    limits: Limits = Limits(),
) -> TeamScenario:
    """``robots`` robots (``r1``, ``r2``, ...) on distinct cells and ``tasks`` tasks (``i1``, ...)
    with distinct pickup and drop-off cells, all drawn from ``rng`` in the maze's largest
    4-connected area; a drop-off lies at least half the largest distance from its pickup."""
    area = _largest_area(maze)
    if robots < 1 or robots > len(area):
        raise InputError(
            f"{robots} robots do not fit: maze {maze.name or '?'} has {len(area)} connected free "
            f"cells (expected 1 to {len(area)} robots)"
        )
    check_limit(robots, limits.max_robots, name="max_robots", what="robots", source=name)
    picks = rng.permutation(len(area))[:robots]
    team = tuple(
        RobotSpec(
            f"r{n + 1}",
            Pose(area[i][0], area[i][1], Heading(int(rng.integers(4)))),
            has_gripper(grippers, n),
        )
        for n, i in enumerate(picks)
    )
    drawn = _draw_tasks(maze, tasks, rng, {r.start.cell for r in team}, limits.max_tasks)
    kwargs = {} if domain is None else {"domain": domain}
    return TeamScenario(maze, team, drawn, (), name=name, source=f"<random:{name}>", **kwargs)


def _largest_area(maze: Maze) -> list[Cell]:
    comp = components(maze)
    if not comp:
        raise InputError(f"maze {maze.name or '?'} has no free cell")
    sizes: dict[int, int] = {}
    for number in comp.values():
        sizes[number] = sizes.get(number, 0) + 1
    best = max(sorted(sizes), key=lambda k: sizes[k])
    return sorted(c for c, n in comp.items() if n == best)


def _draw_tasks(
    maze: Maze, count: int, rng: np.random.Generator, taken: set[Cell], max_tasks: int | None
) -> tuple[Task, ...]:
    area = [c for c in _largest_area(maze) if c not in taken]
    check_limit(count, max_tasks, name="max_tasks", what="tasks", source=maze.name or "<maze>")
    if count < 0 or 2 * count > len(area):
        raise InputError(
            f"expected 0 to {len(area) // 2} tasks for maze {maze.name or '?'} "
            f"(each needs two free cells), got {count}"
        )
    used = set(taken)
    tasks = []
    for n in range(count):
        free = [c for c in area if c not in used]
        pickup = free[int(rng.integers(len(free)))]
        used.add(pickup)
        distances = grid_distances(maze, pickup)
        far = max(distances.values())
        options = sorted(c for c, d in distances.items() if 2 * d >= far and c not in used)
        if not options:
            options = sorted(c for c in distances if c not in used)
        dropoff = options[int(rng.integers(len(options)))]
        used.add(dropoff)
        tasks.append(Task(f"i{n + 1}", pickup, dropoff))
    return tuple(tasks)
