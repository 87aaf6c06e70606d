"""The fault-tolerant executor: plan, execute step by step, repair when the next action is faulty.

:func:`run_mission` takes a :class:`MissionSpec` (everything needed to run the mission again) and
returns a :class:`MissionResult` (status, every executed step, every repair, and the metrics).

The loop, per step:

1. Update the known faults: with detection ``now`` the simulator's sensors report the active
   faults; with ``on-use`` the known faults are those revealed by failed attempts so far.
2. If the next queued action is unavailable under the known faults, ask the strategy for a repair
   (timed with ``time.perf_counter_ns``: the repair latency runs from meeting the faulty action to
   having the next executable action) and splice it into the queue.
3. Send the next action to the simulator. A failed attempt (a fault the executor did not know
   yet) is recorded as a step with source ``failed-attempt`` and reveals its blocking faults.

The initial plan is made, by default, before any fault is known (``initial_faults_known=False``),
as in the original experiment. The executor holds only detected faults; the true ones live in the
:class:`~selfrepair.execution.simulator.Simulator`.

Why ``replacement`` never replans more than ``replan`` when every fault is permanent, present from
step 0 and detected at once: both start from the same (deterministic) initial plan and follow it
through the same poses until its first action that uses a faulty wheel command. ``replan`` replans
there (1 replan) or never meets one (0). ``replacement`` meets that same action first; every action
it inserts is healthy, and after a replan the plan is made with all faults known, so nothing needs
repair afterwards. Hence it makes at most one replan, and only when the initial plan contains a
faulty action, i.e. only when ``replan`` makes one too.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import overload

from selfrepair.errors import ProblemError
from selfrepair.execution.result import MissionResult, MissionSpec, RepairRecord, TraceStep
from selfrepair.execution.simulator import Simulator
from selfrepair.geometry import Pose
from selfrepair.repair.replacement import free_cell_set, prepare_grid_geometry
from selfrepair.repair.strategies import (
    PlannerSettings,
    Repair,
    RepairRequest,
    get_strategy,
)
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL, Action, FaultSet
from selfrepair.search.astar import PlanStatus
from selfrepair.search.backend import use_numba
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem, PlanResult
from selfrepair.tables.model import ReplacementTable

__all__ = [
    "MissionResult",
    "MissionSpec",
    "RepairRecord",
    "TraceStep",
    "run_mission",
]


class _ActionView(Sequence[Action]):
    """A read-only view of the queue's actions, so a repair request costs O(1) to build."""

    __slots__ = ("_queue",)

    def __init__(self, queue: deque[tuple[Action, str]]) -> None:
        self._queue = queue

    def __len__(self) -> int:
        return len(self._queue)

    @overload
    def __getitem__(self, index: int) -> Action: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[Action, ...]: ...

    def __getitem__(self, index: int | slice) -> Action | tuple[Action, ...]:
        if isinstance(index, slice):
            start, stop, stride = index.indices(len(self._queue))
            return tuple(self._queue[i][0] for i in range(start, stop, stride))
        return self._queue[index][0]


def _at_goal(spec: MissionSpec, pose: Pose) -> bool:
    return pose.cell == spec.goal and (
        spec.goal_heading is None or pose.heading == spec.goal_heading
    )


