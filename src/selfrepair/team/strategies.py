"""Team strategies: what the team does when a robot's next higher-level action cannot go on.

The team strategies live in the one strategy registry
(:mod:`selfrepair.repair.strategies.registry`), next to the robot strategies, as entries of the
team kind (:data:`TEAM`): a factory started with the running :class:`TeamWorld` gives a
:class:`~selfrepair.repair.strategies.Repairer` asked about each :class:`Incident`. The built-in
ones keep no state (each is a plain function ``(world, incident) -> Decision`` wrapped by
:func:`~selfrepair.repair.strategies.stateless`): the repairer changes robots' queues in the world
and says what it did; the engine (:mod:`selfrepair.team.engine`) times it, places the changed
robots' next drives in time and records the repair.

``team-replacement``
    Look the incident up in the team replacement table and splice in the first valid candidate,
    bound to the teammate that finishes it soonest (:func:`selfrepair.team.binding.choose`);
    when no candidate is valid, fall back to ``reallocation``.
``reallocation``
    Re-assign every open task (items lying somewhere, items carried by robots that can no longer
    deliver them) to every robot that can still carry (:func:`selfrepair.team.allocation.allocate`)
    and give every robot a new plan: every robot is disturbed, every robot with a drive plans it
    again.
``alone``
    No teamwork: a robot whose drive met a blocked cell plans its own drive again on the known
    map (when the target can still be reached), anything else waits for the fault to clear and
    tries again. The tasks of a robot that stays dead are never delivered.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from selfrepair.geometry import Cell
from selfrepair.repair.strategies import (
    Kind,
    MissionKind,
    Repairer,
    StrategyEntry,
    StrategyName,
    register,
    stateless,
    strategy_for,
)
from selfrepair.search.lattice import bfs_distances
from selfrepair.team.allocation import (
    DistanceMap,
    Job,
    Worker,
    allocate,
    distance_maps,
    job_plan,
)
from selfrepair.team.binding import apply_binding, choose
from selfrepair.team.driving import RETRY_TICKS
from selfrepair.team.model import (
    DROP_TICKS,
    IncidentKind,
    TeamAction,
    drive,
    drop,
    handover,
)
from selfrepair.team.result import RepairOutcome, TeamSource
from selfrepair.team.state import Entry, RobotState, TeamWorld, resource
from selfrepair.team.steps import Incident, Maps, mobile
from selfrepair.team.table import get_team_table

__all__ = ["TEAM", "Decision", "TeamRepairer", "TeamStrategy", "get_team_strategy"]


@dataclass(frozen=True, slots=True)
class Decision:
    """What a team strategy did: the outcome and source, the robots whose queues changed, the
    candidate and teammate (team replacement), the stated pre-emption cost, the actions inserted
    per robot, the items no robot was given, and the messages it sent."""

    outcome: RepairOutcome
    source: TeamSource
    changed: frozenset[str] = frozenset()
    candidate: str = ""
    helper: str = ""
    preempted: bool = False
    preemption_ticks: int = 0
    changes: tuple[tuple[str, tuple[TeamAction, ...]], ...] = ()
    lost: tuple[str, ...] = ()
    messages: int = 0



def team_replacement(world: TeamWorld, incident: Incident) -> Decision:
    """The first valid team-table candidate, else :func:`reallocation`."""
    binding = choose(world, incident, get_team_table(world.options.table))
    if binding is None:
        return reallocation(world, incident)
    changed = apply_binding(world, incident, binding)
    teammates = changed - {incident.robot}
    return Decision(
        RepairOutcome.REPAIRED,
        TeamSource.TEAM_REPLACEMENT,
        frozenset(changed),
        binding.template.name,
        binding.helper,
        binding.preempted,
        binding.preemption_ticks,
        binding.actions,
        messages=2 * len(teammates),  # a request and its acknowledgement per teammate
    )


def reallocation(world: TeamWorld, incident: Incident) -> Decision:
    """Re-assign every open task and give every robot a new plan."""
    known = world.known_map()
    capable = {n: r for n, r in world.robots.items() if r.can_grip and mobile(world, r)}
    jobs: list[Job] = []
    first: dict[str, Job] = {}
    for item in world.open_items():
        state, task = world.items[item], world.scenario.task(item)
        carrier = world.carrier(item)
        if carrier:
            holder = world.robots[carrier]
            if holder.name in capable:
                first[holder.name] = Job(item, holder.pose.cell, task.dropoff)
            else:
                jobs.append(Job(item, holder.pose.cell, task.dropoff, holder.name))
        else:
            assert state.cell is not None
            jobs.append(Job(item, state.cell, task.dropoff))
    backend = world.options.backend
    cells = [j.source for j in jobs if not j.holder] + [j.dropoff for j in (*jobs, *first.values())]
    maps = distance_maps(known, cells, backend=backend)
    for job in jobs:
        if job.holder:  # distances to a stuck carrier's cell, on a map where it is free
            maps[job.source] = bfs_distances(
                world.known_map(job.holder), job.source, backend=backend
            )
    workers = [_worker(world, r, first.get(n), maps) for n, r in capable.items()]
    order, left = allocate(workers, jobs, maps)
    spots = Maps(known, world.options.backend)
    plans: dict[str, list[TeamAction]] = {n: [] for n in world.robots}
    for name, robot in capable.items():
        here = robot.pose.cell
        if name in first:
            job = first[name]
            if job.dropoff != here:
                plans[name].append(drive(name, here, job.dropoff))
            plans[name].append(drop(name, job.item))
            here = job.dropoff
        plans[name] += job_plan(
            name, here, order[name], lambda job, at: _spot(spots, job.source, at)
        )
    for name, assigned in order.items():
        for job in assigned:
            if job.holder:
                plans[job.holder].append(handover(job.holder, name, job.item))
    changed = _install(world, plans, TeamSource.REALLOCATION)
    return Decision(
        RepairOutcome.REPAIRED,
        TeamSource.REALLOCATION,
        frozenset(changed | {incident.robot}),
        changes=tuple((n, tuple(p)) for n, p in plans.items() if n in changed),
        lost=tuple(j.item for j in left),
        messages=len(world.robots) - 1,
    )


def _worker(
    world: TeamWorld, robot: RobotState, carried: Job | None, maps: Mapping[Cell, DistanceMap]
) -> Worker:
    """A capable robot as the allocation sees it: free after its act in progress and after
    delivering what it carries."""
    busy = max(0, robot.busy_until - world.now) // world.scale
    if carried is None:
        return Worker(robot.name, robot.pose.cell, busy)
    x, y = robot.pose.cell
    distance = int(maps[carried.dropoff][y, x])
    return Worker(robot.name, carried.dropoff, busy + max(distance, 0) + DROP_TICKS)


def _spot(maps: Maps, holder: Cell, here: Cell) -> Cell:
    """The free cell next to ``holder`` nearest to ``here`` (for a handover from a carrier that
    cannot deliver), or the holder's cell itself when none can be reached."""
    x, y = holder
    sides = [(x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y)]
    options = [(d, c) for c in sides if (d := maps.distance(here, c)) >= 0]
    return min(options)[1] if options else holder


