"""The team engine: allocate, then run every robot's queue in one shared maze, handling faults.

:func:`run_team` takes a :class:`~selfrepair.team.model.TeamScenario` and
:class:`~selfrepair.team.result.TeamOptions` and returns a
:class:`~selfrepair.team.result.TeamResult`. It is deterministic: the same scenario and
options give the same result (the timings aside).

1. **Allocation and team plan.** Tasks are assigned by :func:`~selfrepair.team.allocation.allocate`
   (Hungarian rounds); each robot's queue is drive - pick - drive - drop per task.
2. **Time.** A discrete-event simulation on integer units (``scale`` per tick). At each event
   time the team faults due then start or clear, then every robot, in scenario order (its
   priority), finishes what ended and starts what it can: the next primitive action of its
   drive (placed in time by :mod:`selfrepair.team.driving`), a pick, a drop, or a handover
   (when its partner stands next to it with the same handover next).
3. **Safety.** Drives are planned around the reservation table; on top of that, a robot starts
   a primitive action only when no other robot holds any cell of its footprint *now* (a moving
   robot holds its whole footprint until the action ends). Plans that went stale (a robot
   delayed by a fault, a robot that could not plan) are placed again. So robots never share a
   cell or a swept cell at the same time, whatever the plans say;
   :func:`~selfrepair.team.trace.replay_team` checks it on every trace.
4. **Faults.** Team faults start at a tick, or some ticks after their robot's first pick. Each
   robot has its own :class:`~selfrepair.execution.simulator.Simulator` (its true faults, their
   clock, its steps; an intermittent fault is drawn per robot step) and executes its primitive
   actions in it. It learns its wheel faults as a single robot does (the scenario's
   ``detection``): ``now``, sensed at once and before every command, or ``on-use``, when a
   command fails (a failed attempt: the robot stays, one tick passes, the trace records it);
   each discovery is recorded with its delay. A next primitive that is faulty under the known
   faults goes to the robot's own :class:`~selfrepair.execution.stepper.Stepper` first (its
   repairer and splice, :mod:`selfrepair.team.driving`); when that fails, or a drive meets a
   blocked cell, or a gripper has failed, the robot has an *incident* and the team strategy
   decides (:mod:`selfrepair.team.strategies`). The repair latency runs from the incident until
   every robot whose plan changed and is not in the middle of an action has its next drive
   placed in time (garbage collection is held off during it; each mission starts without kept
   cost-to-go maps, so a repair's cost does not depend on the missions run before it in the
   process).
5. **End.** When every item is delivered; when nothing more can happen (``stalled``: no robot
   with work can act, no fault will clear, nothing moved for :data:`STALL_TICKS`); or at
   ``max_ticks``.
"""

from __future__ import annotations

import gc
import time
from collections import deque

from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.result import StepSource
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Cell
from selfrepair.repair.strategies import StrategyName
from selfrepair.search.backend import use_numba
from selfrepair.team.allocation import Job, Worker, allocate, distance_maps, job_plan
from selfrepair.team.binding import Incident
from selfrepair.team.driving import (
    INCIDENT_OF_START,
    DriveStart,
    begin_drive,
    cancel_drive,
    mark_stale,
    own_repair,
    place,
)
from selfrepair.team.faults import fault_times, faults_due, know
from selfrepair.team.model import (
    DROP_TICKS,
    HANDOVER_TICKS,
    PICK_TICKS,
    ActionKind,
    IncidentKind,
    Load,
    TeamFaultKind,
    TeamScenario,
    Trigger,
)
from selfrepair.team.reservations import FOREVER, TimedStep
from selfrepair.team.result import (
    ActRecord,
    IncidentRecord,
    MoveRecord,
    TeamOptions,
    TeamRepairRecord,
    TeamResult,
    TeamStatus,
)
from selfrepair.team.robottable import robot_table
from selfrepair.team.scenario import check_scenario
from selfrepair.team.spacetime import clear_cost_to_go
from selfrepair.team.state import (
    Entry,
    FaultState,
    ItemState,
    RobotFaultClock,
    RobotState,
    TeamWorld,
    item_task_of,
)
from selfrepair.team.strategies import get_team_strategy
from selfrepair.team.table import get_team_table

__all__ = ["STALL_TICKS", "default_max_ticks", "run_team"]

