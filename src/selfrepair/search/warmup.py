"""Loading the compiled kernels before anything is timed.

The first call of each numba kernel in a process compiles it (or loads it from the on-disk cache);
:func:`ensure_warm` pays that once, on a tiny maze, so that callers can keep it out of what they
measure. It sits above both planners because it calls them.
"""

from __future__ import annotations

import time
from fractions import Fraction

import numpy as np

from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.search.grid import grid_astar
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.maze import Maze

__all__ = ["KERNELS", "ensure_warm", "warm_up"]

KERNELS = ("grid", "lattice")
"""The kernel families: the MovingAI grid search and the robot's lattice search."""

_WARM: set[str] = set()
"""The kernel families already loaded in this process (at most :data:`KERNELS`)."""


def ensure_warm(*kinds: str) -> int:
    """Run :func:`warm_up` for the kernel families ``kinds`` (default: all) not loaded yet in
    this process, so a caller can keep the one-off cost of loading (or compiling) the kernels
    out of what it times; returns the nanoseconds this call spent (0 when they were warm), so the
    caller can report the load on its own."""
    todo = tuple(k for k in (kinds or KERNELS) if k not in _WARM)
    if not todo:
        return 0
    spent = warm_up(*todo)
    _WARM.update(todo)
    return spent


def warm_up(*kinds: str) -> int:
    """Compile (or load from the cache) the kernels of ``kinds`` (default: every family of
    :data:`KERNELS`) on a tiny maze; returns nanoseconds taken."""
    unknown = set(kinds) - set(KERNELS)
    if unknown:
        raise ProblemError(f"unknown kernel family {sorted(unknown)[0]!r}: expected {KERNELS}")
    chosen = kinds or KERNELS
    t0 = time.perf_counter_ns()
    maze = Maze(np.zeros((3, 3), dtype=bool))
    if "grid" in chosen:
        grid_astar(maze, (0, 0), (2, 2), connectivity=8, backend="numba")
        grid_astar(maze, (0, 0), (2, 2), connectivity=4, backend="numba")
    if "lattice" in chosen:
        start = Pose(0, 0, Heading.E)
        plan(PlanningProblem(maze, start, (2, 2)), backend="numba")
        plan(PlanningProblem(maze, start, (2, 2), clearance_weight=Fraction(1)), backend="numba")
    return time.perf_counter_ns() - t0
