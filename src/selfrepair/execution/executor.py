"""The fault-tolerant executor: plan, execute step by step, repair when the next action is faulty.

:func:`run_mission` takes a :class:`MissionSpec` (everything needed to run the mission again) and
returns a :class:`MissionResult` (status, every executed step, every repair, and the metrics).

The loop, per step:

The strategy is started once per mission (its factory gets a
:class:`~selfrepair.repair.strategies.MissionContext` built here: the planner, the free-cell test
and the step cost on this mission's map) and then asked for each repair.

1. Update the known faults: with detection ``now`` the simulator's sensors report the active
   faults; with ``on-use`` the known faults are those revealed by failed attempts so far.
2. If the next queued action is unavailable under the known faults, ask the strategy for a repair
   (timed with ``time.perf_counter_ns``: the repair latency runs from meeting the faulty action to
   having the next executable action) and splice it into the queue. A strategy with a
   ``horizon`` (lookahead with a window before the faulty action) is asked as soon as one of the
   next ``horizon`` actions after the first is known to be faulty.
3. Send the next action to the simulator. A failed attempt (a fault the executor did not know
   yet) is recorded as a step with source ``failed-attempt`` and reveals its blocking faults.

The initial plan is made, by default, before any fault is known (``initial_faults_known=False``),
as in the original experiment. The executor holds only detected faults; the true ones live in the
:class:`~selfrepair.execution.simulator.Simulator`.

Why ``replacement`` never replans more than ``replan`` when every fault is permanent, present from
step 0 and detected at once: both start from the same (deterministic) initial plan and follow it
through the same poses until its first action that a fault forbids. ``replan`` replans
there (1 replan) or never meets one (0). ``replacement`` meets that same action first; every action
it inserts is healthy, and after a replan the plan is made with all faults known, so nothing needs
repair afterwards. Hence it makes at most one replan, and only when the initial plan contains a
faulty action, i.e. only when ``replan`` makes one too.
"""

from __future__ import annotations

import time
from array import array
from collections import Counter, deque
from collections.abc import Container, Iterator, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from itertools import islice, repeat
from operator import itemgetter
from typing import Any, overload

import numpy as np

from selfrepair.caching import BoundedCache
from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection
from selfrepair.execution.moves import available_moves
from selfrepair.execution.result import (
    MissionResult,
    MissionSpec,
    MissionStatus,
    MissionTally,
    RepairRecord,
    StepSource,
    TraceStep,
)
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.replacement import FreeTest, table_reach
from selfrepair.repair.strategies import (
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    RepairStatus,
    get_strategy,
    replan,
    uses_table,
)
from selfrepair.search.astar import PlanResult, PlanStatus
from selfrepair.search.backend import use_numba
from selfrepair.search.lattice import action_cost, cost_scale, plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.tables.model import ReplacementTable
from selfrepair.world.maze import Maze, clearance_penalties

__all__ = ["mission_context", "run_mission"]


class _ActionView(Sequence[Any]):
    """A read-only view of the queue's actions, so a repair request costs O(1) to build."""

    __slots__ = ("_queue",)

    def __init__(self, queue: deque[tuple[Any, StepSource]]) -> None:
        self._queue = queue

    def __len__(self) -> int:
        return len(self._queue)

    def __iter__(self) -> Iterator[Any]:
        return map(_ACTION, self._queue)

    @overload
    def __getitem__(self, index: int) -> Any: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[Any, ...]: ...

    def __getitem__(self, index: int | slice) -> Any:
        if isinstance(index, slice):
            start, stop, stride = index.indices(len(self._queue))
            if stride == 1:  # in C: a deque is slow to index in the middle
                return tuple(islice(map(_ACTION, self._queue), start, max(start, stop)))
            return tuple(self._queue[i][0] for i in range(start, stop, stride))
        return self._queue[index][0]


_ACTION = itemgetter(0)

_STEP_SOURCES = {str(s): StepSource(s) for s in StepSource}
"""Step sources by value: a dictionary look-up, where calling the enum costs a microsecond inside
the timed repair."""


