"""Carrying out ``drive(robot, a -> b)`` with the single-robot machinery, in a shared maze.

A drive starts (:func:`begin_drive`) the way a single-robot mission does: the robot's own
:class:`~selfrepair.repair.strategies.MissionContext` is built by
:func:`selfrepair.execution.context.mission_context` on the *known* map, the lattice planner
(``context.plan``) plans with the robot's known wheel faults, and the robot's single-robot
strategy is started from its factory (the strategy lifecycle); plan, strategy and known faults
go into a :class:`~selfrepair.execution.stepper.Stepper`, the single-robot executor's own loop.
The plan is then placed in time around the other robots (:func:`place`:
:func:`~selfrepair.team.spacetime.schedule_path`, else cooperative A*, whose plan replaces the
stepper's queue), and its cells are reserved.

When the next primitive action is faulty under the faults the robot knows, :func:`own_repair` asks
the stepper, which asks the robot's own repairer (its replacement table, then its replan) and
splices the repair in, exactly as in a single-robot mission; the repaired plan is placed again. Only
when that fails does the team hear of it (a ``stuck`` incident). A robot that cannot be placed waits
on its cell and tries again later; idle robots standing on its path are asked to make room
(:func:`make_room`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from enum import StrEnum
from types import MappingProxyType

from selfrepair.execution.context import mission_context, start_repairer
from selfrepair.execution.result import MissionSpec, StepSource
from selfrepair.execution.stepper import Stepper, splice
from selfrepair.geometry import Cell
from selfrepair.repair.strategies import StrategyOptions, uses_table
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import bfs_distances, planning_actions
from selfrepair.team.model import IncidentKind
from selfrepair.team.model import drive as drive_action
from selfrepair.team.reservations import TimedStep
from selfrepair.team.result import OwnRepairRecord, TeamSource
from selfrepair.team.robottable import robot_table
from selfrepair.team.scenario import grid_distances
from selfrepair.team.spacetime import cost_to_go, lattice_of, plan_spacetime, schedule_path
from selfrepair.team.state import Drive, Entry, RobotState, TeamWorld

__all__ = [
    "RETRY_TICKS",
    "DriveStart",
    "begin_drive",
    "cancel_drive",
    "make_room",
    "own_repair",
    "place",
]

RETRY_TICKS = 2
"""Ticks a robot that could not place its drive waits before it tries again (doubled after
each failure in a row, up to eight times)."""


class DriveStart(StrEnum):
    """How starting a drive went: placed in time, already there, waiting to try again, or an
    incident (the robot cannot move there / the target cannot be reached on the known map)."""

    PLACED = "placed"
    ARRIVED = "arrived"
    WAITING = "waiting"
    STUCK = "stuck"
    BLOCKED = "blocked"


INCIDENT_OF_START: Mapping[DriveStart, IncidentKind] = MappingProxyType(
    {DriveStart.STUCK: IncidentKind.STUCK, DriveStart.BLOCKED: IncidentKind.BLOCKED}
)
"""The incident a drive that could not start raises (an explicit mapping, never by value)."""


def cancel_drive(world: TeamWorld, robot: RobotState, at: int) -> None:
    """Stop ``robot``'s drive: it keeps its cell from ``at`` until it plans again."""
    robot.drive = None
    world.reservations.release_from(robot.name, at)
    world.reservations.park(robot.name, robot.pose.cell, at)
    mark_stale(world, robot)


def mark_stale(world: TeamWorld, robot: RobotState) -> None:
    """Robots whose plans now overlap ``robot``'s reservations must place their drives again."""
    for name in world.reservations.conflicting_robots(robot.name):
        world.robots[name].stale = True


def begin_drive(world: TeamWorld, robot: RobotState, entry: Entry, at: int) -> DriveStart:
    """Plan the drive of ``entry`` with the robot's own planner and place it (see the module
    docstring)."""
    target = entry.action.target
    assert target is not None
    if robot.pose.cell == target:
        return DriveStart.ARRIVED
    domain = world.scenario.domain
    if not planning_actions(domain, robot.faults):
        return DriveStart.STUCK
    options = world.options
    known = world.known_map(robot.name)
    x, y = robot.pose.cell
    if (
        not known.is_free(*target)
        or bfs_distances(known, target, backend=options.backend)[y, x] < 0
    ):
        return DriveStart.BLOCKED
    spec = MissionSpec(
        world.known_map(robot.name, events=False),  # world events: the robot's belief
        robot.pose,
        target,
        strategy=options.robot_strategy,
        options=StrategyOptions(
            table=robot_table(world.scenario, options), recursion=options.recursion
        ),
        backend=options.backend,
        domain=domain,
        world=world.scenario.world,
    )
    table = spec.options.resolved_table() if uses_table(options.robot_strategy) else None
    context = mission_context(spec, table)
    context.belief.blocked = world.seen
    result = context.plan(robot.pose, target, None, robot.faults, context.replan_budget)
    world.plans += 1
    world.expansions += result.expansions
    if result.status is not PlanStatus.SOLVED:
        return DriveStart.STUCK
    repairer = start_repairer(spec, context)
    stepper = Stepper(context, repairer, result.actions, robot.faults, robot.sim.table)
    robot.drive = Drive(entry, target, stepper, [])
    return DriveStart.PLACED if place(world, robot, at) else DriveStart.WAITING


