"""Team experiment cases: a seeded scenario with one fault of a chosen kind, run and measured.

A :class:`TeamCase` is the situation of one team mission in a sweep: team size, task load,
equipment mix, the fault case (:class:`FaultCase`), its persistence, and the seed. The seed
draws the robots and tasks (:func:`~selfrepair.team.scenario.random_scenario`) and, separately,
the fault (which robot, when, which cells), so every fault case of one seed meets the same team
and tasks, and every strategy the same fault. :func:`case_row` runs the case with one set of
options and returns the metrics row, with the makespan of the same scenario without faults
(kept per process, it does not depend on the strategy) as the baseline.

The experiment configuration, mission keys and the store live in :mod:`selfrepair.experiment`
(``kind = "team"`` files, see docs/team.md); this module only builds and runs cases.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace
from enum import StrEnum
from fractions import Fraction
from typing import Any

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.execution.faults import Persistence
from selfrepair.geometry import Cell
from selfrepair.repair.strategies import StrategyName
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.team.allocation import Job, Worker, allocate, distance_maps
from selfrepair.team.engine import run_team
from selfrepair.team.grid import components
from selfrepair.team.metrics import team_row
from selfrepair.team.model import TeamFault, TeamFaultKind, TeamScenario, Trigger
from selfrepair.team.randomteam import GripperMix, random_scenario
from selfrepair.team.result import TeamOptions, TeamResult
from selfrepair.world.maze import Maze

__all__ = ["FaultCase", "TeamCase", "build_scenario", "case_row", "run_case"]


class FaultCase(StrEnum):
    """The fault of a team experiment case: none; a robot immobilised at a random early tick,
    or a few ticks after its first pick (so while carrying); a gripper broken from the start
    (its first pick fails) or after the first pick (its drop fails); a corridor on a robot's
    first delivery route blocked from the start; two wheel faults of the robot's domain (its own
    replacement table handles them first)."""

    NONE = "none"
    IMMOBILISED = "immobilised"
    IMMOBILISED_CARRYING = "immobilised-carrying"
    GRIPPER = "gripper"
    GRIPPER_CARRYING = "gripper-carrying"
    BLOCKED = "blocked"
    WHEELS = "wheels"


@dataclass(frozen=True, slots=True)
class TeamCase:
    """One team mission's situation (see the module docstring)."""

    team_size: int
    tasks: int
    grippers: GripperMix
    fault: FaultCase
    persistence: Persistence = Persistence.PERMANENT
    duration: int | None = None
    seed: int = 0


def build_scenario(
    maze: Maze, case: TeamCase, *, domain: SomeDomain = FOUR_WHEEL, name: str = ""
) -> TeamScenario:
    """The scenario of ``case`` on ``maze``: seeded robots and tasks, then the seeded fault."""
    rng = np.random.default_rng(case.seed)
    label = name or f"team{case.team_size}-t{case.tasks}-s{case.seed}"
    scenario = random_scenario(
        maze, case.team_size, case.tasks, rng, grippers=case.grippers, domain=domain, name=label
    )
    fault = _fault(scenario, case)
    if fault is None:
        return scenario
    return replace(scenario, faults=(fault,))


def _fault(scenario: TeamScenario, case: TeamCase) -> TeamFault | None:
    """The case's fault on a robot that has work (drawn from the case seed and the case)."""
    if case.fault is FaultCase.NONE:
        return None
    rng = np.random.default_rng([case.seed, list(FaultCase).index(case.fault)])
    first = _first_tasks(scenario)
    if not first:
        return None
    robots = sorted(first)
    robot = robots[int(rng.integers(len(robots)))]
    timing: dict[str, Any] = {"persistence": case.persistence, "duration": case.duration}
    if case.persistence is Persistence.PERMANENT:
        timing["duration"] = None
    if case.fault is FaultCase.IMMOBILISED:
        return TeamFault(TeamFaultKind.IMMOBILISED, robot, at=int(rng.integers(5, 30)), **timing)
    if case.fault is FaultCase.IMMOBILISED_CARRYING:
        return TeamFault(
            TeamFaultKind.IMMOBILISED, robot, at=int(rng.integers(1, 6)), trigger=Trigger.PICK,
            **timing,
        )  # fmt: skip
    if case.fault is FaultCase.GRIPPER:
        return TeamFault(TeamFaultKind.GRIPPER, robot, at=0, **timing)
    if case.fault is FaultCase.GRIPPER_CARRYING:
        return TeamFault(TeamFaultKind.GRIPPER, robot, at=1, trigger=Trigger.PICK, **timing)
    if case.fault is FaultCase.WHEELS:
        doubles = [f for f in scenario.domain.fault_sets if len(f) == 2]
        faults = doubles[int(rng.integers(len(doubles)))]
        text = scenario.domain.format_faults(faults)
        return TeamFault(
            TeamFaultKind.WHEELS, robot, wheel_faults=text, at=int(rng.integers(0, 10)), **timing
        )
    cells = _corridor(scenario, first[robot], rng)
    if not cells:
        return None
    return TeamFault(TeamFaultKind.BLOCKED, cells=cells, at=0, **timing)