STALL_TICKS = 150
"""Ticks without any robot moving or acting (and no fault left to clear) after which a mission
with undelivered items is over."""

_ROUNDS = 12
"""Passes over the robots at one event time (a robot whose plan another changed goes again)."""
_FORGET_EVERY = 10
"""Ticks between two clean-ups of reservations that lie in the past."""
_STEPS = 64
"""Things one robot may do at one event time before it must wait (a guard, never reached)."""


def default_max_ticks(scenario: TeamScenario) -> int:
    """The default ``max_ticks``: generous for the maze and the number of tasks."""
    maze = scenario.maze
    return 300 + 6 * (maze.width + maze.height) * (len(scenario.tasks) + 1)


def run_team(scenario: TeamScenario, options: TeamOptions | None = None) -> TeamResult:
    """Run one team mission (see the module docstring)."""
    options = options or TeamOptions()
    check_scenario(scenario)
    get_team_strategy(options.strategy)  # fails fast on a bad name
    if options.strategy is StrategyName.TEAM_REPLACEMENT:
        get_team_table(options.table)  # a generated table is made before anything is timed
    robot_table(scenario, options)  # so is the robots' own (and a table for another robot fails)
    if use_numba(options.backend):
        from selfrepair.search.warmup import ensure_warm

        ensure_warm()
    clear_cost_to_go()  # every mission's repairs start from the same (cold) heuristics
    world = _world(scenario, options)
    t0 = time.perf_counter_ns()
    _allocate(world)
    allocation_ns = time.perf_counter_ns() - t0
    initial = tuple((n, tuple(e.action for e in r.queue)) for n, r in world.robots.items())
    status, reason = _loop(world)
    return TeamResult(
        scenario,
        options,
        status,
        reason,
        world.scale,
        initial,
        allocation_ns,
        tuple(world.moves),
        tuple(world.acts),
        tuple(world.fault_log),
        tuple(world.incidents),
        tuple(world.repairs),
        tuple(world.own_repairs),
        tuple(
            (item, at)
            for item, state in world.items.items()
            if (at := state.delivered_at) is not None
        ),
        world.now,
        world.messages,
        world.plans,
        world.yields,
        world.expansions,
        tuple(world.discoveries),
    )


def _world(scenario: TeamScenario, options: TeamOptions) -> TeamWorld:
    scale = scenario.domain.time_unit
    states = [
        FaultState(i, f, f.at * scale if f.trigger is Trigger.TICK else None)
        for i, f in enumerate(scenario.faults)
    ]
    detection = FaultSchedule(detection=scenario.detection)
    robots = {}
    for r in scenario.robots:
        clock = RobotFaultClock(scenario.domain, states, r.name, options.seed)
        sim = Simulator(scenario.domain, scenario.maze, r.start, detection, options.seed, clock)
        robots[r.name] = RobotState(r, r.start, deque(), sim, clock)
    items = {t.item: ItemState(t.pickup) for t in scenario.tasks}
    world = TeamWorld(scenario, options, scale, robots, items, faults=states)
    for robot in robots.values():
        world.reservations.park(robot.name, robot.pose.cell, 0)
    return world


def _allocate(world: TeamWorld) -> None:
    """The initial allocation and team plan."""
    scenario = world.scenario
    workers = [Worker(r.name, r.start.cell) for r in scenario.robots if r.gripper]
    jobs = [Job(t.item, t.pickup, t.dropoff) for t in scenario.tasks]
    cells = [j.source for j in jobs] + [j.dropoff for j in jobs]
    maps = distance_maps(scenario.maze, cells, backend=world.options.backend)
    order, left = allocate(workers, jobs, maps)
    if left:
        raise ProblemError(f"no robot can reach item {left[0].item}")  # check_scenario prevents it
    for name, assigned in order.items():
        robot = world.robots[name]
        robot.queue = deque(Entry(a) for a in job_plan(name, robot.pose.cell, assigned, _no_meet))


def _no_meet(job: Job, here: Cell) -> Cell:
    return here


# --- the loop -------------------------------------------------------------------------------------


