"""Exact A* on a robot's pose lattice ``(x, y, heading)``, for any :class:`Domain`.

Search space and pruning
    A node is a :class:`~selfrepair.geometry.Pose`. Only actions available under the faults the
    planner knows about are used, and of each motion class only the fastest
    (:func:`selfrepair.robots.domain.primitive_by_motion`): every other one has the same effect
    and is no shorter, so it can never improve a plan. Actions that change nothing (the four-wheel
    robot's WAIT) are never useful and are left out. For the four-wheel robot the branching
    factor is therefore at most eight. A plan reports the concrete action chosen for each step.

Cost (exact formula)
    For an action started at ``pose``, with footprint cells ``C`` (start cell included)::

        cost = duration + clearance_weight * sum(max(0, clearance_radius - clearance(c)) for c in C)

    where ``clearance(c)`` is :func:`selfrepair.world.maze.clearance_map` (Chebyshev distance to the
    nearest wall, outside counts as wall). The penalty only bites in cells closer than
    ``clearance_radius`` to a wall, and grows by one per cell of missing clearance. A problem
    with a :class:`~selfrepair.search.problem.StepTerm` (the tolerant planner,
    :mod:`selfrepair.repair.tolerance_masks`) adds ``penalty * count`` per step (soft mode) or
    never takes a step whose count is above 0 (hard mode); counts are non-negative, so every
    heuristic below stays admissible and consistent. With
    ``clearance_weight == 0`` the cost of a plan is its total duration, so the plan found has the
    minimum total duration.

Heuristics (:data:`HEURISTICS`), all admissible and consistent
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

Determinism
    Heap keys ``(f, h, counter)`` and a fixed successor order (that of ``primitive_by_motion``), in
    the pure-Python backend (the reference, on :func:`selfrepair.search.astar.astar` with
    ``Domain.step``) and in the numba backend, which therefore return the same plan. The kernel
    takes any domain whose actions stay within the 3x3 cells around the robot; for others the
    exact Python search runs.
"""

from __future__ import annotations

import sys
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.limits import MAX_CLEARANCE_WEIGHT
from selfrepair.robots.domain import Domain, primitive_by_motion
from selfrepair.robots.domain import progress_rate as domain_progress_rate
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanResult, PlanStatus, astar, deadline_from
from selfrepair.search.backend import BACKENDS, numba_available, use_numba
from selfrepair.search.problem import (
    CellBound,
    PlanningProblem,
    StepTerm,
    check_search_inputs,
    with_border,
)
from selfrepair.world.maze import Maze, clearance_map, clearance_penalties

__all__ = [
    "BACKENDS",
    "HEURISTICS",
    "MAX_CLEARANCE_RADIUS",
    "CellBound",
    "PlanResult",
    "PlanStatus",
    "PlanningProblem",
    "action_cost",
    "bfs_distances",
    "cost_scale",
    "numba_available",
    "plan",
    "plan_cost",
    "planning_actions",
    "progress_rate",
]


class HeuristicFn(Protocol):
    """A heuristic builder: ``(maze, goal, domain, actions, *, backend) -> CellBound``."""

    def __call__(
        self,
        maze: Maze,
        goal: Cell,
        domain: Domain[Any, Any],
        actions: Sequence[Any],
        *,
        backend: str = "auto",
    ) -> CellBound: ...


def planning_actions(domain: Domain[Any, Any], faults: frozenset[Any]) -> tuple[Any, ...]:
    """The actions the planner expands under ``faults``: the fastest available one of each motion
    class (:func:`~selfrepair.robots.domain.primitive_by_motion` order), without actions that
    leave the pose unchanged (computed once per domain and fault set)."""
    return _setup(domain, faults).actions


@dataclass(frozen=True, slots=True, eq=False)
class _Setup:
    """What the planner derives from (domain, faults) once: the planning actions and their
    :func:`progress_rate`."""

    actions: tuple[Any, ...]
    rate: Fraction


def _setup(domain: Domain[Any, Any], faults: frozenset[Any]) -> _Setup:
    return _SETUPS.get((domain, faults), lambda: _make_setup(domain, faults))


def _make_setup(domain: Domain[Any, Any], faults: frozenset[Any]) -> _Setup:
    actions = tuple(
        a for a in primitive_by_motion(domain, faults).values() if not _no_op(domain, a)
    )
    return _Setup(actions, progress_rate(domain, actions))


_SETUPS: BoundedCache[tuple[Domain[Any, Any], frozenset[Any]], _Setup] = BoundedCache(
    "planner actions per fault set", 1024, kind=CacheKind.PLAN
)


def _no_op(domain: Domain[Any, Any], action: Any) -> bool:
    return all(domain.apply(Pose(0, 0, h), action) == Pose(0, 0, h) for h in Heading)


