"""Exact A* for the four-wheel robot on its pose lattice ``(x, y, heading)``.

Search space and pruning
    A node is a :class:`~selfrepair.geometry.Pose`. Only actions available under the faults the
    planner knows about are used, and among those with the same motion only the fastest
    (:func:`selfrepair.robots.four_wheel.fastest_by_motion`): every other one has the same effect and is no
    shorter, so it can never improve a plan. WAIT is never useful (it costs time and changes
    nothing). The branching factor is therefore at most eight. A plan reports the concrete wheel
    action chosen for each step.

Cost (exact formula)
    For an action started at ``pose``, with swept cells ``C`` (start cell included)::

        cost = duration + clearance_weight * sum(max(0, clearance_radius - clearance(c)) for c in C)

    where ``clearance(c)`` is :func:`selfrepair.world.maze.clearance_map` (Chebyshev distance to the
    nearest wall, outside counts as wall). The penalty only bites in cells closer than
    ``clearance_radius`` to a wall, and grows by one per cell of missing clearance. With
    ``clearance_weight == 0`` the cost of a plan is its total duration, so the plan found has the
    minimum total duration.

Heuristics (:data:`HEURISTICS`), all admissible and consistent
    Each is ``h(pose) = rate * d(pose.cell)`` with ``rate`` the least number of ticks per cell of
    Manhattan progress over the available motions (``min duration / (|forward| + |lateral|)``;
    1 for a healthy robot). ``"zero"`` uses ``d = 0``; ``"manhattan"`` the Manhattan distance to the
    goal cell; ``"grid-distance"`` the exact 4-connected BFS distance to the goal cell on the maze
    (cells that cannot reach the goal are pruned). Consistency: an action whose endpoints are
    ``a`` and ``b`` with Manhattan displacement ``m`` sweeps a 4-connected free path from ``a`` to
    ``b`` of length ``m`` (a straight move is one step; an arc sweeps ``a``, the cell ahead, and
    ``b`` beside it), so ``d(a) <= m + d(b)`` for both distances, and
    ``cost >= duration >= rate * m >= rate * (d(a) - d(b))``. Turns have ``m = 0`` and leave ``d``
    unchanged. The clearance term is non-negative, so the bound holds for any weight, and
    ``d(goal) = 0``. Internally costs are scaled to integers (``S = 3 * weight denominator``) and
    ``h`` is rounded down, which keeps it consistent because edge costs are integers.

Determinism
    Heap keys ``(f, h, counter)`` and a fixed successor order (that of ``fastest_by_motion``), in
    the pure-Python backend (the reference, on :func:`selfrepair.search.astar` with
    :func:`selfrepair.robots.four_wheel.step`) and in the numba backend, which therefore return the same plan.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import replace
from fractions import Fraction
from typing import Protocol

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Pose
from selfrepair.limits import MAX_CLEARANCE_WEIGHT
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import Action, FaultSet, Motion, MotionKind
from selfrepair.search.astar import PlanStatus, astar, deadline_from
from selfrepair.search.backend import BACKENDS, numba_available, use_numba
from selfrepair.search.problem import (
    CellBound,
    PlanningProblem,
    PlanResult,
    check_search_inputs,
    with_border,
)
from selfrepair.world.maze import Maze, clearance_map, clearance_penalties

__all__ = [
    "BACKENDS",
    "HEURISTICS",
    "CellBound",
    "PlanResult",
    "PlanStatus",
    "PlanningProblem",
    "action_cost",
    "bfs_distances",
    "numba_available",
    "plan",
    "plan_cost",
    "planning_motions",
]


_DURATION_UNITS = {a.code: int(a.duration * four_wheel.TICKS_DENOMINATOR) for a in four_wheel.ACTIONS}
"""Each action's duration in units of ``1 / TICKS_DENOMINATOR`` ticks (exact integers)."""


class HeuristicFn(Protocol):
    """A heuristic builder: ``(maze, goal, motions, *, backend) -> CellBound``."""

    def __call__(
        self, maze: Maze, goal: Cell, motions: Mapping[Motion, Action], *, backend: str = "auto"
    ) -> CellBound: ...


def planning_motions(faults: FaultSet) -> dict[Motion, Action]:
    """The fastest available action of each motion except WAIT, in ``fastest_by_motion`` order."""
    return {
        m: a for m, a in four_wheel.fastest_by_motion(faults).items() if m.kind is not MotionKind.WAIT
    }


