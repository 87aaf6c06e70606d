"""Team faults over time, as the engine (:mod:`selfrepair.team.engine`) applies them: when each
starts and clears (:func:`faults_due`), what each robot learns of its wheel faults (:func:`know`,
with the discovery of each team fault and its delay), grippers and blocked cells, and the work
re-offered when a blockage clears (:func:`reoffer`).

The true wheel faults of a robot are its simulator's (its
:class:`~selfrepair.team.state.RobotFaultClock` reads the stretches kept here); a robot with
detection ``now`` senses them whenever they change and before every command, one with ``on-use``
learns them from failed commands only.

**Re-offered work.** A team strategy may leave an item to no robot: full re-allocation drops the
tasks it cannot reach on the known map, for instance an item lying on a cell blocked for a while.
When blocked cells open again, every open item that no robot carries or has in its queue is
offered again: the robots that can carry are allocated those items by
:func:`~selfrepair.team.allocation.allocate` from where their queues end (idle robots first, as
robots with work are ready only when it is done), and the items go at the end of their queues.
"""

from __future__ import annotations

from selfrepair.execution.faults import Detection, Persistence
from selfrepair.geometry import Cell
from selfrepair.search.lattice import planning_actions
from selfrepair.team.allocation import Job, Worker, allocate, distance_maps, job_plan
from selfrepair.team.model import (
    DROP_TICKS,
    PICK_TICKS,
    ActionKind,
    TeamFault,
    TeamFaultKind,
    Trigger,
)
from selfrepair.team.result import DiscoveryRecord, FaultRecord, TeamSource
from selfrepair.team.state import Entry, FaultState, RobotState, TeamWorld

__all__ = ["fault_times", "faults_due", "know", "reoffer"]


def fault_times(clocks: list[FaultState]) -> list[int]:
    times = []
    for c in clocks:
        if not c.active and not c.done and c.on is not None:
            times.append(c.on)
        if c.active and c.off is not None:
            times.append(c.off)
    return times


def faults_due(world: TeamWorld, clocks: list[FaultState], t: int) -> None:
    """Start and clear the team faults due at ``t`` and apply their effects."""
    changed = False
    for clock in clocks:
        fault = clock.fault
        if clock.on is None and fault.trigger is Trigger.PICK:
            first = world.robots[fault.robot].first_pick
            if first is not None:
                clock.on = first + fault.at * world.scale
        if not clock.active and not clock.done and clock.on is not None and clock.on <= t:
            clock.active, changed = True, True
            if fault.persistence is Persistence.TRANSIENT:
                assert fault.duration is not None
                clock.off = clock.on + fault.duration * world.scale
            world.fault_log.append(FaultRecord(t, clock.index, True))
        elif clock.active and clock.off is not None and clock.off <= t:
            clock.active, clock.done, changed = False, True, True
            world.fault_log.append(FaultRecord(t, clock.index, False))
    if changed:
        _apply(world, [c.fault for c in clocks if c.active])


def _apply(world: TeamWorld, active: list[TeamFault]) -> None:
    """The team faults active now take effect: each robot senses its wheel faults (detection
    ``now``; with ``on-use`` it knows only what failed commands taught it), grippers fail or work
    again, cells block or open."""
    domain = world.scenario.domain
    blocked: set[Cell] = set()
    t = world.now
    for robot in world.robots.values():
        gripper = not any(f.robot == robot.name and f.kind is TeamFaultKind.GRIPPER for f in active)
        known = robot.sim.sense() if world.scenario.detection is Detection.NOW else robot.faults
        if known != robot.faults or gripper != robot.gripper_ok:
            know(world, robot, known, t)
            robot.gripper_ok = gripper
            robot.deferred = None
            if robot.stuck and planning_actions(domain, robot.faults):
                robot.stuck = False  # it can move again: the team hears of it
                world.broadcast(robot.name)
    for fault in active:
        if fault.kind is TeamFaultKind.BLOCKED:
            blocked.update(fault.cells)
    opened = world.blocked - blocked
    world.blocked = blocked
    world.known_blocked &= blocked  # a blocked cell that opened again is reported
    if opened:
        world.dirty.update(reoffer(world))


def know(world: TeamWorld, robot: RobotState, known: frozenset[object], t: int) -> None:
    """``robot`` now knows exactly the domain faults ``known`` (its drive's stepper too); a team
    fault of its own that it had not noticed and that ``known`` shows is discovered at ``t``."""
    robot.faults = known
    if robot.drive is not None:
        robot.drive.stepper.learn(known)
    for state in robot.clock.states():
        if state.on is None or state.index in robot.discovered or state.on > t:
            continue
        if robot.clock.effect(state.index) & known:
            robot.discovered.add(state.index)
            world.discoveries.append(DiscoveryRecord(t, robot.name, state.index, t - state.on))


def orphans(world: TeamWorld) -> list[str]:
    """Open items that no robot carries and no robot's queue picks up or takes, in task order."""
    wanted = {
        e.action.item
        for r in world.robots.values()
        for e in r.queue
        if e.action.kind in (ActionKind.PICK, ActionKind.HANDOVER)
    }
    return [i for i in world.open_items() if i not in wanted and not world.carrier(i)]


def reoffer(world: TeamWorld) -> list[str]:
    """Offer the orphaned items again (see the module docstring); returns the robots given
    work."""
    items = orphans(world)
    if not items:
        return []
    capable = [
        r
        for r in world.robots.values()
        if r.can_grip and not r.stuck and planning_actions(world.scenario.domain, r.faults)
    ]
    idle = [r for r in capable if not r.queue and r.busy_until <= world.now]
    workers = [_worker(world, r) for r in (idle or capable)]
    jobs = []
    for item in items:
        cell = world.items[item].cell
        assert cell is not None  # not carried: it lies somewhere
        jobs.append(Job(item, cell, world.scenario.task(item).dropoff))
    cells = [j.source for j in jobs] + [j.dropoff for j in jobs]
    maps = distance_maps(world.known_map(), cells, backend=world.options.backend)
    order, _ = allocate(workers, jobs, maps)
    given = []
    for worker in workers:
        assigned = order[worker.name]
        if not assigned:
            continue
        robot = world.robots[worker.name]
        plan = job_plan(robot.name, worker.cell, assigned, lambda job, here: here)
        robot.queue.extend(Entry(a, TeamSource.REALLOCATION) for a in plan)
        robot.retry_at, robot.deferred = 0, None
        world.messages += 1  # the offer to this robot
        given.append(robot.name)
    return given


def _worker(world: TeamWorld, robot: RobotState) -> Worker:
    """``robot`` as the allocation sees it: where its queue ends, and roughly when (ticks: the
    grid length of its queued drives and its acts)."""
    cell, ready = robot.pose.cell, max(0, robot.busy_until - world.now) // world.scale
    for entry in robot.queue:
        action = entry.action
        if action.kind is ActionKind.DRIVE and action.robot == robot.name:
            assert action.target is not None
            ready += abs(action.target[0] - cell[0]) + abs(action.target[1] - cell[1])
            cell = action.target
        elif action.kind in (ActionKind.PICK, ActionKind.DROP):
            ready += PICK_TICKS if action.kind is ActionKind.PICK else DROP_TICKS
    return Worker(robot.name, cell, ready)
