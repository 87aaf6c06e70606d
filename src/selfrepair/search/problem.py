"""The values that planning queries and answers are made of, for both planners and the kernels.

:class:`PlanningProblem` and :class:`PlanResult` are the robot-lattice planner's question and
answer (:mod:`selfrepair.search.lattice`); :class:`GridResult` and :class:`OctileCost` those of the
MovingAI grid planner (:mod:`selfrepair.search.grid`); :class:`CellBound` is a heuristic as data.
They sit in a module of their own so that the compiled kernels can use them without importing the
planners that call the kernels.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose, make_pose
from selfrepair.robots.domain import Domain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import BACKENDS, MAX_TIME_LIMIT, PlanStatus
from selfrepair.search.term import StepTerm
from selfrepair.world.maze import Maze

__all__ = [
    "CONNECTIVITIES",
    "NEIGHBOURS",
    "SQRT2",
    "CellBound",
    "GridResult",
    "OctileCost",
    "PlannerSettings",
    "PlanningProblem",
    "StepTerm",
    "check_search_inputs",
    "grid_heuristic",
    "make_pose",
    "pose_table",
    "with_border",
]


@dataclass(frozen=True, slots=True)
class PlanningProblem:
    """What to plan: from ``start`` to ``goal`` (any heading unless ``goal_heading``) on ``maze``,
    for the robot ``domain`` (the four-wheel robot unless given).

    ``faults`` are the faults the planner knows about; actions they forbid are never used.
    ``step_term`` adds a cost term per (pose, action) (:class:`StepTerm`: the tolerant planner's
    masks); ``None``, the default, costs nothing.
    """

    maze: Maze
    start: Pose
    goal: Cell
    goal_heading: Heading | None = None
    faults: frozenset[Any] = frozenset()
    clearance_weight: Fraction | int = Fraction(0)
    clearance_radius: int = 2
    domain: Domain[Any, Any] = FOUR_WHEEL
    step_term: StepTerm | None = None

    def at_goal(self, pose: Pose) -> bool:
        """Whether ``pose`` satisfies the goal."""
        return pose.cell == self.goal and (
            self.goal_heading is None or pose.heading == self.goal_heading
        )


@dataclass(frozen=True, slots=True)
class PlannerSettings:
    """How every planner call of a mission is made (initial plan, replans, lookahead windows):
    heuristic and backend names, the clearance cost term, and the node budget of a replan."""

    heuristic: str = "grid-distance"
    backend: str = "auto"
    clearance_weight: Fraction = Fraction(0)
    clearance_radius: int = 2
    max_expansions: int | None = None


@dataclass(frozen=True, slots=True)
class CellBound:
    """A heuristic as data: ``h(pose) = rate * distance[y, x]`` ticks.

    ``padded`` is an ``int32`` array of shape ``(height + 2, width + 2)``: the distances with a
    negative border (the layout the numba kernels use). A negative value marks a cell from which
    the goal cannot be reached; such nodes are pruned.
    """

    padded: npt.NDArray[np.int32]
    rate: Fraction

    @property
    def distance(self) -> npt.NDArray[np.int32]:
        """The distances as an ``[y, x]`` array (a view without the border)."""
        return self.padded[1:-1, 1:-1]


def pose_table(maze: Maze) -> list[Pose | None] | None:
    """The canonical :class:`~selfrepair.geometry.Pose` of each lattice state of ``maze``, made
    on first use: index ``4 * ((y + 1) * (width + 2) + x + 1) + heading`` (the kernels' padded
    state layout), ``None`` where not made yet. Plan paths and simulator steps share these
    immutable values instead of building a new pose per step. Only for mazes of at most
    :data:`POSE_TABLE_CELLS` cells (8 bytes per state); ``None`` for larger ones. Kept per maze
    in a bounded cache."""
    if maze.width * maze.height > POSE_TABLE_CELLS:
        return None
    return _POSES.get(maze, lambda: [None] * (4 * (maze.height + 2) * (maze.width + 2)))


POSE_TABLE_CELLS = 1 << 16
"""The largest maze (cells) with a :func:`pose_table`: 256 x 256, 2 MB per table."""

_POSES: BoundedCache[Maze, list[Pose | None]] = BoundedCache(
    "canonical poses per maze", 16, kind=CacheKind.PLAN, per_map=True
)


def with_border(inner: npt.NDArray[np.integer]) -> npt.NDArray[np.int32]:
    padded = np.full((inner.shape[0] + 2, inner.shape[1] + 2), -1, dtype=np.int32)
    padded[1:-1, 1:-1] = inner
    return padded


SQRT2 = math.sqrt(2.0)


CONNECTIVITIES = (4, 8)


NEIGHBOURS: tuple[Cell, ...] = (
    (0, -1),
    (1, 0),
    (0, 1),
    (-1, 0),
    (1, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
)
"""Neighbour offsets ``(dx, dy)``: the first four are straight, the last four diagonal."""


@dataclass(frozen=True, slots=True, order=True)
class OctileCost:
    """An exact path cost ``straight + diagonal * sqrt(2)``."""

    straight: int
    diagonal: int

    @property
    def value(self) -> float:
        """The cost as a float, for comparison with MovingAI ``optimal_length``."""
        return self.straight + self.diagonal * SQRT2

    def __str__(self) -> str:
        if self.diagonal == 0:
            return str(self.straight)
        return f"{self.straight}+{self.diagonal}*sqrt2"


@dataclass(frozen=True, slots=True)
class GridResult:
    """The outcome of :func:`grid_astar`; ``path`` (start first) is empty unless solved.
    ``wall_time_ns`` leaves out ``kernel_load_ns``, the time this call spent importing and loading
    (or compiling) the compiled kernels (only the first call of a process pays it)."""

    status: PlanStatus
    path: tuple[Cell, ...]
    cost: OctileCost | None
    expansions: int
    wall_time_ns: int
    kernel_load_ns: int = 0


def grid_heuristic(cell: Cell, goal: Cell, connectivity: int) -> float:
    """Manhattan (4) or octile (8) distance from ``cell`` to ``goal``, as a float."""
    dx = abs(cell[0] - goal[0])
    dy = abs(cell[1] - goal[1])
    if connectivity == 4:
        return float(dx + dy)
    return (dx + dy) + (SQRT2 - 2.0) * min(dx, dy)


def check_search_inputs(
    maze: Maze,
    endpoints: Iterable[tuple[str, tuple[int, int]]],
    *,
    backend: str,
    max_expansions: int | None,
    time_limit: float | None,
) -> None:
    """Raise :class:`ProblemError` for an endpoint outside ``maze`` or in a wall, an unknown
    backend, or a negative budget: the checks the grid and lattice planners share."""
    walls = maze.walls
    height, width = walls.shape
    for label, (x, y) in endpoints:
        if not (0 <= x < width and 0 <= y < height):
            raise ProblemError(f"the {label} ({x},{y}) is outside the {width}x{height} maze")
        if walls[y, x]:
            raise ProblemError(f"the {label} ({x},{y}) is a wall")
    if backend not in BACKENDS:
        raise ProblemError(f"unknown backend {backend!r}; expected one of {', '.join(BACKENDS)}")
    if max_expansions is not None and max_expansions < 0:
        raise ProblemError(f"max_expansions must be >= 0, got {max_expansions}")
    if time_limit is not None and not 0 <= time_limit <= MAX_TIME_LIMIT:
        raise ProblemError(f"time_limit must be from 0 to {MAX_TIME_LIMIT:g} s, got {time_limit}")