def progress_rate(motions: Mapping[Motion, Action]) -> Fraction:
    """Least ticks per cell of Manhattan displacement over ``motions`` (0 if none moves)."""
    rates = [
        a.duration / (abs(m.forward) + abs(m.lateral))
        for m, a in motions.items()
        if abs(m.forward) + abs(m.lateral) > 0
    ]
    return min(rates, default=Fraction(0))


def _zero_bound(
    maze: Maze, goal: Cell, motions: Mapping[Motion, Action], *, backend: str = "auto"
) -> CellBound:
    return CellBound(with_border(np.zeros(maze.walls.shape, dtype=np.int64)), Fraction(0))


def _manhattan_bound(
    maze: Maze, goal: Cell, motions: Mapping[Motion, Action], *, backend: str = "auto"
) -> CellBound:
    ys, xs = np.indices(maze.walls.shape, dtype=np.int64)
    distance = np.abs(xs - goal[0]) + np.abs(ys - goal[1])
    return CellBound(with_border(distance), progress_rate(motions))


def _grid_distance_bound(
    maze: Maze, goal: Cell, motions: Mapping[Motion, Action], *, backend: str = "auto"
) -> CellBound:
    return CellBound(_bfs_padded(maze, goal, backend), progress_rate(motions))


HEURISTICS: dict[str, HeuristicFn] = {
    "zero": _zero_bound,
    "manhattan": _manhattan_bound,
    "grid-distance": _grid_distance_bound,
}
"""Heuristic registry: name -> function ``(maze, goal, motions, *, backend) -> CellBound``."""


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


def action_cost(
    maze: Maze, pose: Pose, action: Action, *, clearance_weight: Fraction, clearance_radius: int
) -> Fraction:
    """The exact cost of ``action`` at ``pose`` (see the module docstring for the formula).

    Does not check that the swept cells are free; :func:`plan_cost` does.
    """
    clearance = clearance_map(maze)
    cost = action.duration
    if clearance_weight:
        penalty = sum(
            max(0, clearance_radius - int(clearance[y, x]))
            if maze.in_bounds(x, y)
            else clearance_radius
            for x, y in four_wheel.swept_cells(pose, action)
        )
        cost += clearance_weight * penalty
    return Fraction(cost)


def plan_cost(problem: PlanningProblem, actions: Sequence[Action]) -> Fraction:
    """Re-simulate ``actions`` from ``problem.start`` and return their total cost.

    Raises :class:`ProblemError` if an action is unavailable under ``problem.faults``, sweeps a wall
    or leaves the grid, or if the plan does not end at the goal.
    """
    pose = problem.start
    total = Fraction(0)
    for index, action in enumerate(actions):
        if not four_wheel.available(action, problem.faults):
            raise ProblemError(f"action {index} ({action}) is not available under the faults")
        end, swept, _ = four_wheel.step(pose, action)
        if not problem.maze.all_free(swept):
            raise ProblemError(
                f"action {index} ({action}) at {pose} sweeps a wall or leaves the grid"
            )
        total += action_cost(
            problem.maze,
            pose,
            action,
            clearance_weight=problem.clearance_weight,
            clearance_radius=problem.clearance_radius,
        )
        pose = end
    if not _at_goal(problem, pose):
        raise ProblemError(f"the plan ends at {pose}, not at the goal")
    return total


def plan(
    problem: PlanningProblem,
    *,
    heuristic: str = "grid-distance",
    max_expansions: int | None = None,
    time_limit: float | None = None,
    backend: str = "auto",
) -> PlanResult:
    """Find a minimum-cost plan for ``problem`` by A* (see the module docstring).

    ``max_expansions`` and ``time_limit`` (seconds) bound the search; hitting either gives
    :attr:`PlanStatus.BUDGET_EXHAUSTED`. Raises :class:`ProblemError` for a start or goal outside
    the grid or in a wall, an unknown heuristic or backend, a negative budget, a weight outside
    ``[0, MAX_CLEARANCE_WEIGHT]`` (:mod:`selfrepair.limits`) or a radius outside
    ``[0, MAX_CLEARANCE_RADIUS]``.
    """
    t0 = time.perf_counter_ns()
    _validate(problem, heuristic, max_expansions, time_limit, backend)
    if not isinstance(problem.clearance_weight, Fraction):
        problem = replace(problem, clearance_weight=Fraction(problem.clearance_weight))
    if _at_goal(problem, problem.start):
        return PlanResult(
            PlanStatus.SOLVED, (), (problem.start,), Fraction(0), Fraction(0), 0, _since(t0)
        )
    motions = planning_motions(problem.faults)
    fast = use_numba(backend)
    bound = HEURISTICS[heuristic](
        problem.maze, problem.goal, motions, backend="numba" if fast else "python"
    )
    scale = 3 * problem.clearance_weight.denominator
    deadline = deadline_from(time_limit, t0)
    found: _Found | None = None
    if fast:
        from selfrepair.search import _kernels

        try:
            found = _kernels.plan_lattice(problem, motions, bound, scale, max_expansions, deadline)
        except OverflowError:  # scaled costs beyond int64: the exact Python search still works
            found = None
    if found is None:
        found = _plan_python(problem, motions, bound, scale, max_expansions, deadline)
    status, actions, poses, cost_scaled, expansions = found
    if status is not PlanStatus.SOLVED:
        return PlanResult(status, (), (), None, Fraction(0), expansions, _since(t0))
    total = Fraction(sum(_DURATION_UNITS[a.code] for a in actions), four_wheel.TICKS_DENOMINATOR)
    return PlanResult(
        status,
        actions,
        poses,
        Fraction(cost_scaled, scale),
        total,
        expansions,
        _since(t0),
    )