def _splice(
    queue: deque[tuple[Any, StepSource]], consumed: int, actions: Sequence[Any], source: StepSource
) -> None:
    """Replace the first ``consumed`` queued actions by ``actions`` marked ``source``, in place.
    A short repair pops and pushes at the front; one that covers much of the queue (a whole-plan
    rewrite) rebuilds it in C, which is cheaper than popping item by item."""
    if 3 * consumed > len(queue):
        rest = list(islice(queue, consumed, None))
        queue.clear()
        queue.extend(zip(actions, repeat(source)))
        queue.extend(rest)
        return
    for _ in range(consumed):
        queue.popleft()
    queue.extendleft(zip(reversed(actions), repeat(source)))


def mission_context(spec: MissionSpec, table: ReplacementTable | None) -> MissionContext:
    """The :class:`~selfrepair.repair.strategies.MissionContext` of ``spec``: its planner, free
    test and step cost on its map, with ``table`` (``None`` for strategies without one)."""
    settings = spec.planner
    weight = Fraction(settings.clearance_weight)
    maze, domain, radius = spec.maze, spec.domain, settings.clearance_radius
    heuristic, backend = settings.heuristic, settings.backend

    def plan_to(
        start: Pose, goal: Cell, heading: Heading | None, known: frozenset[Any], budget: int | None
    ) -> PlanResult:
        problem = PlanningProblem(maze, start, goal, heading, known, weight, radius, domain)
        return plan(problem, heuristic=heuristic, max_expansions=budget, backend=backend)

    def cost(pose: Pose, action: Any) -> Fraction:
        return action_cost(
            maze, pose, action, clearance_weight=weight, clearance_radius=radius, domain=domain
        )

    margin = max(2, table_reach(table)) if table is not None else 2
    grid = maze.free_grid(margin)
    return MissionContext(
        domain=domain,
        goal=spec.goal,
        goal_heading=spec.goal_heading,
        options=spec.options,
        table=table,
        plan=plan_to,
        replan_budget=settings.max_expansions,
        free=free_test(grid),
        grid=grid,
        cost=cost,
        world=spec.maze,
        cost_scale=cost_scale(spec.domain, weight),
        start=spec.start,
    )


def free_test(grid: FreeGrid) -> FreeTest:
    """``grid.all_free`` as one closure over the buffer (no method call per cell)."""
    data, stride, margin = grid.data, grid.stride, grid.margin
    width, height = grid.width, grid.height

    def all_free(cells: tuple[Cell, ...]) -> bool:
        for x, y in cells:
            if not (
                0 <= x < width and 0 <= y < height and data[(y + margin) * stride + x + margin]
            ):
                return False
        return True

    return all_free


@dataclass(slots=True)
class _Run:
    """Mutable state of one mission run."""

    spec: MissionSpec
    sim: Simulator
    context: MissionContext
    repairer: Repairer
    queue: deque[tuple[Any, StepSource]]
    known: frozenset[Any] = frozenset()
    steps: list[TraceStep] = field(default_factory=list)
    repairs: list[RepairRecord] = field(default_factory=list)
    moved: list[int] = field(default_factory=list)
    """Per executed step, its (start state, action) as one integer (for the plan distance)."""
    executed_units: int = 0
    penalty: int = 0

    def repair(self, action: Any | None) -> Repair:
        """Ask the strategy (or, with an empty queue off the goal, a plain replan) for a repair
        and splice it into the queue; the latency covers both."""
        t0 = time.perf_counter_ns()
        request = RepairRequest(self.sim.pose, _ActionView(self.queue), self.known, self.sim.steps)
        fallback = action is None  # the queue ran out away from the goal: plain replan
        repair = replan(self.context, request) if fallback else self.repairer.repair(request)
        if repair.status is RepairStatus.REPAIRED:
            source = _STEP_SOURCES.get(repair.source) or StepSource(repair.source)
            _splice(self.queue, repair.consumed, repair.actions, source)
        latency = time.perf_counter_ns() - t0
        self.repairs.append(RepairRecord(self.sim.steps, self.sim.pose, action, repair, latency))
        return repair


_new_tuple = tuple.__new__
"""Builds the :class:`TraceStep` of each step without the ``NamedTuple`` constructor's Python
frame (the same value)."""


