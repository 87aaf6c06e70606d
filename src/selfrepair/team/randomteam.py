"""Random team scenarios, drawn from a seeded generator: robots on distinct cells, tasks with
distinct pickup and drop-off cells, all in the maze's largest 4-connected area.

Scenario files draw robots and tasks here when they give counts (``robots = 4``), and team
experiments draw every mission's team here; the same seed gives the same team.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES, MAX_ROBOTS, MAX_TASKS, check_limit
from selfrepair.robots.domain import SomeDomain
from selfrepair.team.grid import grid_distances, largest_area
from selfrepair.team.model import RobotSpec, Task, TeamScenario
from selfrepair.world.maze import Maze

__all__ = ["DEFAULT_LIMITS", "GripperMix", "Limits", "draw_tasks", "has_gripper", "random_scenario"]


@dataclass(frozen=True, slots=True)
class Limits:
    """How many robots, tasks and maze cells a scenario may have, and how big its file may be
    (:mod:`selfrepair.limits`; ``None`` turns a check off). The commands set them with
    ``--max-robots``, ``--max-tasks``, ``--max-cells`` and ``--max-file-bytes``."""

    max_robots: int | None = MAX_ROBOTS
    max_tasks: int | None = MAX_TASKS
    max_cells: int | None = MAX_CELLS
    max_file_bytes: int | None = MAX_FILE_BYTES


DEFAULT_LIMITS = Limits()
"""The limits of :mod:`selfrepair.limits`."""


class GripperMix(StrEnum):
    """Equipment of randomly drawn robots: every robot has a gripper (``all``), or every third
    robot (the 3rd, 6th, ...) has none (``mixed``)."""

    ALL = "all"
    MIXED = "mixed"


def has_gripper(mix: GripperMix, index: int) -> bool:
    """Whether robot number ``index`` (0-based) of a random team has a gripper."""
    return mix is GripperMix.ALL or index % 3 != 2


def random_scenario(
    maze: Maze,
    robots: int,
    tasks: int,
    rng: np.random.Generator,
    *,
    grippers: GripperMix = GripperMix.ALL,
    domain: SomeDomain | None = None,
    name: str = "random",
    limits: Limits = DEFAULT_LIMITS,
) -> TeamScenario:
    """``robots`` robots (``r1``, ``r2``, ...) on distinct cells and ``tasks`` tasks (``i1``, ...)
    with distinct pickup and drop-off cells, all drawn from ``rng`` in the maze's largest
    4-connected area; a drop-off lies at least half the largest distance from its pickup."""
    area = largest_area(maze)
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
    drawn = draw_tasks(maze, tasks, rng, {r.start.cell for r in team}, limits.max_tasks)
    scenario = TeamScenario(maze, team, drawn, (), name=name, source=f"<random:{name}>")
    return scenario if domain is None else replace(scenario, domain=domain)


def draw_tasks(
    maze: Maze, count: int, rng: np.random.Generator, taken: set[Cell], max_tasks: int | None
) -> tuple[Task, ...]:
    """``count`` tasks on free cells of the largest area not in ``taken`` (see
    :func:`random_scenario`)."""
    area = [c for c in largest_area(maze) if c not in taken]
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