def _first_tasks(scenario: TeamScenario) -> dict[str, Job]:
    """Each robot's first task in the initial allocation (robots with none left out)."""
    workers = [Worker(r.name, r.start.cell) for r in scenario.robots if r.gripper]
    jobs = [Job(t.item, t.pickup, t.dropoff) for t in scenario.tasks]
    maps = distance_maps(scenario.maze, [j.source for j in jobs] + [j.dropoff for j in jobs])
    order, _ = allocate(workers, jobs, maps)
    return {name: assigned[0] for name, assigned in order.items() if assigned}


def _corridor(scenario: TeamScenario, job: Job, rng: np.random.Generator) -> tuple[Cell, ...]:
    """Cells across the corridor half-way along the grid path of ``job`` (its pickup to its
    drop-off), such that every robot and task cell stays connected (a detour exists); where
    every such cut would split the maze, one cell of the path (the robot must go round it)."""
    maze = scenario.maze
    path = _grid_path(maze, job.source, job.dropoff)
    keep = {r.start.cell for r in scenario.robots}
    keep |= {c for t in scenario.tasks for c in (t.pickup, t.dropoff)}
    middle = path[len(path) // 4 : max(len(path) // 4 + 1, 3 * len(path) // 4)]
    order = [middle[int(i)] for i in rng.permutation(len(middle))]
    for narrow in (False, True):  # the corridor's whole width, else one cell of it
        for cell in order:
            index = path.index(cell)
            if index == 0 or cell in keep:
                continue
            across = {cell} if narrow else _across(maze, cell, path[index - 1])
            if keep.isdisjoint(across) and _connected(maze, frozenset(across), keep):
                return tuple(sorted(across))
    return ()


def _across(maze: Maze, cell: Cell, before: Cell) -> set[Cell]:
    """``cell`` and the free cells beside it, across the direction of travel (the corridor's
    width, at most three cells each way)."""
    dx, dy = cell[0] - before[0], cell[1] - before[1]
    side = (dy, dx)
    out = {cell}
    for sign in (1, -1):
        for step in range(1, 4):
            other = (cell[0] + sign * step * side[0], cell[1] + sign * step * side[1])
            if not maze.is_free(*other):
                break
            out.add(other)
    return out


def _connected(maze: Maze, blocked: frozenset[Cell], cells: set[Cell]) -> bool:
    label = components(_walled(maze, blocked))
    return len({label.get(c, -1) for c in cells}) == 1 and all(c in label for c in cells)


def _walled(maze: Maze, blocked: frozenset[Cell]) -> Maze:
    walls = maze.walls.copy()
    for x, y in blocked:
        walls[y, x] = True
    return Maze(walls, name=maze.name)


def _grid_path(maze: Maze, start: Cell, goal: Cell) -> list[Cell]:
    parent: dict[Cell, Cell | None] = {start: None}
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        if (x, y) == goal:
            break
        for nxt in ((x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y)):
            if nxt not in parent and maze.is_free(*nxt):
                parent[nxt] = (x, y)
                queue.append(nxt)
    if goal not in parent:
        return [start]
    path = [goal]
    while (prev := parent[path[-1]]) is not None:
        path.append(prev)
    return path[::-1]


# --- running --------------------------------------------------------------------------------------

_BASELINES: BoundedCache[tuple[Maze, int, int, str, int, str], Fraction] = BoundedCache(
    "team fault-free makespans", 512, kind=CacheKind.REFERENCE, per_map=True
)


def run_case(maze: Maze, case: TeamCase, options: TeamOptions) -> tuple[TeamResult, Fraction]:
    """Run ``case`` with ``options``; returns the result and the fault-free makespan."""
    scenario = build_scenario(maze, case)
    key = (maze, case.team_size, case.tasks, str(case.grippers), case.seed, options.backend)
    calm = replace(options, strategy=StrategyName.ALONE)
    baseline = _BASELINES.get(key, lambda: run_team(scenario.without_faults(), calm).makespan)
    return run_team(scenario, options), baseline


def case_row(
    maze: Maze, case: TeamCase, options: TeamOptions
) -> dict[str, int | float | str | None]:
    """The metrics row of ``case`` run with ``options`` (see :func:`run_case`), with the fault's
    description and the faulty robot."""
    result, baseline = run_case(maze, case, options)
    row = team_row(result, baseline)
    faults = result.scenario.faults
    row["fault"] = "; ".join(f.describe() for f in faults) or "none"
    row["faulty_robot"] = next((f.robot for f in faults if f.robot), None)
    return row