def _install(world: TeamWorld, plans: dict[str, list[TeamAction]], source: TeamSource) -> set[str]:
    """Replace every robot's queue by its new plan; returns the robots whose queue changed."""
    changed: set[str] = set()
    for name, actions in plans.items():
        robot = world.robots[name]
        if [e.action for e in robot.queue] != actions:
            robot.queue = deque(Entry(a, source) for a in actions)
            resource(robot)
            robot.deferred = None
            changed.add(name)
    return changed


def alone(world: TeamWorld, incident: Incident) -> Decision:
    """The robot deals with it by itself: plan its own drive again around a blocked cell, or
    wait and try again."""
    robot = world.robots[incident.robot]
    target = incident.entry.action.target
    if incident.kind is IncidentKind.BLOCKED and target is not None and mobile(world, robot):
        x, y = robot.pose.cell
        grid = bfs_distances(world.known_map(), target, backend=world.options.backend)
        if world.known_map().is_free(*target) and grid[y, x] >= 0:
            return Decision(RepairOutcome.REPAIRED, TeamSource.ALONE, frozenset({robot.name}))
    robot.retry_at = world.now + RETRY_TICKS * world.scale
    robot.deferred = (incident.entry.action, incident.kind.value)
    return Decision(RepairOutcome.DEFERRED, TeamSource.ALONE)


TEAM: Kind[TeamWorld, Incident, Decision] = Kind(MissionKind.TEAM)
"""A team's mission: its strategies start with the running :class:`TeamWorld`, are asked about
an :class:`Incident` and answer a :class:`Decision`."""

TeamRepairer = Repairer[Incident, Decision]
"""A team strategy started for one mission: asked about each incident, it may keep state between
them (the strategy lifecycle, as a robot's repairer)."""

TeamStrategy = Callable[[TeamWorld], TeamRepairer]
"""A team strategy's factory: started with the team's world, it answers incidents (changing the
world's queues) with decisions."""

for _name, _fn in (
    (StrategyName.TEAM_REPLACEMENT, team_replacement),
    (StrategyName.REALLOCATION, reallocation),
    (StrategyName.ALONE, alone),
):
    register(StrategyEntry(_name, TEAM, stateless(_fn), _name is StrategyName.TEAM_REPLACEMENT))


def get_team_strategy(name: str) -> TeamStrategy:
    """The factory of team strategy ``name`` (unknown names raise ``ProblemError``)."""
    return strategy_for(name, TEAM)