def run_mission(spec: MissionSpec) -> MissionResult:
    """Plan, execute and repair one mission (see the module docstring)."""
    factory = get_strategy(spec.strategy)  # fails fast on a bad name
    sim = Simulator(spec.domain, spec.maze, spec.start, spec.schedule, spec.seed)
    initial_known = sim.sense() if spec.initial_faults_known else frozenset()
    table = spec.options.resolved_table() if uses_table(spec.strategy) else None
    _prepare(spec, table)
    context = mission_context(spec, table)
    t0 = time.perf_counter_ns()
    initial = context.plan(
        spec.start, spec.goal, spec.goal_heading, initial_known, context.replan_budget
    )
    planning_ns = time.perf_counter_ns() - t0
    queue = deque((a, StepSource.PLAN) for a in initial.actions)
    run = _Run(spec, sim, context, factory(context), queue, initial_known)
    if initial.status is not PlanStatus.SOLVED:
        reason = f"initial plan: {initial.status.value}"
        return _result(run, initial, planning_ns, MissionStatus.NO_INITIAL_PLAN, reason)
    status, reason = _loop(run)
    return _result(run, initial, planning_ns, status, reason)


def _prepare(spec: MissionSpec, table: ReplacementTable | None) -> None:
    """Check the table's robot and load the compiled planner before anything is timed (the
    table's geometry and the maze's free grid are made by :func:`mission_context`, also before),
    so the first planning time and the first repair latency of a process are not inflated by
    one-off costs."""
    if table is not None and table.domain is not spec.domain:
        raise ProblemError(
            f"table {spec.options.table_label!r} is for the {table.domain.name!r} domain; "
            f"this mission's robot is {spec.domain.name!r}"
        )
    if use_numba(spec.backend, spec.domain):
        from selfrepair.search.warmup import ensure_warm

        ensure_warm()


def _loop(run: _Run) -> tuple[MissionStatus, str]:
    """Execute until the goal, a failed repair, the step limit or a collision.

    The hot path of every experiment: it keeps what it reads on each step in locals, tests
    availability against the moves available under the known faults (one look-up per step) and
    records each step as a light :class:`TraceStep`.
    """
    spec, sim, queue, steps = run.spec, run.sim, run.queue, run.steps
    limit = spec.step_limit()
    goal, goal_heading = spec.goal, spec.goal_heading
    sense_now = spec.schedule.detection is Detection.NOW
    table = sim.table
    weight = bool(Fraction(spec.clearance_weight))
    margin, stride = sim.grid.margin, sim.grid.stride
    penalty = penalty_buffer(sim.grid, spec.maze, spec.clearance_radius) if weight else b""
    moved = run.moved
    n_actions = len(spec.domain.actions)
    known = run.known
    available = available_moves(table, known)
    horizon = int(getattr(run.repairer, "horizon", 0))
    early_at = -1  # the step of the last early repair: at most one per step, so none can loop
    while True:
        pose = sim.pose
        if pose.cell == goal and (goal_heading is None or pose.heading == goal_heading):
            return MissionStatus.REACHED, "goal reached"
        if sim.steps >= limit:
            return MissionStatus.STEP_LIMIT, f"{limit} steps without reaching the goal"
        if sense_now:
            sensed = sim.sense()
            if sensed is not known:
                run.known = known = sensed
                available = available_moves(table, known)
        if not queue or queue[0][0] not in available:
            repair = run.repair(queue[0][0] if queue else None)
            if repair.status is not RepairStatus.REPAIRED:
                return MissionStatus(repair.status), _why(repair, run)
            continue
        if (
            horizon
            and early_at != sim.steps
            and (ahead := _faulty_ahead(queue, available, horizon))
        ):
            early_at = sim.steps
            repair = run.repair(ahead[0])  # a known fault ahead: the repairer wants it early
            if repair.status is not RepairStatus.REPAIRED:
                return MissionStatus(repair.status), _why(repair, run)
            continue
        action, source = queue[0]
        step = sim.steps
        outcome = sim.advance(action)
        if outcome is Outcome.MOVED:
            queue.popleft()
            move = sim.last_move
            assert move is not None
            run.executed_units += move.units
            moved.append(
                (((pose.y << 32) + 4 * pose.x + pose.heading) * n_actions) + move.action_index
            )
            if weight:
                base = (pose.y + margin) * stride + pose.x + margin
                run.penalty += sum([penalty[base + offset] for offset in move.cells])
        elif outcome is Outcome.FAILED_ATTEMPT:
            run.known = known | sim.last_blocking
            source = StepSource.FAILED_ATTEMPT
        else:
            name = spec.domain.format_action(action)
            return MissionStatus.COLLISION, f"{name} at {sim.pose} would sweep a wall"
        steps.append(
            _new_tuple(TraceStep, (step, action, pose, sim.pose, sim.last_duration, source, known))
        )
        if run.known is not known:
            known = run.known
            available = available_moves(table, known)