def progress_rate(domain: Domain[Any, Any], actions: Sequence[Any]) -> Fraction:
    """Least ticks per cell of Manhattan displacement over ``actions`` from any heading (0 if none
    moves)."""
    return _RATES.get((domain, tuple(actions)), lambda: _progress_rate(domain, actions))


_RATES: BoundedCache[tuple[Domain[Any, Any], tuple[Any, ...]], Fraction] = BoundedCache(
    "planner progress rates", 1024, kind=CacheKind.PLAN
)


def _progress_rate(domain: Domain[Any, Any], actions: Sequence[Any]) -> Fraction:
    return domain_progress_rate(domain, actions)


def cost_scale(domain: Domain[Any, Any], weight: Fraction) -> int:
    """The factor that makes every edge cost an integer: the domain's time unit
    (:attr:`~selfrepair.robots.domain.Domain.time_unit`) times the clearance weight's
    denominator."""
    return domain.time_unit * weight.denominator


def _zero_distances(maze: Maze, goal: Cell, backend: str) -> npt.NDArray[np.int32]:
    return with_border(np.zeros(maze.walls.shape, dtype=np.int64))


def _manhattan_distances(maze: Maze, goal: Cell, backend: str) -> npt.NDArray[np.int32]:
    ys, xs = np.indices(maze.walls.shape, dtype=np.int64)
    return with_border(np.abs(xs - goal[0]) + np.abs(ys - goal[1]))


_DistanceFn = Callable[[Maze, Cell, str], npt.NDArray[np.int32]]


def _zero_bound(
    maze: Maze,
    goal: Cell,
    domain: Domain[Any, Any],
    actions: Sequence[Any],
    *,
    backend: str = "auto",
) -> CellBound:
    return CellBound(_goal_distances(_zero_distances, maze, (0, 0), backend)[0], Fraction(0))


def _manhattan_bound(
    maze: Maze,
    goal: Cell,
    domain: Domain[Any, Any],
    actions: Sequence[Any],
    *,
    backend: str = "auto",
) -> CellBound:
    distance, _ = _goal_distances(_manhattan_distances, maze, goal, backend)
    return CellBound(distance, progress_rate(domain, actions))


def _grid_distance_bound(
    maze: Maze,
    goal: Cell,
    domain: Domain[Any, Any],
    actions: Sequence[Any],
    *,
    backend: str = "auto",
) -> CellBound:
    distance, _ = _goal_distances(_bfs_padded, maze, goal, backend)
    return CellBound(distance, progress_rate(domain, actions))


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
    "goal distances (mazes up to 512x512)", 32, kind=CacheKind.PLAN
)
_LARGE_DISTANCES: BoundedCache[tuple[_DistanceFn, Maze, Cell], _Distances] = BoundedCache(
    "goal distances (larger mazes)", 4, kind=CacheKind.PLAN
)


HEURISTICS: dict[str, HeuristicFn] = {
    "zero": _zero_bound,
    "manhattan": _manhattan_bound,
    "grid-distance": _grid_distance_bound,
}
"""Heuristic registry: name -> function ``(maze, goal, domain, actions, *, backend) ->
CellBound``."""


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


_BUILT_IN: dict[HeuristicFn, tuple[_DistanceFn, bool]] = {
    _zero_bound: (_zero_distances, False),
    _manhattan_bound: (_manhattan_distances, True),
    _grid_distance_bound: (_bfs_padded, True),
}
"""The built-in heuristics as (cached distances, whether scaled by the progress rate): what
:func:`plan` builds their bound from without calling them (the same bound, with the rate taken
from the per-fault-set setup)."""


def _bound(
    problem: PlanningProblem, heuristic: str, setup: _Setup, backend: str
) -> tuple[CellBound, int | None]:
    """The heuristic bound of ``problem`` (see :data:`_BUILT_IN`) and its largest distance when
    known without a scan."""
    fn = HEURISTICS[heuristic]
    built_in = _BUILT_IN.get(fn)
    if built_in is None:
        bound = fn(problem.maze, problem.goal, problem.domain, setup.actions, backend=backend)
        return bound, None
    make, scaled = built_in
    goal = problem.goal if make is not _zero_distances else (0, 0)
    distance, largest = _goal_distances(make, problem.maze, goal, backend)
    return CellBound(distance, setup.rate if scaled else Fraction(0)), largest