_Found = tuple[PlanStatus, tuple[Action, ...], tuple[Pose, ...], int, int]


def _plan_python(
    problem: PlanningProblem,
    motions: Mapping[Motion, Action],
    bound: CellBound,
    scale: int,
    max_expansions: int | None,
    deadline_ns: int | None,
) -> _Found:
    """The reference search: poses as nodes, :func:`four_wheel.step` for every successor."""
    maze = problem.maze
    weight = problem.clearance_weight
    penalty = clearance_penalties(maze, problem.clearance_radius).tolist()
    distance = bound.distance.tolist()
    rate = bound.rate * scale
    moves = tuple(motions.values())

    def heuristic(pose: Pose) -> int | None:
        d = distance[pose.y][pose.x]
        return None if d < 0 else d * rate.numerator // rate.denominator

    def successors(pose: Pose) -> list[tuple[Pose, int, Action]]:
        out = []
        for action in moves:
            end, swept, dur = four_wheel.step(pose, action)
            if maze.all_free(swept):
                cost = dur + weight * sum(penalty[y][x] for x, y in swept)
                scaled = cost * scale
                out.append((end, scaled.numerator, action))
        return out

    outcome = astar(
        problem.start,
        successors=successors,
        heuristic=heuristic,
        is_goal=lambda pose: _at_goal(problem, pose),
        max_expansions=max_expansions,
        deadline_ns=deadline_ns,
    )
    cost = int(outcome.cost) if outcome.cost is not None else 0
    return outcome.status, outcome.labels, outcome.path, cost, outcome.expansions


def _at_goal(problem: PlanningProblem, pose: Pose) -> bool:
    return pose.cell == problem.goal and (
        problem.goal_heading is None or pose.heading == problem.goal_heading
    )


MAX_CLEARANCE_RADIUS = 1_000_000
"""Far beyond any maze's clearance; keeps the penalties inside ``int64``."""

# MAX_CLEARANCE_WEIGHT lives in selfrepair.limits (the experiment schema and the CLI use it too).


def _validate(
    problem: PlanningProblem,
    heuristic: str,
    max_expansions: int | None,
    time_limit: float | None,
    backend: str,
) -> None:
    check_search_inputs(
        problem.maze,
        (("start", problem.start.cell), ("goal", problem.goal)),
        backend=backend,
        max_expansions=max_expansions,
        time_limit=time_limit,
    )
    if heuristic not in HEURISTICS:
        raise ProblemError(
            f"unknown heuristic {heuristic!r}; expected one of {', '.join(HEURISTICS)}"
        )
    if not 0 <= problem.clearance_weight <= MAX_CLEARANCE_WEIGHT:
        raise ProblemError(
            f"clearance_weight must be from 0 to {MAX_CLEARANCE_WEIGHT:,}, "
            f"got {_short_number(problem.clearance_weight)}"
        )
    if not 0 <= problem.clearance_radius <= MAX_CLEARANCE_RADIUS:
        raise ProblemError(
            f"clearance_radius must be from 0 to {MAX_CLEARANCE_RADIUS}, "
            f"got {problem.clearance_radius}"
        )


def _short_number(value: Fraction | int | float) -> str:
    """``value`` as text, or its order of magnitude when that text would be long."""
    text = str(value)
    if len(text) <= 24:
        return text
    digits = len(str(abs(int(value))))
    return f"{'-' if value < 0 else ''}a number of {digits} digits"


def _since(t0: int) -> int:
    return time.perf_counter_ns() - t0
