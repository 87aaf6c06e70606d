"""Picks, drops and handovers in a team mission: when each can start, and its effect on the
items when it ends (part of :mod:`selfrepair.team.engine`'s step 2)."""

from __future__ import annotations

from selfrepair.team.incidents import incident
from selfrepair.team.model import DROP_TICKS, HANDOVER_TICKS, PICK_TICKS, ActionKind, IncidentKind
from selfrepair.team.result import ActRecord
from selfrepair.team.state import Entry, RobotState, TeamWorld
from selfrepair.team.strategies import TeamRepairer

__all__ = ["finish", "handover", "pick_or_drop", "start_act"]


def pick_or_drop(
    world: TeamWorld, repairer: TeamRepairer, robot: RobotState, head: Entry, t: int
) -> int | None:
    action = head.action
    state = world.items[action.item]
    if state.settled or (action.kind is ActionKind.DROP and robot.holding != action.item):
        robot.queue.popleft()  # settled, or nothing to drop: the item went another way
        return None
    if not robot.can_grip:
        incident(world, repairer, robot, head, IncidentKind.GRIPPER, t)
        return None
    if action.kind is ActionKind.PICK and (
        robot.holding or state.holder or state.cell != robot.pose.cell
    ):
        return t + world.scale  # the item is not here (yet)
    ticks = PICK_TICKS if action.kind is ActionKind.PICK else DROP_TICKS
    start_act(world, (robot,), head, t + ticks * world.scale)
    return None


def handover(
    world: TeamWorld, repairer: TeamRepairer, robot: RobotState, head: Entry, t: int
) -> int | None:
    action = head.action
    if world.items[action.item].settled:
        robot.queue.popleft()
        return None
    giver, taker = world.robots[action.robot], world.robots[action.taker]
    if robot is taker and not taker.can_grip:
        incident(world, repairer, robot, head, IncidentKind.GRIPPER, t)
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
    start_act(world, (giver, taker), head, t + HANDOVER_TICKS * world.scale)
    world.dirty.add(other.name)
    return None


def start_act(world: TeamWorld, robots: tuple[RobotState, ...], head: Entry, end: int) -> None:
    t = world.now
    for robot in robots:
        if robot.drive is not None:
            robot.drive = None
        robot.queue.popleft()
        robot.busy_until, robot.footprint, robot.pending = end, (), head.action
    world.acts.append(ActRecord(t, end, head.action, tuple(r.pose.cell for r in robots)))
    world.last_progress = t


def finish(world: TeamWorld, robot: RobotState, t: int) -> None:
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