def action_cost(
    maze: Maze,
    pose: Pose,
    action: Any,
    *,
    clearance_weight: Fraction,
    clearance_radius: int,
    domain: Domain[Any, Any] = FOUR_WHEEL,
) -> Fraction:
    """The exact cost of ``action`` at ``pose`` (see the module docstring for the formula), for
    the four-wheel robot unless ``domain`` is given.

    Does not check that the footprint cells are free; :func:`plan_cost` does.
    """
    cost = Fraction(domain.duration(action))
    if clearance_weight:
        clearance = clearance_map(maze)
        penalty = sum(
            max(0, clearance_radius - int(clearance[y, x]))
            if maze.in_bounds(x, y)
            else clearance_radius
            for x, y in domain.footprint(pose, action)
        )
        cost += clearance_weight * penalty
    return cost


def plan_cost(problem: PlanningProblem, actions: Sequence[Any]) -> Fraction:
    """Re-simulate ``actions`` from ``problem.start`` and return their total cost.

    Raises :class:`ProblemError` if an action is unavailable under ``problem.faults``, sweeps a wall
    or leaves the grid, or if the plan does not end at the goal.
    """
    domain = problem.domain
    pose = problem.start
    total = Fraction(0)
    for index, action in enumerate(actions):
        name = domain.format_action(action)
        if not domain.available(action, problem.faults):
            raise ProblemError(f"action {index} ({name}) is not available under the faults")
        end, swept, _ = domain.step(pose, action)
        if not problem.maze.all_free(swept):
            raise ProblemError(
                f"action {index} ({name}) at {pose} sweeps a wall or leaves the grid"
            )
        total += action_cost(
            problem.maze,
            pose,
            action,
            clearance_weight=Fraction(problem.clearance_weight),
            clearance_radius=problem.clearance_radius,
            domain=domain,
        )
        total += _term_cost(problem.step_term, pose, action, index, name)
        pose = end
    if not problem.at_goal(pose):
        raise ProblemError(f"the plan ends at {pose}, not at the goal")
    return total