def place(world: TeamWorld, robot: RobotState, at: int) -> bool:
    """Place the rest of ``robot``'s drive in time from ``at`` and reserve it; when neither way
    finds a placement, the robot keeps its cell and tries again after :data:`RETRY_TICKS`."""
    drive = robot.drive
    assert drive is not None
    robot.stale = False
    res, domain, scale = world.reservations, world.scenario.domain, world.scale
    res.release_from(robot.name, at)
    known = world.known_map(robot.name, events=False)  # the stepper avoids what it sees
    actions = drive.actions()
    steps = schedule_path(
        res, robot.name, domain, scale, known, robot.pose, at, actions,
        max_wait=world.options.max_wait_ticks * scale,
    )  # fmt: skip
    if steps is None:
        found, _ = _cooperative(world, robot, drive.target, at)
        if found is not None:
            steps = found
            queue = drive.stepper.queue
            splice(queue, len(queue), [a.action for a in found], StepSource.REPLAN)
    if steps is None:
        res.park(robot.name, robot.pose.cell, at)
        mark_stale(world, robot)
        robot.failures += 1
        robot.retry_at = at + RETRY_TICKS * scale * min(8, 2 ** (robot.failures - 1))
        drive.steps = []
        make_room(world, robot, at)
        return False
    robot.failures = 0
    drive.steps = list(steps)
    end = steps[-1].after if steps else robot.pose
    res.reserve_path(robot.name, steps, end, steps[-1].end if steps else at)
    return True


def _cooperative(
    world: TeamWorld, robot: RobotState, target: Cell, at: int
) -> tuple[tuple[TimedStep, ...] | None, int]:
    """Cooperative A* for ``robot`` to ``target`` from ``at``; skipped (``None``: wait and try
    again) when the cells that robots hold until they plan again - now or from some time on -
    wall the target off (A* would search the whole space-time horizon in vain)."""
    res, domain, scale = world.reservations, world.scenario.domain, world.scale
    extra = world.known_extra(robot.name)
    lattice = lattice_of(world.scenario.maze, domain, planning_actions(domain, robot.faults), scale)
    rest = lattice.cost(cost_to_go(lattice, extra, target), robot.pose)
    parked = res.parked(robot.name)
    if rest is None or target in parked:
        return None, 0
    if robot.pose.cell not in grid_distances(
        world.known_map(robot.name), target, frozenset(parked)
    ):
        return None, 0
    found, expanded = plan_spacetime(
        res, robot.name, lattice, extra, robot.pose, at, target,
        wait=scale, horizon=3 * rest + 40 * scale,
        max_expansions=world.options.spacetime_expansions,
    )  # fmt: skip
    world.plans += 1
    world.expansions += expanded
    return found, expanded


def own_repair(world: TeamWorld, robot: RobotState, at: int) -> bool:
    """The robot's own repair of its faulty next primitive: its stepper repairs and splices (the
    single-robot loop); the repaired plan is placed. ``False`` when the robot's strategy found
    nothing (or no motion is left under its known faults)."""
    drive = robot.drive
    assert drive is not None
    if not planning_actions(world.scenario.domain, robot.faults):
        return False
    stepper = drive.stepper
    before = len(stepper.repairs)
    entry = stepper.next_action(robot.pose, robot.sim.steps)
    for record in stepper.repairs[before:]:
        repair = record.repair
        world.plans += repair.replans
        world.expansions += repair.expansions
        world.own_repairs.append(
            OwnRepairRecord(
                at, robot.name, record.pose, record.action, repair.status, repair.source,
                repair.actions, record.latency_ns,
            )
        )  # fmt: skip
    if entry is None:
        return False
    place(world, robot, at)
    return True


def make_room(world: TeamWorld, robot: RobotState, at: int) -> None:
    """Ask idle robots that stand on ``robot``'s planned path to drive to the nearest cell off
    it (each such request is one message and one yield)."""
    drive = robot.drive
    if drive is None:
        return
    domain = world.scenario.domain
    path: set[Cell] = {robot.pose.cell, drive.target}
    pose = robot.pose
    for action in drive.actions():
        path.update(domain.footprint(pose, action))
        pose = domain.apply(pose, action)
    known = world.known_map()
    taken = {r.pose.cell for r in world.robots.values()}
    for other in world.robots.values():
        if other is robot or other.queue or other.busy_until > at or other.stuck:
            continue
        if other.pose.cell not in path or not planning_actions(domain, other.faults):
            continue
        distances = grid_distances(known, other.pose.cell)
        spots = sorted(
            (d, c) for c, d in distances.items() if c not in path and c not in taken and d > 0
        )
        if not spots:
            continue
        spot = spots[0][1]
        taken.add(spot)
        other.queue = deque(
            [Entry(drive_action(other.name, other.pose.cell, spot), TeamSource.YIELD)]
        )
        other.retry_at = 0
        world.yields += 1
        world.messages += 1
