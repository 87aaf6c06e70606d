"""Loading the compiled kernels before anything is timed.

The first call of each numba kernel in a process compiles it (or loads it from the on-disk cache);
:func:`ensure_warm` pays that once, on a tiny maze, so that callers can keep it out of what they
measure. It sits above both planners because it calls them.
"""

from __future__ import annotations

import time
from fractions import Fraction

import numpy as np

from selfrepair.geometry import Heading, Pose
from selfrepair.search.grid import grid_astar
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.maze import Maze

__all__ = ["ensure_warm", "warm_up"]


_WARM = False


def ensure_warm() -> int:
    """Run :func:`warm_up` once per process, so a caller can keep the one-off cost of loading
    (or compiling) the kernels out of what it times; returns the nanoseconds this call spent
    (0 when the kernels were already warm), so the caller can report the load on its own."""
    global _WARM
    if _WARM:
        return 0
    spent = warm_up()
    _WARM = True
    return spent


def warm_up() -> int:
    """Compile (or load from the cache) every kernel on a tiny maze; returns nanoseconds taken."""

    t0 = time.perf_counter_ns()
    maze = Maze(np.zeros((3, 3), dtype=bool))
    grid_astar(maze, (0, 0), (2, 2), connectivity=8, backend="numba")
    grid_astar(maze, (0, 0), (2, 2), connectivity=4, backend="numba")
    start = Pose(0, 0, Heading.E)
    plan(PlanningProblem(maze, start, (2, 2)), backend="numba")
    plan(PlanningProblem(maze, start, (2, 2), clearance_weight=Fraction(1)), backend="numba")
    return time.perf_counter_ns() - t0