def _loop(world: TeamWorld) -> tuple[TeamStatus, str]:
    scenario, scale = world.scenario, world.scale
    limit = (world.options.max_ticks or default_max_ticks(scenario)) * scale
    clocks = world.faults
    wake = {name: 0 for name in world.robots}
    t = forgotten = 0
    while True:
        world.now = t
        faults_due(world, clocks, t)
        pending = list(world.robots)
        for _ in range(_ROUNDS):
            world.dirty.clear()
            for name in pending:
                wake[name] = _advance(world, world.robots[name], t)
            pending = [n for n in world.robots if n in world.dirty]
            if not pending:
                break
        if t - forgotten >= _FORGET_EVERY * scale:
            world.reservations.forget_before(t)
            forgotten = t
        if all(s.delivered_at is not None for s in world.items.values()):
            return TeamStatus.DELIVERED, "every item delivered"
        if t >= limit:
            return TeamStatus.TIME_LIMIT, f"{limit // scale} ticks passed (max_ticks)"
        upcoming = [c for c in fault_times(clocks) if c > t]
        if t - world.last_progress > STALL_TICKS * scale and not upcoming:
            return TeamStatus.STALLED, _stall_reason(world)
        candidates = [w for w in wake.values() if w > t] + upcoming
        nxt = min(candidates, default=FOREVER)
        if nxt >= FOREVER:
            return TeamStatus.STALLED, _stall_reason(world)
        t = min(nxt, limit)


def _stall_reason(world: TeamWorld) -> str:
    waiting = [r.name for r in world.robots.values() if r.queue]
    left = [i for i in world.open_items()]
    return (
        f"{len(left)} items undelivered ({', '.join(left) or 'none'}); robots with work left: "
        f"{', '.join(waiting) or 'none'}"
    )


def _advance(world: TeamWorld, robot: RobotState, t: int) -> int:
    """Let ``robot`` do what it can at ``t``; returns when it wants to act next."""
    for _ in range(_STEPS):
        if robot.busy_until > t:
            return robot.busy_until
        if robot.pending is not None:
            _finish(world, robot, t)
        if not robot.queue:
            if robot.drive is not None:
                cancel_drive(world, robot, t)
            return FOREVER
        if robot.retry_at > t:
            return robot.retry_at
        head = robot.queue[0]
        kind = head.action.kind
        if kind is ActionKind.DRIVE:
            wait = _drive(world, robot, head, t)
        elif kind is ActionKind.HANDOVER:
            wait = _handover(world, robot, head, t)
        else:
            wait = _pick_or_drop(world, robot, head, t)
        if wait is not None:
            return wait
    return t + 1


def _drive(world: TeamWorld, robot: RobotState, head: Entry, t: int) -> int | None:
    """One go at the head drive; ``None`` to look at the robot again at once."""
    drive = robot.drive
    if drive is not None and drive.target != head.action.target:
        cancel_drive(world, robot, t)
        drive = None
    if drive is None:
        start = begin_drive(world, robot, head, t)
        if start is DriveStart.ARRIVED:
            robot.queue.popleft()
            return None
        if start in (DriveStart.STUCK, DriveStart.BLOCKED):
            _incident(world, robot, head, INCIDENT_OF_START[start], t)
            return None
        if start is DriveStart.WAITING:
            return robot.retry_at
        drive = robot.drive
        assert drive is not None
    drive.entry = head
    if robot.stale and not place(world, robot, t):
        return robot.retry_at
    if not drive.steps:
        if drive.stepper.queue:
            return robot.retry_at if not place(world, robot, t) else None
        robot.drive = None
        robot.queue.popleft()
        return None
    step = drive.steps[0]
    if step.start > t:
        return step.start
    if step.start < t:
        return robot.retry_at if not place(world, robot, t) else None
    sim, stepper = robot.sim, drive.stepper
    if world.scenario.detection is Detection.NOW:
        sensed = sim.sense()  # the robot senses its faults before every command
        if sensed is not robot.faults and sensed != robot.faults:
            know(world, robot, sensed, t)
    if not stepper.available(step.action):
        if not own_repair(world, robot, t):
            _incident(world, robot, head, IncidentKind.STUCK, t)
        return None
    if any(c in world.blocked for c in step.cells[1:]):
        _learn_blocked(world, robot, step.cells)
        _incident(world, robot, head, IncidentKind.BLOCKED, t)
        return None
    if not _safe(world, robot, step.cells, t):
        _hold(world, robot, t)
        robot.retry_at = t + 1
        return t + 1
    return _command(world, robot, step, t)