@dataclass(slots=True)
class _Run:
    """Mutable state of one mission run."""

    spec: MissionSpec
    sim: Simulator
    queue: deque[tuple[Action, str]]
    known: FaultSet = frozenset()
    table: ReplacementTable | None = None
    planner: PlannerSettings = field(default_factory=PlannerSettings)
    steps: list[TraceStep] = field(default_factory=list)
    repairs: list[RepairRecord] = field(default_factory=list)

    def sense(self) -> None:
        if self.spec.schedule.detection == "now":
            self.known = self.sim.sense()

    def repair(self, action: Action) -> Repair:
        spec = self.spec
        t0 = time.perf_counter_ns()
        request = RepairRequest(
            spec.maze,
            self.sim.pose,
            _ActionView(self.queue),
            self.known,
            spec.goal,
            spec.goal_heading,
            spec.options,
            self.planner,
            self.table,
        )
        repair = get_strategy(spec.strategy)(request)
        if repair.status == "repaired":
            for _ in range(repair.consumed):
                self.queue.popleft()
            self.queue.extendleft((a, repair.source) for a in reversed(repair.actions))
        latency = time.perf_counter_ns() - t0
        self.repairs.append(RepairRecord(self.sim.steps, self.sim.pose, action, repair, latency))
        return repair

    def execute(self, action: Action, source: str) -> str | None:
        """Run one command; returns a terminal status or ``None`` to go on."""
        outcome = self.sim.execute(action)
        if outcome.status == "collision":
            return "collision"
        known = self.known  # what was known when the command was given
        if outcome.status == "failed-attempt":
            self.known = known | outcome.blocking
            source = "failed-attempt"
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
    get_strategy(spec.strategy)  # fail fast on a bad name
    sim = Simulator(spec.maze, spec.start, spec.schedule, spec.seed)
    initial_known = sim.sense() if spec.initial_faults_known else frozenset()
    settings = spec.planner
    problem = PlanningProblem(
        spec.maze,
        spec.start,
        spec.goal,
        spec.goal_heading,
        initial_known,
        settings.clearance_weight,
        settings.clearance_radius,
    )
    table = spec.options.resolved_table() if spec.strategy != "replan" else None
    _prepare(spec, table)
    t0 = time.perf_counter_ns()
    initial = plan(
        problem,
        heuristic=spec.heuristic,
        max_expansions=spec.replan_max_expansions,
        backend=spec.backend,
    )
    planning_ns = time.perf_counter_ns() - t0
    run = _Run(
        spec, sim, deque((a, "plan") for a in initial.actions), initial_known, table, settings
    )
    if initial.status is not PlanStatus.SOLVED:
        return _result(
            run, initial, planning_ns, "no_initial_plan", f"initial plan: {initial.status.value}"
        )
    status, reason = _loop(run)
    return _result(run, initial, planning_ns, status, reason)


def _prepare(spec: MissionSpec, table: ReplacementTable | None) -> None:
    """Check the table's domain and pay the one-off costs (loading the compiled planner, the
    table's grid geometry, the maze's free-cell set) before anything is timed, so the first
    planning time and the first repair latency of a process are not inflated by them."""
    if table is not None and table.domain != FOUR_WHEEL.name:
        raise ProblemError(
            f"table {spec.options.table_label!r} is for the {table.domain!r} domain; "
            f"missions need a {FOUR_WHEEL.name!r} table"
        )
    if use_numba(spec.backend):
        from selfrepair.search.warmup import ensure_warm

        ensure_warm()
    if table is not None:
        if spec.options.recursion == "flat":
            prepare_grid_geometry(FOUR_WHEEL, table)  # once per table object, like loading it
        free_cell_set(spec.maze)


def _loop(run: _Run) -> tuple[str, str]:
    spec = run.spec
    limit = spec.step_limit()
    while True:
        if _at_goal(spec, run.sim.pose):
            return "reached", "goal reached"
        if run.sim.steps >= limit:
            return "step_limit", f"{limit} steps without reaching the goal"
        run.sense()
        if not run.queue or not four_wheel.available(run.queue[0][0], run.known):
            faulty = run.queue[0][0] if run.queue else None
            repair = _repair_or_replan(run, faulty)
            if repair.status != "repaired":
                return repair.status, _why(repair, run)
            continue
        action, source = run.queue[0]
        terminal = run.execute(action, source)
        if terminal is not None:
            return terminal, f"{action} at {run.sim.pose} would sweep a wall"


def _repair_or_replan(run: _Run, faulty: Action | None) -> Repair:
    """A repair for the faulty next action; with an empty queue off the goal, a plain replan."""
    if faulty is not None:
        return run.repair(faulty)
    from selfrepair.repair.strategies import replan

    spec = run.spec
    t0 = time.perf_counter_ns()
    request = RepairRequest(
        spec.maze,
        run.sim.pose,
        (),
        run.known,
        spec.goal,
        spec.goal_heading,
        spec.options,
        spec.planner,
    )
    repair = replan(request)
    if repair.status == "repaired":
        run.queue.extend((a, "replan") for a in repair.actions)
    run.repairs.append(
        RepairRecord(run.sim.steps, run.sim.pose, None, repair, time.perf_counter_ns() - t0)
    )
    return repair


def _why(repair: Repair, run: _Run) -> str:
    tried = " then ".join(repair.attempts)
    what = "no plan exists" if repair.status == "stuck" else "the planner budget ran out"
    return (
        f"at {run.sim.pose} with known faults "
        f"{four_wheel.format_faults(run.known) or 'none'}: tried {tried}; {what}"
    )


def _result(
    run: _Run, initial: PlanResult, planning_ns: int, status: str, reason: str
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
