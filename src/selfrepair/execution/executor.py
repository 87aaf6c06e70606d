"""The fault-tolerant executor: plan, then drive the mission's stepper against its simulator.

:func:`run_mission` takes a :class:`MissionSpec` (everything needed to run the mission again) and
returns a :class:`MissionResult` (status, every executed step, every repair, and the metrics).

The strategy is started once per mission (its factory gets a
:class:`~selfrepair.repair.strategies.MissionContext` built by
:func:`selfrepair.execution.context.mission_context`: the planner, the free-cell test and the step
cost on this mission's map). The initial plan, the strategy and the known faults go
into a :class:`~selfrepair.execution.stepper.Stepper`, which holds the queue, repairs and splices
it, and records the steps and repairs. :func:`run_mission` runs it to the end; per step:

1. Stop at the goal or at the step limit.
2. With detection ``now`` the simulator's sensors report the active faults to the stepper; with
   ``on-use`` the known faults are those revealed by failed attempts so far.
3. Ask the stepper for the next command (it repairs the queue first when its next action, or
   with a ``horizon`` one of the next few, is unavailable under the known faults; the repair
   latency runs from meeting the faulty action to having the next executable action). When no
   plan exists, the robot waits in place up to ``StrategyOptions.max_wait`` steps in all (the
   faults it senses may clear; not under detection ``on-use``, whose known faults never clear)
   and asks again; a failed repair without waits left ends the mission (``stuck`` or
   ``budget_exhausted``).
4. Send the command to the simulator and tell the stepper what it did. A failed attempt (a fault
   the robot did not know yet) is recorded as a step with source ``failed-attempt`` and reveals
   its blocking faults. With detection ``hidden`` the stepper is also given what the robot
   observed (:meth:`Simulator.observe`) and whether the command took it elsewhere than it should
   have (see :mod:`selfrepair.execution.stepper`), and what its observing teammates saw of
   it (``MissionSpec.observers``, :meth:`Simulator.witnessed`). An oracle strategy (registered
   ``told``) is told the true faults before every command, whatever the detection.

The initial plan is made, by default, before any fault is known (``initial_faults_known=False``),
as in the original experiment. In a changing world it avoids the cells the robot sees blocked at
the start; when none avoids them, it is made on the maze alone, and the robot waits at them. The
executor holds only detected faults; the true ones live in the
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
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.execution.context import mission_context, start_repairer
from selfrepair.execution.faults import Detection
from selfrepair.execution.result import (
    MissionResult,
    MissionSpec,
    MissionStatus,
    MissionTally,
    StepSource,
    TraceStep,
)
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.execution.stepper import Stepper
from selfrepair.geometry import FreeGrid
from selfrepair.repair.strategies import (
    ROBOT,
    Repair,
    RepairStatus,
    diagnosis_report,
    get_strategy,
    strategy_entry,
    uses_table,
)
from selfrepair.search.astar import PlanResult, PlanStatus
from selfrepair.search.backend import use_numba
from selfrepair.search.openmoves import open_moves
from selfrepair.status import mission_status
from selfrepair.tables.model import SomeTable
from selfrepair.world.maze import Maze, clearance_penalties

__all__ = ["run_mission"]


@dataclass(slots=True)
class _Tally:
    """What the mission loop sums on the way, for the metrics (mutable)."""

    moved: list[int] = field(default_factory=list)
    """Per executed step, its (start state, action) as one integer (for the plan distance)."""
    executed_units: int = 0
    penalty: int = 0
    trace: Sequence[TraceStep] | None = None
    """The compiled loop's trace (``None``: the stepper's steps are the trace)."""
    waits: int = 0
    """The compiled loop's wait steps (counted from the trace's rows)."""


def run_mission(
    spec: MissionSpec, *, simulator: Callable[[MissionSpec], Simulator] | None = None
) -> MissionResult:
    """Plan, execute and repair one mission (see the module docstring). ``simulator`` makes the
    simulator that holds the truth (default: the lattice :class:`Simulator`; a physics one is
    :class:`selfrepair.physics.simulator.PhysicsSimulator`)."""
    get_strategy(spec.strategy)  # fails fast on a bad name
    if simulator is not None:
        sim = simulator(spec)
    else:
        sim = Simulator(
            spec.domain,
            spec.maze,
            spec.start,
            spec.schedule,
            spec.seed,
            world=spec.world,
            behaviour=spec.behaviour,
            observation=spec.observation,
            observers=spec.observers,
        )
    initial_known = sim.sense() if spec.initial_faults_known else frozenset()
    table = spec.options.resolved_table() if uses_table(spec.strategy) else None
    _prepare(spec, table)
    context = mission_context(spec, table)
    context.belief.blocked = sim.sense_cells(frozenset())  # what the robot sees at the start
    t0 = time.perf_counter_ns()
    initial = context.plan(
        spec.start, spec.goal, spec.goal_heading, initial_known, context.replan_budget
    )
    if initial.status is PlanStatus.UNSOLVABLE and context.belief.blocked:
        seen, context.belief.blocked = context.belief.blocked, frozenset()
        initial = context.plan(  # no way round what it sees: plan on the maze, wait at them
            spec.start, spec.goal, spec.goal_heading, initial_known, context.replan_budget
        )
        context.belief.blocked = seen
    planning_ns = time.perf_counter_ns() - t0
    # on-use and hidden: the known faults never clear by themselves, so waiting cannot help
    waits = None if spec.schedule.detection is Detection.NOW else 0
    repairer = start_repairer(spec, context)
    stepper = Stepper(context, repairer, initial.actions, initial_known, sim.table, max_wait=waits)
    tally = _Tally()
    if initial.status is not PlanStatus.SOLVED:
        reason = f"initial plan: {initial.status.value}"
        footing = _footing(spec, sim, stepper)
        return _result(spec, sim, stepper, tally, initial, planning_ns, NO_PLAN, reason, footing)
    status, reason, footing = _run_loop(spec, sim, stepper, tally)
    return _result(spec, sim, stepper, tally, initial, planning_ns, status, reason, footing)


def _footing(spec: MissionSpec, sim: Simulator, stepper: Stepper) -> str:
    """The footing the mission's loop would run on (for a mission that ends before it)."""
    if spec.footing == "python":
        return "python"
    from selfrepair.execution.compiled import runs_compiled

    return "compiled" if runs_compiled(spec, sim, stepper) else "python"


