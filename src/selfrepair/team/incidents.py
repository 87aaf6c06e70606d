"""A team robot's incident: recorded, then repaired by the team strategy, timed (part of
:mod:`selfrepair.team.engine`'s step 4). The robots whose plans the decision changed place their
next drive within the timed part."""

from __future__ import annotations

import gc
import time

from selfrepair.team.binding import Incident
from selfrepair.team.driving import DriveStart, begin_drive, cancel_drive
from selfrepair.team.model import ActionKind, IncidentKind, Load
from selfrepair.team.result import IncidentRecord, TeamRepairRecord
from selfrepair.team.state import Entry, RobotState, TeamWorld, item_task_of
from selfrepair.team.strategies import TeamRepairer

__all__ = ["incident", "prepare"]


def incident(
    world: TeamWorld,
    repairer: TeamRepairer,
    robot: RobotState,
    entry: Entry,
    kind: IncidentKind,
    t: int,
) -> None:
    """Record the incident and let the team strategy, ``repairer`` (started once for the
    mission), repair it (timed)."""
    if robot.deferred == (entry.action, kind.value):
        robot.retry_at = t + 2 * world.scale
        return
    if robot.last_incident == (t, entry.action, kind):
        # the strategy's answer gave the robot the same incident at the same instant (a carrier
        # whose drop-off is walled off for now): it waits that incident out, as ``alone`` does
        robot.deferred = (entry.action, kind.value)
        robot.retry_at = t + 2 * world.scale
        return
    robot.last_incident = (t, entry.action, kind)
    item = entry.action.item or item_task_of(robot)
    load = Load.CARRYING if robot.load else Load.EMPTY
    world.incidents.append(IncidentRecord(t, robot.name, entry.action, kind, load))
    if kind is IncidentKind.STUCK:
        robot.stuck = True
        world.broadcast(robot.name)
    if robot.drive is not None:
        cancel_drive(world, robot, t)
    collecting = gc.isenabled()
    gc.disable()  # a collection's pause belongs to no repair: it runs after the timed part
    try:
        t0, c0 = time.perf_counter_ns(), time.thread_time_ns()
        plans0, expansions0 = world.plans, world.expansions
        decision = repairer.repair(Incident(robot.name, entry, kind, load, item, t))
        for name in world.robots:  # scenario order: a frozenset's order depends on the hash seed
            if name in decision.changed:
                prepare(world, world.robots[name], t)
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


def prepare(world: TeamWorld, robot: RobotState, t: int) -> None:
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
