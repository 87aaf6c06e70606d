"""The lattice planner's heuristics (:data:`HEURISTICS`), all admissible and consistent.

Each is ``h(pose) = rate * d(pose.cell)`` with ``rate`` the least number of ticks per cell of
Manhattan progress over the available actions, from any heading (:func:`progress_rate`; 1 for a
healthy four-wheel robot). ``"zero"`` uses ``d = 0``; ``"manhattan"`` the Manhattan distance to
the goal cell; ``"grid-distance"`` the exact 4-connected BFS distance to the goal cell on the
maze (cells that cannot reach the goal are pruned). Consistency: an action whose endpoints are
``a`` and ``b`` with Manhattan displacement ``m`` changes the Manhattan distance by at most
``m``, so ``cost >= duration >= rate * m >= rate * (d(a) - d(b))``. For the BFS distance this
needs one more property of the domain, ``Domain.footprint_connected``: the footprint holds a
4-connected free path from ``a`` to ``b`` of length ``m`` (true for the four-wheel robot: a
straight move is one step; an arc sweeps ``a``, the cell ahead, and ``b`` beside it). For a
domain without it ``"grid-distance"`` is refused. The clearance term is non-negative, so the
bound holds for any weight, and ``d(goal) = 0``. Internally costs are scaled to integers
(``S = domain.time_unit * weight denominator``) and ``h`` is rounded down,
which keeps it consistent because edge costs are integers.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Protocol

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.domain import progress_rate as domain_progress_rate
from selfrepair.search.backend import use_numba
from selfrepair.search.problem import CellBound, PlanningProblem, with_border
from selfrepair.world.maze import Maze

__all__ = [
    "HEURISTICS",
    "NEEDS_CONNECTED_FOOTPRINTS",
    "HeuristicFn",
    "bfs_distances",
    "heuristic_bound",
    "progress_rate",
]


class HeuristicFn(Protocol):
    """A heuristic builder: ``(maze, goal, domain, actions, *, backend) -> CellBound``."""

    def __call__(
        self,
        maze: Maze,
        goal: Cell,
        domain: SomeDomain,
        actions: Sequence[object],
        *,
        backend: str = "auto",
    ) -> CellBound: ...


def progress_rate(domain: SomeDomain, actions: Sequence[object]) -> Fraction:
    """Least ticks per cell of Manhattan displacement over ``actions`` from any heading (0 if none
    moves)."""
    return _RATES.get((domain, tuple(actions)), lambda: _progress_rate(domain, actions))


_RATES: BoundedCache[tuple[SomeDomain, tuple[object, ...]], Fraction] = BoundedCache(
    "planner progress rates", 1024, kind=CacheKind.PLAN
)


def _progress_rate(domain: SomeDomain, actions: Sequence[object]) -> Fraction:
    return domain_progress_rate(domain, actions)


def _zero_distances(maze: Maze, goal: Cell, backend: str) -> npt.NDArray[np.int32]:
    return with_border(np.zeros(maze.walls.shape, dtype=np.int64))


def _manhattan_distances(maze: Maze, goal: Cell, backend: str) -> npt.NDArray[np.int32]:
    ys, xs = np.indices(maze.walls.shape, dtype=np.int64)
    return with_border(np.abs(xs - goal[0]) + np.abs(ys - goal[1]))


_DistanceFn = Callable[[Maze, Cell, str], npt.NDArray[np.int32]]


def _goal_distances(
    make: _DistanceFn, maze: Maze, goal: Cell, backend: str
) -> tuple[npt.NDArray[np.int32], int]:
    """The padded distances of a built-in heuristic to one goal and their maximum, made once and
    reused by every query to that goal on that maze (any faults, any start, either backend: both
    compute the same distances): read-only arrays in a bounded cache, a small one for large mazes
    (an entry costs 4 bytes per cell)."""
    cache = _DISTANCES if maze.width * maze.height <= _SMALL_MAZE else _LARGE_DISTANCES

    def made() -> tuple[npt.NDArray[np.int32], int]:
        distance = make(maze, goal, backend)
        distance.setflags(write=False)
        return distance, int(distance.max(initial=0))

    return cache.get((make, maze, goal), made)


_SMALL_MAZE = 1 << 18
"""Mazes up to this many cells (512 x 512) share the larger cache of goal distances."""

_Distances = tuple[npt.NDArray[np.int32], int]
_DISTANCES: BoundedCache[tuple[_DistanceFn, Maze, Cell], _Distances] = BoundedCache(
    "goal distances (mazes up to 512x512)", 32, kind=CacheKind.PLAN, per_map=True
)
_LARGE_DISTANCES: BoundedCache[tuple[_DistanceFn, Maze, Cell], _Distances] = BoundedCache(
    "goal distances (larger mazes)", 4, kind=CacheKind.PLAN, per_map=True
)


NEEDS_CONNECTED_FOOTPRINTS = frozenset({"grid-distance"})
"""Heuristics that are admissible only for domains with ``footprint_connected``."""


def bfs_distances(maze: Maze, goal: Cell, *, backend: str = "auto") -> npt.NDArray[np.int32]:
    """Exact 4-connected step distance from every cell to ``goal`` (-1: unreachable or wall)."""
    return np.maximum(_bfs_padded(maze, goal, backend)[1:-1, 1:-1], -1)


def _bfs_padded(maze: Maze, goal: Cell, backend: str) -> npt.NDArray[np.int32]:
    if use_numba(backend):
        from selfrepair.search import _kernels

        return _kernels.bfs_padded(maze, goal)
    h, w = maze.walls.shape
    free = (~maze.walls).tolist()
    dist = [[-1] * w for _ in range(h)]
    gx, gy = goal
    dist[gy][gx] = 0
    queue = deque([(gx, gy)])
    while queue:
        x, y = queue.popleft()
        d = dist[y][x] + 1
        for nx, ny in ((x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y)):
            if 0 <= nx < w and 0 <= ny < h and free[ny][nx] and dist[ny][nx] < 0:
                dist[ny][nx] = d
                queue.append((nx, ny))
    return with_border(np.array(dist, dtype=np.int32))


@dataclass(frozen=True, slots=True)
class _BuiltIn:
    """A built-in heuristic: the cached distances ``make`` gives to the goal (to a fixed cell
    for ``zero``: they are the same for every goal), times the progress rate of the actions when
    ``scaled``. :func:`heuristic_bound` builds its bound from these parts without calling it (the
    same bound, with the rate the planner has already computed for the fault set)."""

    make: _DistanceFn
    scaled: bool

    def target(self, goal: Cell) -> Cell:
        """The cell the distances are measured to."""
        return goal if self.make is not _zero_distances else (0, 0)

    def __call__(
        self,
        maze: Maze,
        goal: Cell,
        domain: SomeDomain,
        actions: Sequence[object],
        *,
        backend: str = "auto",
    ) -> CellBound:
        distance, _ = _goal_distances(self.make, maze, self.target(goal), backend)
        return CellBound(distance, progress_rate(domain, actions) if self.scaled else Fraction(0))


HEURISTICS: dict[str, HeuristicFn] = {
    "zero": _BuiltIn(_zero_distances, scaled=False),
    "manhattan": _BuiltIn(_manhattan_distances, scaled=True),
    "grid-distance": _BuiltIn(_bfs_padded, scaled=True),
}
"""Heuristic registry: name -> function ``(maze, goal, domain, actions, *, backend) ->
CellBound``."""


def heuristic_bound(
    problem: PlanningProblem,
    heuristic: str,
    actions: Sequence[object],
    rate: Fraction,
    backend: str,
) -> tuple[CellBound, int | None]:
    """The heuristic bound of ``problem`` for the planning ``actions`` and their progress
    ``rate`` (see :class:`_BuiltIn`), and its largest distance when known without a scan."""
    fn = HEURISTICS[heuristic]
    if not isinstance(fn, _BuiltIn):
        bound = fn(problem.maze, problem.goal, problem.domain, actions, backend=backend)
        return bound, None
    distance, largest = _goal_distances(fn.make, problem.maze, fn.target(problem.goal), backend)
    return CellBound(distance, rate if fn.scaled else Fraction(0)), largest