def _command(world: TeamWorld, robot: RobotState, step: TimedStep, t: int) -> int:
    """Send the placed primitive ``step`` to the robot's simulator at ``t``; returns when the
    robot is free again. A failed attempt (a fault the robot did not know) teaches it the
    faults that blocked the command; its drive is placed again after the attempt."""
    drive, sim = robot.drive, robot.sim
    assert drive is not None
    stepper, pose = drive.stepper, robot.pose
    source = stepper.queue[0][1]
    number = sim.steps
    sim.wait_until(t)
    outcome = sim.advance(step.action)
    stepper.record(
        number, step.action, source, outcome, pose, sim.pose, sim.last_duration,
        sim.last_blocking,
    )  # fmt: skip
    if outcome is Outcome.FAILED_ATTEMPT:
        end = sim.units
        robot.busy_until, robot.footprint = end, (pose.cell,)
        world.moves.append(
            MoveRecord(robot.name, t, end, step.action, pose, pose, StepSource.FAILED_ATTEMPT)
        )
        know(world, robot, stepper.known, t)
        _hold(world, robot, t)
        return end
    if outcome is not Outcome.MOVED or sim.pose != step.after or sim.units != step.end:
        raise ProblemError(f"{robot.name}: the placed step {step} is not what the robot does")
    robot.pose, robot.busy_until, robot.footprint = step.after, step.end, step.cells
    world.moves.append(
        MoveRecord(robot.name, t, step.end, step.action, step.before, step.after, source)
    )
    drive.steps.pop(0)
    world.last_progress = t
    return step.end


def _hold(world: TeamWorld, robot: RobotState, t: int) -> None:
    """``robot`` keeps its cell from ``t`` and places its drive again when it next acts."""
    assert robot.drive is not None
    world.reservations.release_from(robot.name, t)
    world.reservations.park(robot.name, robot.pose.cell, t)
    mark_stale(world, robot)
    robot.drive.steps = []


def _safe(world: TeamWorld, robot: RobotState, cells: tuple[Cell, ...], t: int) -> bool:
    """Whether no other robot holds a cell of ``cells`` now."""
    wanted = set(cells)
    return not any(
        wanted.intersection(other.occupancy(t))
        for other in world.robots.values()
        if other is not robot
    )


def _learn_blocked(world: TeamWorld, robot: RobotState, cells: tuple[Cell, ...]) -> None:
    """The robot sees the blocked cells in its way (the whole blocked group) and tells all."""
    for fault in world.scenario.faults:
        if fault.kind is TeamFaultKind.BLOCKED and any(c in fault.cells for c in cells[1:]):
            world.known_blocked.update(c for c in fault.cells if c in world.blocked)
    world.broadcast(robot.name)


def _pick_or_drop(world: TeamWorld, robot: RobotState, head: Entry, t: int) -> int | None:
    action = head.action
    state = world.items[action.item]
    if state.delivered_at is not None or state.lost:
        robot.queue.popleft()
        return None
    if action.kind is ActionKind.DROP and robot.holding != action.item:
        robot.queue.popleft()  # nothing to drop: the item went another way
        return None
    if not robot.can_grip:
        _incident(world, robot, head, IncidentKind.GRIPPER, t)
        return None
    if action.kind is ActionKind.PICK and (
        robot.holding or state.holder or state.cell != robot.pose.cell
    ):
        return t + world.scale  # the item is not here (yet)
    ticks = PICK_TICKS if action.kind is ActionKind.PICK else DROP_TICKS
    _start_act(world, (robot,), head, t + ticks * world.scale)
    return None


def _handover(world: TeamWorld, robot: RobotState, head: Entry, t: int) -> int | None:
    action = head.action
    state = world.items[action.item]
    if state.delivered_at is not None or state.lost:
        robot.queue.popleft()
        return None
    giver, taker = world.robots[action.robot], world.robots[action.taker]
    if robot is taker and not taker.can_grip:
        _incident(world, robot, head, IncidentKind.GRIPPER, t)
        return None
    other = taker if robot is giver else giver
    ready = (
        bool(other.queue)
        and other.queue[0].action == action
        and other.busy_until <= t
        and other.pending is None
        and giver.holding == action.item
        and taker.can_grip
        and not taker.holding
    )
    (gx, gy), (tx, ty) = giver.pose.cell, taker.pose.cell
    if not ready or abs(gx - tx) + abs(gy - ty) != 1:
        return t + 1
    _start_act(world, (giver, taker), head, t + HANDOVER_TICKS * world.scale)
    world.dirty.add(other.name)
    return None


