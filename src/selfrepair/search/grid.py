"""Plain grid A* with MovingAI rules: 4- or 8-connected, straight 1, diagonal sqrt(2).

A diagonal step needs both orthogonally adjacent cells free (no corner cutting). The heuristic is
the Manhattan distance (4-connected) or the octile distance ``max + (sqrt2 - 1) * min``
(8-connected): both are the exact distance on an empty grid, hence admissible and consistent.

Exactness
    The cost of a path is reported exactly as an :class:`OctileCost` ``straight + diagonal *
    sqrt2`` (counted along the path); ``.value`` is its float for comparison with ``.scen`` files.
    The search itself orders nodes by float ``g + h``. That is exact for every grid we meet: two
    different values ``a + b*sqrt2`` with ``|a|, |b| <= n`` differ by at least ``1 / (2.42 n)``
    (because ``|a^2 - 2 b^2| >= 1``), while the float error of a sum of ``n`` such steps stays
    below ``n^2 * 2.42 * 2^-53``; for paths shorter than 70,000 steps the float order is the exact
    order, so the path found is exactly optimal.

Determinism: neighbours in the order N, E, S, W, NE, SE, SW, NW and heap keys ``(f, h, counter)``,
in the pure-Python reference (:func:`selfrepair.search.astar`) and in the numba kernel alike.
"""

from __future__ import annotations

import itertools
import sys
import time

import numpy as np

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell
from selfrepair.search.astar import PlanStatus, astar, deadline_from
from selfrepair.search.backend import use_numba
from selfrepair.search.problem import (
    CONNECTIVITIES,
    NEIGHBOURS,
    SQRT2,
    GridResult,
    OctileCost,
    check_search_inputs,
    grid_heuristic,
)
from selfrepair.world.maze import Maze

__all__ = [
    "CONNECTIVITIES",
    "NEIGHBOURS",
    "SQRT2",
    "GridResult",
    "OctileCost",
    "grid_astar",
    "grid_heuristic",
]


def grid_astar(
    maze: Maze,
    start: Cell,
    goal: Cell,
    *,
    connectivity: int = 8,
    max_expansions: int | None = None,
    time_limit: float | None = None,
    backend: str = "auto",
) -> GridResult:
    """Shortest path from ``start`` to ``goal`` on ``maze`` under MovingAI rules.

    Raises :class:`ProblemError` for a start or goal outside the grid or in a wall, a connectivity
    other than 4 or 8, an unknown backend or a negative budget. The first call of a process with
    the compiled backend imports numba and loads the kernels: ``kernel_load_ns``, left out of
    ``wall_time_ns`` and of the time limit.
    """
    t0 = time.perf_counter_ns()
    check_search_inputs(
        maze,
        (("start", start), ("goal", goal)),
        backend=backend,
        max_expansions=max_expansions,
        time_limit=time_limit,
    )
    if connectivity not in CONNECTIVITIES:
        raise ProblemError(f"connectivity must be 4 or 8, got {connectivity}")
    fast, load_ns = _load(backend)
    if start == goal:
        return GridResult(
            PlanStatus.SOLVED, (start,), OctileCost(0, 0), 0, _since(t0, load_ns), load_ns
        )
    deadline = deadline_from(time_limit, t0 + load_ns)
    found = None
    if fast:
        from selfrepair.search import _kernels

        try:
            found = _kernels.grid_search(maze, start, goal, connectivity, max_expansions, deadline)
        except OverflowError:  # a grid too large for int32 indices: Python has no such limit
            found = None
    if found is None:
        found = _grid_python(maze, start, goal, connectivity, max_expansions, deadline)
    status, path, expansions, diagonal = found
    if status is not PlanStatus.SOLVED:
        return GridResult(status, (), None, expansions, _since(t0, load_ns), load_ns)
    cost = OctileCost(len(path) - 1 - diagonal, diagonal)
    return GridResult(status, path, cost, expansions, _since(t0, load_ns), load_ns)


def _load(backend: str) -> tuple[bool, int]:
    """Whether ``backend`` means the compiled kernel, and the nanoseconds spent now importing
    numba and loading it (0 when this process already had)."""
    t0 = time.perf_counter_ns()
    cold = "selfrepair.search._kernels" not in sys.modules
    fast = use_numba(backend)
    global _KERNEL_LOADED
    if fast and not _KERNEL_LOADED:
        _KERNEL_LOADED = cold = True
        maze = Maze(np.zeros((3, 3), dtype=bool))
        for connectivity in CONNECTIVITIES:
            grid_astar(maze, (0, 0), (2, 2), connectivity=connectivity, backend="numba")
    return fast, (time.perf_counter_ns() - t0 if cold else 0)


_KERNEL_LOADED = False
"""Whether this process has loaded the grid kernel (see :func:`_load`)."""


def _grid_python(
    maze: Maze,
    start: Cell,
    goal: Cell,
    connectivity: int,
    max_expansions: int | None,
    deadline_ns: int | None,
) -> tuple[PlanStatus, tuple[Cell, ...], int, int]:
    """The reference search on :func:`selfrepair.search.astar` with cells as nodes; returns the
    status, path, expansions and number of diagonal steps."""
    h, w = maze.walls.shape
    free = (~maze.walls).tolist()

    def is_free(x: int, y: int) -> bool:
        return 0 <= x < w and 0 <= y < h and bool(free[y][x])

    def successors(cell: Cell) -> list[tuple[Cell, float, None]]:
        x, y = cell
        out: list[tuple[Cell, float, None]] = []
        for dx, dy in NEIGHBOURS[:connectivity]:
            nx, ny = x + dx, y + dy
            if not is_free(nx, ny):
                continue
            if dx and dy:
                if not (is_free(x + dx, y) and is_free(x, y + dy)):
                    continue
                out.append(((nx, ny), SQRT2, None))
            else:
                out.append(((nx, ny), 1.0, None))
        return out

    outcome = astar(
        start,
        successors=successors,
        heuristic=lambda cell: grid_heuristic(cell, goal, connectivity),
        is_goal=lambda cell: cell == goal,
        max_expansions=max_expansions,
        deadline_ns=deadline_ns,
    )
    path = outcome.path
    diagonal = sum(1 for a, b in itertools.pairwise(path) if a[0] != b[0] and a[1] != b[1])
    return outcome.status, path, outcome.expansions, diagonal


def _since(t0: int, load_ns: int = 0) -> int:
    return time.perf_counter_ns() - t0 - load_ns