def _run_loop(
    spec: MissionSpec, sim: Simulator, stepper: Stepper, tally: _Tally
) -> tuple[MissionStatus, str, str]:
    """The mission's loop on its footing (:mod:`selfrepair.execution.compiled` where it can
    run, unless ``spec.footing`` is ``python``), and which footing ran."""
    if spec.footing != "python":
        from selfrepair.execution.compiled import compiled_loop

        weight = bool(Fraction(spec.clearance_weight))
        penalty = penalty_buffer(sim.grid, spec.maze, spec.clearance_radius) if weight else b""
        ended = compiled_loop(
            spec, sim, stepper, tally.moved, lambda f: _why(f, spec, sim, stepper), penalty
        )
        if ended is not None:
            tally.executed_units, tally.penalty = ended.units, ended.penalty
            tally.trace, tally.waits = ended.trace, ended.waits
            return ended.status, ended.reason, "compiled"
    status, reason = _loop(spec, sim, stepper, tally)
    return status, reason, "python"


NO_PLAN = MissionStatus.NO_INITIAL_PLAN


def _prepare(spec: MissionSpec, table: SomeTable | None) -> None:
    """Check the table's robot, derive the robot's open-plane moves and load the compiled planner
    before anything is timed (the table's geometry and the maze's free grid are made by
    :func:`mission_context`, also before), so the first planning time and the first repair
    latency of a process are not inflated by one-off costs."""
    if table is not None and table.domain is not spec.domain:
        raise ProblemError(
            f"table {spec.options.table_label!r} is for the {table.domain.name!r} domain; "
            f"this mission's robot is {spec.domain.name!r}"
        )
    open_moves(spec.domain)  # the domain's alone (kind prefilled: a cold run keeps it)
    if use_numba(spec.backend, spec.domain):
        from selfrepair.search.warmup import ensure_warm

        ensure_warm()


