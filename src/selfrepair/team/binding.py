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

The teammate must be free or pre-emptible: a robot that carries another item first finishes
that delivery (the candidate goes in after its drop; it is *pre-empted* after it), one that
carries nothing is pre-empted at once. The binding states the cost: ``cost`` estimates when the
candidate is done (ticks from now: one per grid cell, plus the acts), ``preemption_ticks`` how
long the teammate's own work is put off. :func:`choose` takes, for the first candidate in table
order that has a valid binding, the teammate with the lowest ``cost``.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from selfrepair.geometry import Cell
from selfrepair.search.lattice import bfs_distances, planning_actions
from selfrepair.team.model import (
    DROP_TICKS,
    HANDOVER_TICKS,
    PICK_TICKS,
    ActionKind,
    IncidentKind,
    Load,
    TeamAction,
    drive,
    drop,
    handover,
    pick,
)
from selfrepair.team.result import TeamSource
from selfrepair.team.state import Entry, RobotState, TeamWorld, resource
from selfrepair.team.table import Key, Place, Role, Scope, TeamTable, Template
from selfrepair.world.maze import Maze

__all__ = ["Binding", "Incident", "Maps", "apply_binding", "bind", "choose", "strip_item"]

_SIDES = ((0, -1), (1, 0), (0, 1), (-1, 0))


@dataclass(frozen=True, slots=True)
class Incident:
    """A robot whose next action cannot go on: why, with what load, and the item concerned."""

    robot: str
    entry: Entry
    kind: IncidentKind
    load: Load
    item: str
    at: int

    @property
    def key(self) -> Key:
        """The team-table key of the incident."""
        return (self.entry.action.kind, self.kind, self.load)


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


class Maps:
    """Grid distances to cells on one known map, made on first use (for one repair)."""

    def __init__(self, maze: Maze, backend: str) -> None:
        self.maze, self.backend = maze, backend
        self._maps: dict[Cell, npt.NDArray[np.int32]] = {}

    def distance(self, source: Cell, target: Cell) -> int:
        """Grid steps from ``source`` to ``target`` (-1: not reachable or a wall)."""
        if not self.maze.is_free(*target) or not self.maze.is_free(*source):
            return -1
        grid = self._maps.get(target)
        if grid is None:
            grid = self._maps[target] = bfs_distances(self.maze, target, backend=self.backend)
        return int(grid[source[1], source[0]])

    def path(self, source: Cell, target: Cell) -> list[Cell]:
        """One shortest grid path from ``source`` to ``target`` (both included), or ``[]``."""
        if self.distance(source, target) < 0:
            return []
        grid = self._maps[target]
        cells = [source]
        while cells[-1] != target:
            x, y = cells[-1]
            here = int(grid[y, x])
            cells.append(
                next(
                    (x + dx, y + dy)
                    for dx, dy in _SIDES
                    if self.maze.is_free(x + dx, y + dy) and int(grid[y + dy, x + dx]) == here - 1
                )
            )
        return cells


def mobile(world: TeamWorld, robot: RobotState) -> bool:
    """Whether the team may give ``robot`` a drive."""
    return not robot.stuck and bool(planning_actions(world.scenario.domain, robot.faults))


# --- binding --------------------------------------------------------------------------------------


