"""Task allocation: which robot delivers which item, in which order, and the team plan it gives.

:func:`allocate` assigns tasks in rounds with the Hungarian method
(``scipy.optimize.linear_sum_assignment``): in each round every capable robot
gets at most one task, minimising the sum of the estimated completion times

    ready(robot) + d(robot's position, where the item is) + d(there, drop-off)

where ``d`` is the 4-connected grid distance on the known map (a healthy four-wheel robot needs
at least one tick per cell) and ``ready`` the estimated time the robot finishes what it was given
in earlier rounds; a round's robots then stand at their drop-off cells. Pairs that cannot reach
each other cost :data:`UNREACHABLE` and are never assigned. This is the classic round-based
assignment of multi-robot task allocation (Gerkey & Mataric 2004, "ST-SR-TA" with time-extended
rounds).

The same function serves the initial allocation and the *full re-allocation* strategy, which calls
it with every open task (an item lying somewhere, or carried by a robot that can no longer
deliver it: then the new robot takes it over in a handover next to the carrier).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.optimize import linear_sum_assignment

from selfrepair.geometry import Cell
from selfrepair.search.lattice import bfs_distances
from selfrepair.team.model import DROP_TICKS, PICK_TICKS, TeamAction, drive, drop, handover, pick
from selfrepair.world.maze import Maze

__all__ = [
    "UNREACHABLE",
    "DistanceMap",
    "Job",
    "Worker",
    "allocate",
    "distance_maps",
    "job_plan",
]

UNREACHABLE = 10**9
"""The cost of a robot-task pair that cannot reach each other."""


@dataclass(frozen=True, slots=True)
class Job:
    """An open task: bring ``item`` from ``source`` to ``dropoff``. ``holder`` names the robot
    that carries it and cannot deliver it any more (the new robot then takes it in a handover
    next to ``source``, the holder's cell); empty when the item lies on ``source``."""

    item: str
    source: Cell
    dropoff: Cell
    holder: str = ""


@dataclass(frozen=True, slots=True)
class Worker:
    """A robot that can take tasks: where it will be free, and when (estimated ticks from now)."""

    name: str
    cell: Cell
    ready: int = 0


DistanceMap = npt.NDArray[np.int32]
"""Grid distances to one cell, ``[y, x]``, -1 where it cannot be reached."""


def distance_maps(
    maze: Maze, cells: Sequence[Cell], *, backend: str = "auto"
) -> dict[Cell, DistanceMap]:
    """The 4-connected distance from every cell to each of ``cells`` on ``maze``."""
    return {c: bfs_distances(maze, c, backend=backend) for c in dict.fromkeys(cells)}


def _distance(maps: Mapping[Cell, DistanceMap], target: Cell, cell: Cell, *, adjacent: bool) -> int:
    """Grid distance from ``cell`` to ``target`` (to a cell next to it when ``adjacent``)."""
    value = int(maps[target][cell[1], cell[0]])
    if value < 0:
        return UNREACHABLE
    return max(0, value - 1) if adjacent else value


def _carry(maps: Mapping[Cell, DistanceMap], job: Job) -> int:
    """Grid distance from where the job's item is taken to its drop-off: from its cell, or,
    for an item taken from a carrier, from the nearest cell next to the carrier."""
    grid = maps[job.dropoff]
    x, y = job.source
    if not job.holder:
        value = int(grid[y, x])
        return value if value >= 0 else UNREACHABLE
    height, width = grid.shape
    values = [
        int(grid[ny, nx])
        for nx, ny in ((x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y))
        if 0 <= nx < width and 0 <= ny < height and grid[ny, nx] >= 0
    ]
    return min(values) if values else UNREACHABLE


def allocate(
    workers: Sequence[Worker], jobs: Sequence[Job], maps: Mapping[Cell, DistanceMap]
) -> tuple[dict[str, list[Job]], tuple[Job, ...]]:
    """Jobs per worker, in the order to do them, and the jobs no worker can reach (see the
    module docstring). ``maps`` must hold the distance map of every job's source and drop-off."""
    order: dict[str, list[Job]] = {w.name: [] for w in workers}
    cell = {w.name: w.cell for w in workers}
    ready = {w.name: w.ready for w in workers}
    remaining = list(jobs)
    names = [w.name for w in workers]
    while remaining and names:
        costs = np.full((len(names), len(remaining)), UNREACHABLE, dtype=np.int64)
        for i, name in enumerate(names):
            for j, job in enumerate(remaining):
                fetch = _distance(maps, job.source, cell[name], adjacent=bool(job.holder))
                carry = _carry(maps, job)
                if fetch < UNREACHABLE and carry < UNREACHABLE:
                    costs[i, j] = ready[name] + fetch + carry
        rows, cols = linear_sum_assignment(costs)
        assigned = [
            (int(i), int(j)) for i, j in zip(rows, cols, strict=True) if costs[i, j] < UNREACHABLE
        ]
        if not assigned:
            break
        for i, j in assigned:
            name, job = names[i], remaining[j]
            order[name].append(job)
            ready[name] = int(costs[i, j]) + PICK_TICKS + DROP_TICKS
            cell[name] = job.dropoff
        taken = {j for _, j in assigned}
        remaining = [job for j, job in enumerate(remaining) if j not in taken]
    return order, tuple(remaining)


def job_plan(
    robot: str, start: Cell, jobs: Sequence[Job], meet: Callable[[Job, Cell], Cell]
) -> list[TeamAction]:
    """The higher-level plan of ``robot`` for ``jobs`` from cell ``start``: drive to the item,
    pick it (or take it in a handover next to its holder, at the cell ``meet(job, here)``),
    drive to the drop-off, drop it."""
    actions: list[TeamAction] = []
    here = start
    for job in jobs:
        if job.holder:
            spot = meet(job, here)
            if spot != here:
                actions.append(drive(robot, here, spot))
            actions.append(handover(job.holder, robot, job.item))
            here = spot
        else:
            if job.source != here:
                actions.append(drive(robot, here, job.source))
            actions.append(pick(robot, job.item))
            here = job.source
        if job.dropoff != here:
            actions.append(drive(robot, here, job.dropoff))
        actions.append(drop(robot, job.item))
        here = job.dropoff
    return actions