def _loop(
    spec: MissionSpec, sim: Simulator, stepper: Stepper, tally: _Tally
) -> tuple[MissionStatus, str]:
    """Drive ``stepper`` against ``sim`` until the goal, a failed repair, the step limit or a
    collision.

    The hot path of every experiment: it keeps what it reads on each step in locals and sums the
    metrics' tallies (plan-distance keys, executed time, clearance penalty) as it goes.
    """
    limit = spec.step_limit()
    goal, goal_heading = spec.goal, spec.goal_heading
    told = strategy_entry(spec.strategy, ROBOT).told  # an oracle: told the true faults
    sense_now = spec.schedule.detection is Detection.NOW or told
    hidden = spec.schedule.detection is Detection.HIDDEN
    observers = bool(spec.observers)
    expect = sim.table.moves
    weight = bool(Fraction(spec.clearance_weight))
    margin, stride = sim.grid.margin, sim.grid.stride
    penalty = penalty_buffer(sim.grid, spec.maze, spec.clearance_radius) if weight else b""
    moved = tally.moved
    n_actions = len(spec.domain.actions)
    world = sim.world is not None
    next_action, moved_, record, learn, advance, sense = (
        stepper.next_action, stepper.moved, stepper.record, stepper.learn, sim.advance, sim.sense
    )  # fmt: skip
    if told:
        sense = sim.true_faults
    while True:
        pose = sim.pose
        if pose.cell == goal and (goal_heading is None or pose.heading == goal_heading):
            return MissionStatus.REACHED, "goal reached"
        step = sim.steps
        if step >= limit:
            return MissionStatus.STEP_LIMIT, f"{limit} steps without reaching the goal"
        if sense_now and (sensed := sense()) is not stepper.known:
            learn(sensed)
        if world and (seen := sim.sense_cells(stepper.blocked)) is not stepper.blocked:
            stepper.see(seen)
        entry = next_action(pose, step)
        if entry is None:
            failure = stepper.failure
            assert failure is not None
            return mission_status(failure.status), _why(failure, spec, sim, stepper)
        action, source = entry
        outcome = advance(action)
        if outcome is Outcome.MOVED:
            move = sim.last_move
            assert move is not None
            tally.executed_units += move.units
            moved.append(
                (((pose.y << 32) + 4 * pose.x + pose.heading) * n_actions) + move.action_index
            )
            if weight:
                base = (pose.y + margin) * stride + pose.x + margin
                tally.penalty += sum([penalty[base + offset] for offset in move.cells])
            moved_(step, action, source, pose, sim.pose, move.duration)
            if sim.deviated:  # localised off the plan (physics): replan from where it is
                stepper.relocalise()
        elif outcome is Outcome.COLLISION:
            name = spec.domain.format_action(action)
            return MissionStatus.COLLISION, f"{name} at {sim.pose} would sweep a wall"
        else:
            record(step, action, source, outcome, pose, sim.pose, sim.last_duration,
                   sim.last_blocking, sim.last_bumped)  # fmt: skip
        if hidden:  # what the robot observes of its command, and whether it went astray
            end, want = sim.pose, expect[action][pose.heading]
            deviated = outcome is Outcome.MOVED and (
                (end.x - pose.x, end.y - pose.y, end.heading) != (want.dx, want.dy, want.heading)
            )
            stepper.perceive(
                sim.observe(step, action, pose, outcome),
                deviated,
                outcome is Outcome.MOVED,
                sim.witnessed(step, action, pose, outcome) if observers else (),
            )


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
    "clearance penalties in free-grid layout", 8, kind=CacheKind.PLAN, per_map=True
)


def _why(repair: Repair, spec: MissionSpec, sim: Simulator, stepper: Stepper) -> str:
    tried = " then ".join(repair.attempts)
    what = "no plan exists" if repair.status is RepairStatus.STUCK else "the planner budget ran out"
    known = spec.domain.format_faults(stepper.known) or "none"
    waited = f" after waiting {stepper.waits} steps" if stepper.waits else ""
    return f"at {sim.pose} with known faults {known}: tried {tried}; {what}{waited}"


def _result(
    spec: MissionSpec,
    sim: Simulator,
    stepper: Stepper,
    tally: _Tally,
    initial: PlanResult,
    planning_ns: int,
    status: MissionStatus,
    reason: str,
    footing: str = "python",
) -> MissionResult:
    removed, added, motion_removed, motion_added = _plan_distances(spec, sim, tally, initial)
    steps: Sequence[TraceStep]
    if tally.trace is None:
        steps = tuple(stepper.steps)
        waits = sum(1 for s in steps if s.source is StepSource.WAIT)
        bumps = sum(1 for s in steps if s.source is StepSource.BUMPED)
    else:  # the compiled loop's: no step made (the kernel never bumps)
        steps, waits, bumps = tally.trace, tally.waits, 0
    sums = MissionTally(
        len(tally.moved),
        tally.executed_units,
        sim.unit,
        tally.penalty,
        removed,
        added,
        motion_removed,
        motion_added,
        waits,
        bumps,
    )
    return MissionResult(
        spec,
        status,
        reason,
        steps,
        tuple(stepper.repairs),
        initial,
        planning_ns,
        sim.pose,
        sim.ticks,
        sums,
        footing,
        diagnosis_report(stepper.repairer),
        tuple(stepper.observations),
        tuple(stepper.beliefs),
    )


def _plan_distances(
    spec: MissionSpec, sim: Simulator, tally: _Tally, initial: PlanResult
) -> tuple[int, int, int, int]:
    """Removed and added actions between the initial plan and the executed steps, as multisets
    of (start state, action) encoded as integers (the same keys the loop recorded), then the same
    by motion class (each action index replaced by that of the first action of its motion)."""
    moves = sim.table.moves
    domain = spec.domain
    n_actions = len(domain.actions)
    planned = [
        (((p.y << 32) + 4 * p.x + p.heading) * n_actions) + moves[a][0].action_index
        for p, a in zip(initial.poses, initial.actions, strict=False)
    ]
    executed = tally.moved
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
