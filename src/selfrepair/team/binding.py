"""Binding a team-table candidate to robots and cells, checking it is valid, and splicing it in.

A candidate (:class:`~selfrepair.team.table.Template`) is **valid** for an incident when, bound
to the robot with the incident (``r1``), a teammate (``r2``) and the cells of its places
(:func:`bind`), the paper's three conditions hold, lifted to higher-level actions:

1. *healthy*: every action is healthy for the robot that does it - a drive needs a robot the team
   does not believe stuck and that has some motion left under its known wheel faults; a pick, a
   drop or taking in a handover needs a working gripper (robots without one never qualify). The
   actions ``r1`` keeps for the same task after a partial replacement must be healthy too;
2. *executable where it is used*: every drive's goal is a free cell of the known map that the
   robot can reach from where it will be (grid distance on the known map: known walls, blocked
   cells met so far, robots believed stuck); a pick finds the item on the robot's cell; a drop
   happens at the drop-off; a handover's robots stand on adjacent cells, the giver holding the
   item;
3. *not being replaced*: no action of the bound candidate is the failing action or one the
   failing action is itself helping to replace (the entry's guard), and replacements nest at
   most ``max_depth`` deep.

These are the replacement core's three conditions (:mod:`selfrepair.repair.core`), and the test
is the core's: :func:`~selfrepair.repair.core.walk` over the team's steps
(:class:`~selfrepair.team.steps.TeamSteps`, the team's lifted world), with the guard carried by
the queue entries. A team replacement that meets a failing action later is replaced when it is
met, with the guard extended, as a deferred action of the core's ``primitive`` mode is; the guard's
size is the nesting depth, bounded by ``max_depth`` as in ``guarded`` mode. The table is the core's
:class:`~selfrepair.repair.core.CandidateTable` too: candidates by the failing action's kind and
what is known to be wrong (the incident and the load).

The teammate must be free or pre-emptible: a robot that carries another item first finishes
that delivery (the candidate goes in after its drop; it is *pre-empted* after it), one that
carries nothing is pre-empted at once. The binding states the cost: ``cost`` estimates when the
candidate is done (ticks from now: one per grid cell, plus the acts), ``preemption_ticks`` how
long the teammate's own work is put off. :func:`choose` takes, for the first candidate in table
order that has a valid binding, the teammate with the lowest ``cost``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from selfrepair.geometry import Cell
from selfrepair.repair.core import CandidateTable, walk
from selfrepair.team.model import (
    DROP_TICKS,
    ActionKind,
    TeamAction,
)
from selfrepair.team.result import TeamSource
from selfrepair.team.state import Entry, RobotState, TeamWorld, resource
from selfrepair.team.steps import Incident, Maps, TeamSteps, Where, mobile
from selfrepair.team.table import Known, Scope, Template

__all__ = [
    "Binding",
    "Incident",
    "Maps",
    "TeamSteps",
    "Where",
    "apply_binding",
    "bind",
    "choose",
    "strip_item",
]


@dataclass(frozen=True, slots=True)
class Binding:
    """A valid candidate bound to robots and cells (see the module docstring)."""

    template: Template
    helper: str
    actions: tuple[tuple[str, tuple[TeamAction, ...]], ...]
    insert_at: int
    cost: int
    preempted: bool
    preemption_ticks: int


def _insertion(robot: RobotState, item: str) -> tuple[int, Cell, int] | None:
    """Where a candidate goes into a teammate's queue: at once when it carries nothing (or the
    incident's item), else after it has got rid of what it carries; with the cell it will be
    on then and the estimated ticks until then. ``None`` when it would never be free."""
    load = robot.load
    if not load or load == item:
        return 0, robot.pose.cell, 0
    here, ticks = robot.pose.cell, 0
    for index, entry in enumerate(robot.queue):
        a = entry.action
        if a.kind is ActionKind.DRIVE and a.robot == robot.name:
            assert a.source is not None and a.target is not None
            ticks += abs(a.source[0] - a.target[0]) + abs(a.source[1] - a.target[1])
            here = a.target
        if a.item == load and (
            (a.kind is ActionKind.DROP) or (a.kind is ActionKind.HANDOVER and a.robot == robot.name)
        ):
            return index + 1, here, ticks + DROP_TICKS
    return None


def bind(
    world: TeamWorld, incident: Incident, template: Template, helper: str, maps: Maps
) -> Binding | None:
    """``template`` bound to the incident's robot and teammate ``helper`` (empty: none), or
    ``None`` when it is not valid (see the module docstring)."""
    r1 = world.robots[incident.robot]
    r2 = world.robots[helper] if helper else None
    if template.needs_helper != (r2 is not None) or r2 is r1:
        return None
    insert_at, start2, wait2 = 0, r1.pose.cell, 0
    if r2 is not None:
        slot = _insertion(r2, incident.item)
        if slot is None:
            return None
        insert_at, start2, wait2 = slot
    state = world.items[incident.item] if incident.item else None
    carrier = world.carrier(incident.item) if incident.item else ""
    steps = TeamSteps(world, incident, maps, r1, r2)
    start = Where(
        (r1.pose.cell, start2),
        (0, wait2),
        carrier,
        state.cell if state is not None and not carrier else None,
    )
    walked = walk(steps, template.steps, start, incident.entry.guard | {incident.entry.action})
    if walked is None or not steps.complete(template.scope, walked[1]):
        return None
    end = walked[1]
    if not _rest_healthy(world, r1, incident, template.scope):
        return None
    cost = max(end.clock)
    own = bool(r2 is not None and (r2.queue or r2.load))
    actions: tuple[tuple[str, tuple[TeamAction, ...]], ...] = ((r1.name, end.plans[0]),)
    if r2 is not None:
        actions += ((r2.name, end.plans[1]),)
    work = end.clock[1] - wait2 if r2 is not None else 0
    return Binding(template, helper, actions, insert_at, cost, own, work if own else 0)


def _rest_healthy(world: TeamWorld, r1: RobotState, incident: Incident, scope: Scope) -> bool:
    """Whether what ``r1`` keeps of the task after a partial replacement is healthy for it."""
    if scope is Scope.TASK or not incident.item:
        return True
    kept = list(r1.queue)[1:]
    if scope is Scope.FETCH:
        index = next((i for i, e in enumerate(kept) if e.action.item == incident.item), None)
        kept = kept[index + 1 :] if index is not None else kept
    for entry in kept:
        a = entry.action
        if a.kind is ActionKind.DRIVE and not mobile(world, r1):
            return False
        if a.kind in (ActionKind.PICK, ActionKind.DROP) and not r1.can_grip:
            return False
        if a.item == incident.item and a.kind is ActionKind.DROP:
            break
    return True


def choose(
    world: TeamWorld, incident: Incident, table: CandidateTable[ActionKind, Known, Template]
) -> Binding | None:
    """The first candidate of ``table`` for the incident with a valid binding, with the
    teammate that finishes it soonest (see the module docstring)."""
    if len(incident.entry.guard) >= world.options.max_depth:
        return None
    maps = Maps(world.known_map(incident.robot), world.options.backend)
    handover_giver = (
        incident.entry.action.robot if incident.entry.action.kind is ActionKind.HANDOVER else ""
    )
    for template in table.candidates(incident.entry.action.kind, incident.known):
        if not template.needs_helper:
            helpers = [""]
        elif handover_giver:
            helpers = [handover_giver]
        else:
            helpers = [name for name in world.robots if name != incident.robot]
        bindings = [b for h in helpers if (b := bind(world, incident, template, h, maps))]
        if bindings:
            return min(
                bindings,
                key=lambda b: (b.cost, list(world.robots).index(b.helper) if b.helper else 0),
            )
    return None


# --- splicing -------------------------------------------------------------------------------------


def strip_item(robot: RobotState, item: str, *, keep_head: bool = False) -> bool:
    """Remove every queued action about ``item`` from ``robot``'s queue, with the drive that
    leads to each; returns whether anything was removed."""
    entries = list(robot.queue)
    drop_at: set[int] = set()
    for i, entry in enumerate(entries):
        if entry.action.item == item:
            drop_at.add(i)
            if i > 0 and entries[i - 1].action.kind is ActionKind.DRIVE:
                drop_at.add(i - 1)
    if keep_head:
        drop_at.discard(0)
    robot.queue = deque(e for i, e in enumerate(entries) if i not in drop_at)
    return bool(drop_at)


def apply_binding(world: TeamWorld, incident: Incident, binding: Binding) -> set[str]:
    """Splice ``binding`` into the queues (see :class:`~selfrepair.team.table.Scope`); returns
    the robots whose queues changed."""
    r1 = world.robots[incident.robot]
    failing = incident.entry.action
    guard = incident.entry.guard | {failing}
    changed = {r1.name}
    scope = binding.template.scope
    if scope is Scope.TASK:
        for robot in world.robots.values():
            if strip_item(robot, incident.item):
                changed.add(robot.name)
        if r1.queue and r1.queue[0] is incident.entry:
            r1.queue.popleft()
    elif scope is Scope.FETCH:
        while r1.queue:
            entry = r1.queue.popleft()
            a = entry.action
            if a.item == incident.item and a.kind in (ActionKind.PICK, ActionKind.HANDOVER):
                break
    elif r1.queue and r1.queue[0] is incident.entry:
        r1.queue.popleft()
    for name, actions in binding.actions:
        robot = world.robots[name]
        new = [Entry(a, TeamSource.TEAM_REPLACEMENT, guard) for a in actions]
        at = 0 if name == r1.name else binding.insert_at
        at = min(at, len(robot.queue))
        robot.queue = deque([*list(robot.queue)[:at], *new, *list(robot.queue)[at:]])
        changed.add(name)
    for name in world.robots:  # scenario order, never a set's (hash-seed) order
        if name in changed:
            resource(world.robots[name])
    return changed