def _start_act(world: TeamWorld, robots: tuple[RobotState, ...], head: Entry, end: int) -> None:
    t = world.now
    for robot in robots:
        if robot.drive is not None:
            robot.drive = None
        robot.queue.popleft()
        robot.busy_until, robot.footprint, robot.pending = end, (), head.action
    world.acts.append(ActRecord(t, end, head.action, tuple(r.pose.cell for r in robots)))
    world.last_progress = t


def _finish(world: TeamWorld, robot: RobotState, t: int) -> None:
    """Apply the effect of the act that ``robot`` just finished (once for a handover)."""
    action = robot.pending
    robot.pending = None
    assert action is not None
    state = world.items[action.item]
    if action.kind is ActionKind.PICK:
        robot.holding, state.holder, state.cell = action.item, robot.name, None
        if robot.first_pick is None:
            robot.first_pick = robot.busy_until
    elif action.kind is ActionKind.DROP:
        robot.holding, state.holder, state.cell = "", "", robot.pose.cell
        if robot.pose.cell == world.scenario.task(action.item).dropoff:
            state.delivered_at = robot.busy_until
    elif state.holder == action.robot:
        world.robots[action.robot].holding = ""
        world.robots[action.taker].holding = action.item
        state.holder = action.taker


# --- incidents ------------------------------------------------------------------------------------


def _incident(
    world: TeamWorld, robot: RobotState, entry: Entry, kind: IncidentKind, t: int
) -> None:
    """Record the incident and let the team strategy repair it (timed)."""
    if robot.deferred == (entry.action, kind.value):
        robot.retry_at = t + 2 * world.scale
        return
    item = entry.action.item or item_task_of(robot)
    load = Load.CARRYING if robot.load else Load.EMPTY
    world.incidents.append(IncidentRecord(t, robot.name, entry.action, kind, load))
    if kind is IncidentKind.STUCK:
        robot.stuck = True
        world.broadcast(robot.name)
    if robot.drive is not None:
        cancel_drive(world, robot, t)
    repairer = get_team_strategy(world.options.strategy)(world)  # stateless: started per incident
    collecting = gc.isenabled()
    gc.disable()  # a collection's pause belongs to no repair: it runs after the timed part
    try:
        t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
        plans0, expansions0 = world.plans, world.expansions
        decision = repairer.repair(Incident(robot.name, entry, kind, load, item, t))
        for name in world.robots:  # scenario order: a frozenset's order depends on the hash seed
            if name in decision.changed:
                _prepare(world, world.robots[name], t)
        latency, cpu = time.perf_counter_ns() - t0, time.thread_time_ns() - c0
    finally:
        if collecting:
            gc.enable()
    world.repairs.append(
        TeamRepairRecord(
            t,
            robot.name,
            entry.action,
            kind,
            decision.outcome,
            decision.source,
            decision.candidate,
            decision.helper,
            decision.preempted,
            decision.preemption_ticks,
            tuple(sorted(decision.changed - {robot.name})),
            decision.messages,
            world.plans - plans0,
            world.expansions - expansions0,
            latency,
            decision.changes,
            decision.lost,
            cpu,
        )
    )
    world.messages += decision.messages
    world.dirty.update(decision.changed)


def _prepare(world: TeamWorld, robot: RobotState, t: int) -> None:
    """Place the next drive of a robot whose plan changed (part of the repair latency); a robot
    in the middle of an action plans when the action ends."""
    if robot.busy_until > t:
        if robot.drive is not None:
            robot.drive = None
            world.reservations.release_from(robot.name, robot.busy_until)
            world.reservations.park(robot.name, robot.pose.cell, robot.busy_until)
        return
    if robot.drive is not None:
        cancel_drive(world, robot, t)
    robot.retry_at = 0
    if robot.queue and robot.queue[0].action.kind is ActionKind.DRIVE:
        start = begin_drive(world, robot, robot.queue[0], t)
        if start is not DriveStart.PLACED:
            robot.drive = None