@dataclass(slots=True)
class _Binder:
    """The walk through one template with one teammate (see :func:`bind`)."""

    world: TeamWorld
    incident: Incident
    maps: Maps
    r1: RobotState
    r2: RobotState | None
    guard: frozenset[TeamAction]
    pos: dict[Role, Cell]
    clock: dict[Role, int]
    holder: str
    item_cell: Cell | None
    meet: tuple[Cell, Cell] | None = None
    next_cell: Cell | None = None

    def robot(self, role: Role) -> RobotState | None:
        return self.r1 if role is Role.FAULTY else self.r2

    def place(self, place: Place, role: Role) -> Cell | None:
        here = self.r1.pose.cell
        task = self.world.scenario.task(self.incident.item) if self.incident.item else None
        if place is Place.ITEM:
            return self.item_cell if not self.holder else None
        if place is Place.DROPOFF:
            return task.dropoff if task else None
        if place is Place.TARGET:
            return self.incident.entry.action.target
        if place is Place.HERE:
            return here
        if place is Place.NEXT:
            return self._next(here)
        if place is Place.AWAY:
            return self._away(here, task.dropoff if task else None)
        if place is Place.WAY:
            return self._waypoint(here)
        if place in (Place.MEET1, Place.MEET2):
            if self.meet is None:
                self.meet = self._meeting()
            if self.meet is None:
                return None
            return self.meet[0] if place is Place.MEET1 else self.meet[1]
        return None

    def _free_sides(self, cell: Cell) -> Iterator[Cell]:
        x, y = cell
        for dx, dy in _SIDES:
            if self.maps.maze.is_free(x + dx, y + dy):
                yield (x + dx, y + dy)

    def _next(self, here: Cell) -> Cell | None:
        if self.next_cell is None and self.r2 is not None:
            start = self.pos[Role.HELPER]
            options = [
                (d, c) for c in self._free_sides(here) if (d := self.maps.distance(start, c)) >= 0
            ]
            self.next_cell = min(options)[1] if options else None
        return self.next_cell

    def _away(self, here: Cell, dropoff: Cell | None) -> Cell | None:
        taken = {self.next_cell, dropoff, self.item_cell}
        return next((c for c in self._free_sides(here) if c not in taken), None)

    def _waypoint(self, here: Cell) -> Cell | None:
        target = self.incident.entry.action.target
        if target is None:
            return None
        path = self.maps.path(here, target)
        return path[len(path) // 2] if len(path) >= 3 else None

    def _meeting(self) -> tuple[Cell, Cell] | None:
        """Adjacent cells on a shortest path between the two robots, split so that neither
        waits long for the other."""
        path = self.maps.path(self.pos[Role.FAULTY], self.pos[Role.HELPER])
        if len(path) < 2:
            return None
        k = len(path) - 1
        c1, c2 = self.clock[Role.FAULTY], self.clock[Role.HELPER]
        best = min(range(k), key=lambda i: (max(c1 + i, c2 + k - i - 1), i))
        return path[best], path[best + 1]

    def run(self, template: Template) -> dict[Role, list[TeamAction]] | None:
        out: dict[Role, list[TeamAction]] = {Role.FAULTY: [], Role.HELPER: []}
        for step in template.steps:
            actions = self.step(step)
            if actions is None:
                return None
            for role, action in actions:
                if action in self.guard:
                    return None
                out[role].append(action)
        if not self._goal_reached(template.scope):
            return None
        return out

    def step(self, step: object) -> list[tuple[Role, TeamAction]] | None:
        from selfrepair.team.table import Step

        assert isinstance(step, Step)
        robot = self.robot(step.role)
        if robot is None:
            return None
        role, name, at = step.role, robot.name, self.pos[step.role]
        item = self.incident.item
        if step.kind is ActionKind.DRIVE:
            assert step.place is not None
            dest = self.place(step.place, role)
            if dest is None or not mobile(self.world, robot):
                return None
            if dest == at:
                return []
            distance = self.maps.distance(at, dest)
            if distance < 0 or dest == self.pos[_other(role)]:
                return None
            self.pos[role] = dest
            self.clock[role] += distance
            return [(role, drive(name, at, dest))]
        if step.kind is ActionKind.PICK:
            if not robot.can_grip or self.holder or self.item_cell != at:
                return None
            self.holder, self.clock[role] = name, self.clock[role] + PICK_TICKS
            return [(role, pick(name, item))]
        if step.kind is ActionKind.DROP:
            if not robot.can_grip or self.holder != name:
                return None
            self.holder, self.item_cell = "", at
            self.clock[role] += DROP_TICKS
            return [(role, drop(name, item))]
        assert step.other is not None
        taker = self.robot(step.other)
        if taker is None or self.holder != name or not taker.can_grip:
            return None
        if not _adjacent(at, self.pos[step.other]):
            return None
        done = max(self.clock[role], self.clock[step.other]) + HANDOVER_TICKS
        self.clock[role] = self.clock[step.other] = done
        self.holder = taker.name
        action = handover(name, taker.name, item)
        return [(role, action), (step.other, action)]

    def _goal_reached(self, scope: Scope) -> bool:
        task = self.world.scenario.task(self.incident.item) if self.incident.item else None
        if scope is Scope.TASK:
            return task is not None and not self.holder and self.item_cell == task.dropoff
        if scope is Scope.FETCH:
            return self.holder == self.r1.name
        return self.pos[Role.FAULTY] == self.incident.entry.action.target


def _other(role: Role) -> Role:
    return Role.HELPER if role is Role.FAULTY else Role.FAULTY


def _adjacent(a: Cell, b: Cell) -> bool:
    return abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1


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
    binder = _Binder(
        world,
        incident,
        maps,
        r1,
        r2,
        incident.entry.guard | {incident.entry.action},
        {Role.FAULTY: r1.pose.cell, Role.HELPER: start2},
        {Role.FAULTY: 0, Role.HELPER: wait2},
        carrier,
        state.cell if state is not None and not carrier else None,
    )
    out = binder.run(template)
    if out is None or not _rest_healthy(world, r1, incident, template.scope):
        return None
    cost = max(binder.clock.values())
    own = bool(r2 is not None and (r2.queue or r2.load))
    actions: tuple[tuple[str, tuple[TeamAction, ...]], ...] = ((r1.name, tuple(out[Role.FAULTY])),)
    if r2 is not None:
        actions += ((r2.name, tuple(out[Role.HELPER])),)
    work = binder.clock[Role.HELPER] - wait2 if r2 is not None else 0
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


def choose(world: TeamWorld, incident: Incident, table: TeamTable) -> Binding | None:
    """The first candidate of ``table`` for the incident with a valid binding, with the
    teammate that finishes it soonest (see the module docstring)."""
    if len(incident.entry.guard) >= world.options.max_depth:
        return None
    maps = Maps(world.known_map(incident.robot), world.options.backend)
    handover_giver = (
        incident.entry.action.robot if incident.entry.action.kind is ActionKind.HANDOVER else ""
    )
    for template in table.candidates(incident.key):
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
