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
   decides (:mod:`selfrepair.team.strategies`; started once for the mission, as a robot's
   repairer is, so it may keep state between incidents). The repair latency runs from the
   incident until every robot whose plan changed and is not in the middle of an action has its
   next drive placed in time (garbage collection is held off during it; each mission starts
   without kept cost-to-go maps, so a repair's cost does not depend on the missions run before
   it in the process).
5. **A changing world.** The scenario's world events (:mod:`selfrepair.world.events`) are
   applied by every robot's simulator (the one schedule); each robot senses them as a single
   robot does (by range: before it plans a drive, before every command and when the world
   changes while it rests; or by bumping into them) and the team shares what they see
   (:func:`~selfrepair.team.moves.tell`). A next primitive that sweeps a cell believed blocked
   goes to the robot's stepper (its strategy's detour or replan); when that fails, a
   ``blocked`` incident goes to the team strategy, which plans on a known map with the cells.
   A mission does not stall while a world event is still to come.
6. **End.** When every item is delivered; when nothing more can happen (``stalled``: no robot
   with work can act, no fault will clear, nothing moved for :data:`STALL_TICKS`); or at
   ``max_ticks``.
"""

from __future__ import annotations

import time
from collections import deque

from selfrepair.errors import ProblemError
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.simulator import Simulator
from selfrepair.geometry import Cell
from selfrepair.repair.strategies import StrategyName
from selfrepair.search.backend import use_numba
from selfrepair.team.acts import finish, handover, pick_or_drop
from selfrepair.team.allocation import Job, Worker, allocate, distance_maps, job_plan
from selfrepair.team.driving import cancel_drive
from selfrepair.team.faults import fault_times, faults_due
from selfrepair.team.model import ActionKind, TeamScenario, Trigger
from selfrepair.team.moves import drive_once, look
from selfrepair.team.reservations import FOREVER
from selfrepair.team.result import TeamOptions, TeamResult, TeamStatus
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
)
from selfrepair.team.strategies import TeamRepairer, get_team_strategy
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
    repairer = get_team_strategy(options.strategy)(world)  # once per mission, as for a robot
    status, reason = _loop(world, repairer)
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
        sim = Simulator(
            scenario.domain, scenario.maze, r.start, detection, options.seed, clock,
            world=scenario.world or None,
        )  # fmt: skip
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


def _loop(world: TeamWorld, repairer: TeamRepairer) -> tuple[TeamStatus, str]:
    scenario, scale = world.scenario, world.scale
    limit = (world.options.max_ticks or default_max_ticks(scenario)) * scale
    clocks = world.faults
    changed = {e.at * scale for e in scenario.world.events}  # the world changes then
    changes = sorted(changed)
    wake = {name: 0 for name in world.robots}
    t = forgotten = 0
    while True:
        world.now = t
        faults_due(world, clocks, t)
        if t in changed:  # the world changes: every robot at rest sees it (range sensing)
            for robot in world.robots.values():
                if robot.sim.units <= t:
                    look(world, robot, t)
        pending = list(world.robots)
        for _ in range(_ROUNDS):
            world.dirty.clear()
            for name in pending:
                wake[name] = _advance(world, repairer, world.robots[name], t)
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
        upcoming += [u for u in changes if u > t]
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


def _advance(world: TeamWorld, repairer: TeamRepairer, robot: RobotState, t: int) -> int:
    """Let ``robot`` do what it can at ``t`` (``repairer``: the team strategy); returns when it
    wants to act next."""
    for _ in range(_STEPS):
        if robot.busy_until > t:
            return robot.busy_until
        if robot.pending is not None:
            finish(world, robot, t)
        if not robot.queue:
            if robot.drive is not None:
                cancel_drive(world, robot, t)
            return FOREVER
        if robot.retry_at > t:
            return robot.retry_at
        head = robot.queue[0]
        kind = head.action.kind
        if kind is ActionKind.DRIVE:
            wait = drive_once(world, repairer, robot, head, t)
        elif kind is ActionKind.HANDOVER:
            wait = handover(world, repairer, robot, head, t)
        else:
            wait = pick_or_drop(world, repairer, robot, head, t)
        if wait is not None:
            return wait
    return t + 1