def penalty_buffer(grid: FreeGrid, maze: Maze, radius: int) -> Sequence[int]:
    """The clearance penalties ``max(0, radius - clearance)`` of ``maze`` in the layout of
    ``grid`` (its free-cell buffer; 0 in the margin), as compact bytes or an ``array`` (kept per
    maze, radius and margin)."""
    return _PENALTIES.get((maze, radius, grid.margin), lambda: _penalty_buffer(grid, maze, radius))


def _penalty_buffer(grid: FreeGrid, maze: Maze, radius: int) -> Sequence[int]:
    m = grid.margin
    padded = np.zeros((grid.height + 2 * m, grid.width + 2 * m), dtype=np.int64)
    padded[m : m + grid.height, m : m + grid.width] = clearance_penalties(maze, radius)
    if int(padded.max(initial=0)) < 256:
        return padded.astype(np.uint8).tobytes()
    return array("q", padded.tobytes())


_PENALTIES: BoundedCache[tuple[Maze, int, int], Sequence[int]] = BoundedCache(
    "clearance penalties in free-grid layout", 8
)


def _faulty_ahead(
    queue: deque[tuple[Any, StepSource]], available: Container[Any], horizon: int
) -> tuple[Any] | None:
    """The first of the ``horizon`` queued actions after the front that is unavailable under the
    known faults (not in ``available``, the moves available under them), in a 1-tuple (``None``
    when all are available)."""
    for i in range(1, min(horizon + 1, len(queue))):
        if queue[i][0] not in available:
            return (queue[i][0],)
    return None


def _why(repair: Repair, run: _Run) -> str:
    tried = " then ".join(repair.attempts)
    what = "no plan exists" if repair.status is RepairStatus.STUCK else "the planner budget ran out"
    known = run.spec.domain.format_faults(run.known) or "none"
    return f"at {run.sim.pose} with known faults {known}: tried {tried}; {what}"


def _result(
    run: _Run, initial: PlanResult, planning_ns: int, status: MissionStatus, reason: str
) -> MissionResult:
    removed, added, motion_removed, motion_added = _plan_distances(run, initial)
    tally = MissionTally(
        len(run.moved),
        run.executed_units,
        run.sim.unit,
        run.penalty,
        removed,
        added,
        motion_removed,
        motion_added,
    )
    return MissionResult(
        run.spec,
        status,
        reason,
        tuple(run.steps),
        tuple(run.repairs),
        initial,
        planning_ns,
        run.sim.pose,
        run.sim.ticks,
        tally,
    )


def _plan_distances(run: _Run, initial: PlanResult) -> tuple[int, int, int, int]:
    """Removed and added actions between the initial plan and the executed steps, as multisets
    of (start state, action) encoded as integers (the same keys the loop recorded), then the same
    by motion class (each action index replaced by that of the first action of its motion)."""
    moves = run.sim.table.moves
    domain = run.spec.domain
    n_actions = len(domain.actions)
    planned = [
        (((p.y << 32) + 4 * p.x + p.heading) * n_actions) + moves[a][0].action_index
        for p, a in zip(initial.poses, initial.actions, strict=False)
    ]
    executed = run.moved
    removed, added = _multiset_distance(planned, executed)
    first_of: dict[str, int] = {}
    motion = [first_of.setdefault(domain.motion_class(a), i) for i, a in enumerate(domain.actions)]
    if all(m == i for i, m in enumerate(motion)):  # every action its own motion class
        return removed, added, removed, added
    planned = [k - k % n_actions + motion[k % n_actions] for k in planned]
    by_motion = [k - k % n_actions + motion[k % n_actions] for k in executed]
    return (removed, added, *_multiset_distance(planned, by_motion))


def _multiset_distance(planned: list[int], executed: list[int]) -> tuple[int, int]:
    """Elements of ``planned`` not in ``executed`` and of ``executed`` not in ``planned``, as
    multisets."""
    first, second = set(planned), set(executed)
    if len(first) == len(planned) and len(second) == len(executed):
        common = len(first & second)
    else:
        a, b = Counter(planned), Counter(executed)
        common = sum(min(n, b[k]) for k, n in a.items())
    return len(planned) - common, len(executed) - common
