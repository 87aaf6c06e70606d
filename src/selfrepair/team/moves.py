"""One go at a team robot's drive: place it, sense and repair faults and cells blocked by world
events, keep other robots' cells free, and send the next primitive action to the robot's
simulator (part of :mod:`selfrepair.team.engine`'s steps 3 and 4)."""

from __future__ import annotations

from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection
from selfrepair.execution.result import STEP_OF_OUTCOME
from selfrepair.execution.simulator import Outcome
from selfrepair.geometry import Cell
from selfrepair.team.driving import (
    INCIDENT_OF_START,
    DriveStart,
    begin_drive,
    cancel_drive,
    mark_stale,
    own_repair,
    place,
)
from selfrepair.team.faults import know, reoffer
from selfrepair.team.incidents import incident
from selfrepair.team.model import IncidentKind, TeamFaultKind
from selfrepair.team.reservations import TimedStep
from selfrepair.team.result import MoveRecord
from selfrepair.team.state import Entry, RobotState, TeamWorld
from selfrepair.team.strategies import TeamRepairer

__all__ = ["command", "drive_once", "hold", "learn_blocked", "look", "safe", "tell"]


def drive_once(
    world: TeamWorld, repairer: TeamRepairer, robot: RobotState, head: Entry, t: int
) -> int | None:
    """One go at the head drive; ``None`` to look at the robot again at once."""
    drive = robot.drive
    if drive is not None and drive.target != head.action.target:
        cancel_drive(world, robot, t)
        drive = None
    if drive is None:
        if robot.sim.world is not None:
            look(world, robot, t)  # it plans its drive around what it sees
        start = begin_drive(world, robot, head, t)
        if start is DriveStart.ARRIVED:
            robot.queue.popleft()
            return None
        if start in (DriveStart.STUCK, DriveStart.BLOCKED):
            incident(world, repairer, robot, head, INCIDENT_OF_START[start], t)
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
    if sim.world is not None:
        look(world, robot, t)  # its range sensors, before every command
    faulty = not stepper.available(step.action)
    if faulty or (stepper.blocked and stepper.sweeps_blocked(robot.pose, step.action)):
        if not own_repair(world, robot, t):
            kind = IncidentKind.STUCK if faulty else IncidentKind.BLOCKED
            incident(world, repairer, robot, head, kind, t)
        return None
    if any(c in world.blocked for c in step.cells[1:]):
        learn_blocked(world, robot, step.cells)
        incident(world, repairer, robot, head, IncidentKind.BLOCKED, t)
        return None
    if not safe(world, robot, step.cells, t):
        hold(world, robot, t)
        robot.retry_at = t + 1
        return t + 1
    return command(world, robot, step, t)


def command(world: TeamWorld, robot: RobotState, step: TimedStep, t: int) -> int:
    """Send the placed primitive ``step`` to the robot's simulator at ``t``; returns when the
    robot is free again. A failed attempt (a fault the robot did not know) teaches it the
    faults that blocked the command, a bump (a cell blocked by a world event that it had not
    seen) the cells it touched; its drive is placed again after the attempt."""
    drive, sim = robot.drive, robot.sim
    assert drive is not None
    stepper, pose = drive.stepper, robot.pose
    source = stepper.queue[0][1]
    number = sim.steps
    sim.wait_until(t)
    outcome = sim.advance(step.action)
    stepper.record(
        number, step.action, source, outcome, pose, sim.pose, sim.last_duration,
        sim.last_blocking, sim.last_bumped,
    )  # fmt: skip
    if outcome is Outcome.FAILED_ATTEMPT or outcome is Outcome.BUMPED:
        end = sim.units
        robot.busy_until, robot.footprint = end, (pose.cell,)
        failed = outcome is Outcome.FAILED_ATTEMPT
        world.moves.append(
            MoveRecord(robot.name, t, end, step.action, pose, pose, STEP_OF_OUTCOME[outcome])
        )
        if failed:
            know(world, robot, stepper.known, t)
        else:  # it touched blocked cells: its stepper learned them, the team hears of them
            tell(world, robot, stepper.blocked)
        hold(world, robot, t)
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


def hold(world: TeamWorld, robot: RobotState, t: int) -> None:
    """``robot`` keeps its cell from ``t`` and places its drive again when it next acts."""
    assert robot.drive is not None
    world.reservations.release_from(robot.name, t)
    world.reservations.park(robot.name, robot.pose.cell, t)
    mark_stale(world, robot)
    robot.drive.steps = []


def safe(world: TeamWorld, robot: RobotState, cells: tuple[Cell, ...], t: int) -> bool:
    """Whether no other robot holds a cell of ``cells`` now."""
    wanted = set(cells)
    return not any(
        wanted.intersection(other.occupancy(t))
        for other in world.robots.values()
        if other is not robot
    )


def look(world: TeamWorld, robot: RobotState, t: int) -> None:
    """``robot``'s range sensors at ``t`` (its simulator's
    :meth:`~selfrepair.execution.simulator.Simulator.sense_cells`: nothing with bump sensing)
    update what the team believes blocked by world events (:func:`tell`)."""
    robot.sim.wait_until(t)
    tell(world, robot, robot.sim.sense_cells(world.seen))


def tell(world: TeamWorld, robot: RobotState, believed: frozenset[Cell]) -> None:
    """``robot`` now believes ``believed`` blocked by world events: when that changes what the
    team believes, it tells the team (one broadcast), every robot's drive sees the new belief,
    and when cells opened the team's orphaned items are offered again (as when a blocked team
    fault clears, :func:`~selfrepair.team.faults.reoffer`)."""
    if believed is world.seen or believed == world.seen:
        return
    opened = bool(world.seen - believed)
    world.seen = believed
    world.broadcast(robot.name)
    for other in world.robots.values():
        if other.drive is not None:
            other.drive.stepper.see(believed)
    if opened:
        world.dirty.update(reoffer(world))


def learn_blocked(world: TeamWorld, robot: RobotState, cells: tuple[Cell, ...]) -> None:
    """The robot sees the blocked cells in its way (the whole blocked group) and tells all."""
    for fault in world.scenario.faults:
        if fault.kind is TeamFaultKind.BLOCKED and any(c in fault.cells for c in cells[1:]):
            world.known_blocked.update(c for c in fault.cells if c in world.blocked)
    world.broadcast(robot.name)