def _term_cost(term: StepTerm | None, pose: Pose, action: Any, index: int, name: str) -> Fraction:
    """The step term's cost of ``action`` at ``pose`` (0 without a term); a step a hard term
    forbids, or an action it has no count for, raises :class:`ProblemError`."""
    if term is None:
        return Fraction(0)
    if action not in term.actions:
        raise ProblemError(f"action {index} ({name}) is not one the step term was made for")
    count = int(term.counts[pose.y, pose.x, pose.heading, term.actions.index(action)])
    if term.penalty is None:
        if count:
            raise ProblemError(f"action {index} ({name}) at {pose} is forbidden by the hard term")
        return Fraction(0)
    return term.penalty * count


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
    the grid or in a wall, an unknown heuristic or backend, a heuristic that is not admissible for
    the domain, a negative budget, a weight outside ``[0, MAX_CLEARANCE_WEIGHT]``
    (:mod:`selfrepair.limits`) or a radius outside ``[0, MAX_CLEARANCE_RADIUS]``.

    The first call of a process with the compiled backend imports numba and loads the kernels;
    that time is reported as ``kernel_load_ns`` and left out of ``wall_time_ns`` (and of the time
    limit).
    """
    t0 = time.perf_counter_ns()
    _validate(problem, heuristic, max_expansions, time_limit, backend)
    fast, load_ns = _load(backend, problem.domain)
    if not isinstance(problem.clearance_weight, Fraction):
        problem = replace(problem, clearance_weight=Fraction(problem.clearance_weight))
    if problem.at_goal(problem.start):
        return PlanResult(
            PlanStatus.SOLVED, (), (problem.start,), Fraction(0), Fraction(0), 0,
            _since(t0, load_ns), load_ns,
        )  # fmt: skip
    domain = problem.domain
    setup = _setup(domain, problem.faults)
    actions = setup.actions
    bound, largest = _bound(problem, heuristic, setup, "numba" if fast else "python")
    scale = domain.time_unit * problem.clearance_weight.denominator
    term = problem.step_term
    if term is not None:
        _check_term(problem, term, actions)
        if term.penalty is not None:
            scale *= term.penalty.denominator
    deadline = deadline_from(time_limit, t0 + load_ns)
    found: _Found | None = None
    if fast:
        from selfrepair.search import _kernels

        key = (domain, problem.faults)  # what ``actions`` are a function of
        try:
            found = _kernels.plan_lattice(
                problem, actions, bound, scale, max_expansions, deadline, key=key, largest=largest
            )
        except OverflowError:  # beyond int64 or the 3x3 neighbourhood: the Python search works
            found = None
    if found is None:
        found = _plan_python(problem, actions, bound, scale, max_expansions, deadline)
    status, steps, poses, cost_scaled, duration_scaled, expansions = found
    if status is not PlanStatus.SOLVED:
        return PlanResult(
            status, (), (), None, Fraction(0), expansions, _since(t0, load_ns), load_ns
        )
    return PlanResult(
        status,
        steps,
        poses,
        Fraction(cost_scaled, scale),
        Fraction(duration_scaled, scale),
        expansions,
        _since(t0, load_ns),
        load_ns,
    )


def _load(backend: str, domain: Domain[Any, Any] | None = None) -> tuple[bool, int]:
    """Whether ``backend`` means the compiled kernels for ``domain`` (see
    :func:`~selfrepair.search.backend.use_numba`: an explicit ``numba`` for a robot the kernels
    cannot take is refused), and the nanoseconds spent now importing numba and loading them (0
    when this process already had)."""
    t0 = time.perf_counter_ns()
    cold = "selfrepair.search._kernels" not in sys.modules
    fast = use_numba(backend, domain)
    global _KERNELS_LOADED
    if fast and not _KERNELS_LOADED:
        _KERNELS_LOADED = cold = True
        maze = Maze(np.zeros((3, 3), dtype=bool))
        for weight in (Fraction(0), Fraction(1)):
            problem = PlanningProblem(maze, Pose(0, 0, Heading.E), (2, 2), clearance_weight=weight)
            plan(problem, backend="numba")
    return fast, (time.perf_counter_ns() - t0 if cold else 0)


_KERNELS_LOADED = False
"""Whether this process has loaded the lattice kernels (see :func:`_load`)."""


_Found = tuple[PlanStatus, tuple[Any, ...], tuple[Pose, ...], int, int, int]
"""Status, actions, poses, scaled cost, scaled duration, expansions."""


def _plan_python(
    problem: PlanningProblem,
    actions: Sequence[Any],
    bound: CellBound,
    scale: int,
    max_expansions: int | None,
    deadline_ns: int | None,
) -> _Found:
    """The reference search: poses as nodes, ``Domain.step`` for every successor."""
    maze = problem.maze
    domain = problem.domain
    weight = problem.clearance_weight
    penalty = clearance_penalties(maze, problem.clearance_radius).tolist()
    distance = bound.distance.tolist()
    rate = bound.rate * scale
    term = problem.step_term
    counts = term.counts.tolist() if term is not None else None
    hard = term is not None and term.hard
    per_count = 0 if term is None or term.penalty is None else int(term.penalty * scale)

    def heuristic(pose: Pose) -> int | None:
        d = distance[pose.y][pose.x]
        return None if d < 0 else d * rate.numerator // rate.denominator

    def successors(pose: Pose) -> list[tuple[Pose, int, Any]]:
        out = []
        here = counts[pose.y][pose.x][pose.heading] if counts is not None else None
        for k, action in enumerate(actions):
            end, swept, dur = domain.step(pose, action)
            if maze.all_free(swept):
                cost = dur + weight * sum(penalty[y][x] for x, y in swept)
                scaled = (cost * scale).numerator
                if here is not None:
                    if hard and here[k]:
                        continue
                    scaled += per_count * here[k]
                out.append((end, scaled, action))
        return out

    outcome = astar(
        problem.start,
        successors=successors,
        heuristic=heuristic,
        is_goal=problem.at_goal,
        max_expansions=max_expansions,
        deadline_ns=deadline_ns,
    )
    cost = int(outcome.cost) if outcome.cost is not None else 0
    duration = sum(Fraction(domain.duration(a)) for a in outcome.labels) * scale
    assert duration.denominator == 1  # the scale makes every duration an integer
    return outcome.status, outcome.labels, outcome.path, cost, int(duration), outcome.expansions


MAX_CLEARANCE_RADIUS = 1_000_000
"""Far beyond any maze's clearance; keeps the penalties inside ``int64``."""

# MAX_CLEARANCE_WEIGHT lives in selfrepair.limits (the experiment schema and the CLI use it too).


def _check_term(problem: PlanningProblem, term: StepTerm, actions: tuple[Any, ...]) -> None:
    """Refuse a step term made for other planning actions or another maze size."""
    if term.actions != actions:
        raise ProblemError(
            f"the step term {term.label!r} was made for other planning actions than those under "
            f"the faults known ({problem.domain.format_faults(problem.faults) or 'none'})"
        )
    height, width = problem.maze.walls.shape
    if term.counts.shape[:2] != (height, width):
        raise ProblemError(
            f"the step term {term.label!r} is for a {term.counts.shape[1]}x"
            f"{term.counts.shape[0]} maze, not {width}x{height}"
        )


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
    if heuristic in NEEDS_CONNECTED_FOOTPRINTS and not problem.domain.footprint_connected:
        raise ProblemError(
            f"heuristic {heuristic!r} is admissible only for domains whose footprints are "
            f"4-connected, which domain {problem.domain.name!r} does not declare; use manhattan"
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


def _since(t0: int, load_ns: int = 0) -> int:
    return time.perf_counter_ns() - t0 - load_ns
