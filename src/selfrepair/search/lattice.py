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

Heuristics
    See :mod:`selfrepair.search.heuristics` (all admissible and consistent). Internally costs are
    scaled to integers (``S = domain.time_unit * weight denominator``) and ``h`` is rounded down,
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
from collections.abc import Sequence
from dataclasses import dataclass, replace
from fractions import Fraction

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.limits import MAX_CLEARANCE_WEIGHT
from selfrepair.robots.domain import SomeDomain, primitive_by_motion
from selfrepair.search.astar import PlanResult, PlanStatus, astar, deadline_from
from selfrepair.search.backend import BACKENDS, numba_available, use_numba
from selfrepair.search.cost import action_cost, plan_cost
from selfrepair.search.heuristics import (
    HEURISTICS,
    NEEDS_CONNECTED_FOOTPRINTS,
    bfs_distances,
    heuristic_bound,
    progress_rate,
)
from selfrepair.search.openmoves import open_moves
from selfrepair.search.problem import (
    CellBound,
    PlanningProblem,
    StepTerm,
    check_search_inputs,
)
from selfrepair.world.maze import Maze, clearance_penalties

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


def planning_actions(domain: SomeDomain, faults: frozenset[object]) -> tuple[object, ...]:
    """The actions the planner expands under ``faults``: the fastest available one of each motion
    class (:func:`~selfrepair.robots.domain.primitive_by_motion` order), without actions that
    leave the pose unchanged (computed once per domain and fault set)."""
    return _setup(domain, faults).actions


@dataclass(frozen=True, slots=True, eq=False)
class _Setup:
    """What the planner derives from (domain, faults) once: the planning actions and their
    :func:`progress_rate`."""

    actions: tuple[object, ...]
    rate: Fraction


def _setup(domain: SomeDomain, faults: frozenset[object]) -> _Setup:
    return _SETUPS.get((domain, faults), lambda: _make_setup(domain, faults))


def _make_setup(domain: SomeDomain, faults: frozenset[object]) -> _Setup:
    moves = open_moves(domain)
    actions = tuple(
        a for a in primitive_by_motion(domain, faults).values() if not moves.stays(moves.index(a))
    )
    return _Setup(actions, progress_rate(domain, actions))


_SETUPS: BoundedCache[tuple[SomeDomain, frozenset[object]], _Setup] = BoundedCache(
    "planner actions per fault set", 1024, kind=CacheKind.PLAN
)


def cost_scale(domain: SomeDomain, weight: Fraction) -> int:
    """The factor that makes every edge cost an integer: the domain's time unit
    (:attr:`~selfrepair.robots.domain.Domain.time_unit`) times the clearance weight's
    denominator."""
    return domain.time_unit * weight.denominator


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
    bound, largest = heuristic_bound(
        problem, heuristic, setup.actions, setup.rate, "numba" if fast else "python"
    )
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


def _load(backend: str, domain: SomeDomain | None = None) -> tuple[bool, int]:
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


_Found = tuple[PlanStatus, tuple[object, ...], tuple[Pose, ...], int, int, int]
"""Status, actions, poses, scaled cost, scaled duration, expansions."""


def _plan_python(
    problem: PlanningProblem,
    actions: Sequence[object],
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
    counts = term.dense_counts() if term is not None else None
    hard = term is not None and term.hard
    per_count = 0 if term is None or term.penalty is None else int(term.penalty * scale)

    def heuristic(pose: Pose) -> int | None:
        d = distance[pose.y][pose.x]
        return None if d < 0 else d * rate.numerator // rate.denominator

    def successors(pose: Pose) -> list[tuple[Pose, int, object]]:
        out = []
        here = counts[pose.y, pose.x, pose.heading].tolist() if counts is not None else None
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


def _check_term(problem: PlanningProblem, term: StepTerm, actions: tuple[object, ...]) -> None:
    """Refuse a step term made for other planning actions or another maze size."""
    if term.actions != actions:
        raise ProblemError(
            f"the step term {term.label!r} was made for other planning actions than those under "
            f"the faults known ({problem.domain.format_faults(problem.faults) or 'none'})"
        )
    height, width = problem.maze.walls.shape
    if term.size != (height, width):
        raise ProblemError(
            f"the step term {term.label!r} is for a {term.size[1]}x{term.size[0]} maze, "
            f"not {width}x{height}"
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
