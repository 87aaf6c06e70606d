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
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from itertools import islice, repeat
from operator import itemgetter
from typing import Any, overload

from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection
from selfrepair.execution.result import (
    MissionResult,
    MissionSpec,
    MissionStatus,
    RepairRecord,
    StepSource,
    TraceStep,
)
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.replacement import table_reach
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

    def plan_to(
        start: Pose, goal: Cell, heading: Heading | None, known: frozenset[Any], budget: int | None
    ) -> PlanResult:
        problem = PlanningProblem(
            spec.maze, start, goal, heading, known, weight, settings.clearance_radius, spec.domain
        )
        return plan(
            problem, heuristic=settings.heuristic, max_expansions=budget, backend=settings.backend
        )

    def cost(pose: Pose, action: Any) -> Fraction:
        return action_cost(
            spec.maze,
            pose,
            action,
            clearance_weight=weight,
            clearance_radius=settings.clearance_radius,
            domain=spec.domain,
        )

    margin = max(2, table_reach(table)) if table is not None else 2
    grid = spec.maze.free_grid(margin)
    return MissionContext(
        domain=spec.domain,
        goal=spec.goal,
        goal_heading=spec.goal_heading,
        options=spec.options,
        table=table,
        plan=plan_to,
        replan_budget=settings.max_expansions,
        free=grid.all_free,
        grid=grid,
        cost=cost,
        world=spec.maze,
        cost_scale=cost_scale(spec.domain, weight),
        start=spec.start,
    )


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

    def sense(self) -> None:
        if self.spec.schedule.detection is Detection.NOW:
            self.known = self.sim.sense()

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

    def execute(self, action: Any, source: StepSource) -> MissionStatus | None:
        """Run one command; returns a terminal status or ``None`` to go on."""
        outcome = self.sim.execute(action)
        if outcome.status is Outcome.COLLISION:
            return MissionStatus.COLLISION
        known = self.known  # what was known when the command was given
        if outcome.status is Outcome.FAILED_ATTEMPT:
            self.known = known | outcome.blocking
            source = StepSource.FAILED_ATTEMPT
        else:
            self.queue.popleft()
        self.steps.append(
            TraceStep(
                outcome.step, action, outcome.start, outcome.end, outcome.duration, source, known
            )
        )
        return None


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
    if use_numba(spec.backend):
        from selfrepair.search.warmup import ensure_warm

        ensure_warm()


def _loop(run: _Run) -> tuple[MissionStatus, str]:
    spec = run.spec
    domain = spec.domain
    limit = spec.step_limit()
    horizon = int(getattr(run.repairer, "horizon", 0))
    early_at = -1  # the step of the last early repair: at most one per step, so none can loop
    while True:
        if spec.at_goal(run.sim.pose):
            return MissionStatus.REACHED, "goal reached"
        if run.sim.steps >= limit:
            return MissionStatus.STEP_LIMIT, f"{limit} steps without reaching the goal"
        run.sense()
        if not run.queue or not domain.available(run.queue[0][0], run.known):
            repair = run.repair(run.queue[0][0] if run.queue else None)
            if repair.status is not RepairStatus.REPAIRED:
                return MissionStatus(repair.status), _why(repair, run)
            continue
        if horizon and early_at != run.sim.steps and (ahead := _faulty_ahead(run, horizon)):
            early_at = run.sim.steps
            repair = run.repair(ahead[0])  # a known fault ahead: the repairer wants it early
            if repair.status is not RepairStatus.REPAIRED:
                return MissionStatus(repair.status), _why(repair, run)
            continue
        action, source = run.queue[0]
        terminal = run.execute(action, source)
        if terminal is not None:
            name = domain.format_action(action)
            return terminal, f"{name} at {run.sim.pose} would sweep a wall"


def _faulty_ahead(run: _Run, horizon: int) -> tuple[Any] | None:
    """The first of the ``horizon`` queued actions after the front that is unavailable under the
    known faults, in a 1-tuple (``None`` when all are available)."""
    available, known, queue = run.spec.domain.available, run.known, run.queue
    for i in range(1, min(horizon + 1, len(queue))):
        if not available(queue[i][0], known):
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
    )
