"""A team table's steps as the replacement core walks them: the incident, the distances on the
known map, and :class:`TeamSteps`, the team's :class:`~selfrepair.repair.core.LiftedWorld`.

The validity of a bound candidate is the core's test (:func:`selfrepair.repair.core.walk`, the
same three conditions as for one robot's primitive actions, lifted to drive, pick, drop and
handover: see :mod:`selfrepair.team.binding`); this module says what each step needs and does.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace

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
from selfrepair.team.state import Entry, RobotState, TeamWorld
from selfrepair.team.table import Key, Known, Place, Role, Scope, Step
from selfrepair.world.maze import Maze

__all__ = ["Incident", "Maps", "TeamSteps", "Where", "adjacent", "mobile"]

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

    @property
    def known(self) -> Known:
        """What is known to be wrong: why the action failed, and the robot's load."""
        return (self.kind, self.load)


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


@dataclass(frozen=True, slots=True)
class Where:
    """Where a binding walk stands after some steps of a template: each role's cell and clock
    (ticks from now), who holds the item and where it lies otherwise, the meeting cells and the
    cell next to ``r1`` once chosen (chosen once per walk, when a step first needs them), and each
    role's bound actions so far. The state of :class:`TeamSteps` (immutable, as the core wants)."""

    pos: tuple[Cell, Cell]
    clock: tuple[int, int]
    holder: str
    item_cell: Cell | None
    meet: tuple[Cell, Cell] | None = None
    next_cell: Cell | None = None
    plans: tuple[tuple[TeamAction, ...], tuple[TeamAction, ...]] = ((), ())


def _i(role: Role) -> int:
    return 0 if role is Role.FAULTY else 1


@dataclass(frozen=True, slots=True)
class TeamSteps:
    """A team table's steps as the replacement core sees them
    (:class:`~selfrepair.repair.core.LiftedWorld`), for one incident and one teammate: the three
    conditions of the module docstring, lifted to higher-level actions. A step is healthy when
    the robot of its role exists and can do it (a drive: mobile; a pick or drop: a working
    gripper; a handover: a taker with one); it is executable from a :class:`Where` when its place
    binds to a reachable free cell, the item is where the step needs it and a handover's robots
    stand side by side; it binds to the team actions it puts in the queues."""

    world: TeamWorld
    incident: Incident
    maps: Maps
    r1: RobotState
    r2: RobotState | None

    def robot(self, role: Role) -> RobotState | None:
        """The robot that plays ``role``."""
        return self.r1 if role is Role.FAULTY else self.r2

    def healthy(self, step: Step, where: Where) -> bool:
        """Condition 1 for ``step``."""
        robot = self.robot(step.role)
        if robot is None:
            return False
        if step.kind is ActionKind.DRIVE:
            return mobile(self.world, robot)
        if step.kind is ActionKind.HANDOVER:
            assert step.other is not None
            taker = self.robot(step.other)
            return taker is not None and taker.can_grip
        return robot.can_grip

    def advance(self, step: Step, where: Where) -> tuple[tuple[TeamAction, ...], Where] | None:
        """Condition 2 for the healthy ``step`` at ``where``: its actions and where it leads."""
        robot = self.robot(step.role)
        assert robot is not None
        role, name = step.role, robot.name
        at = where.pos[_i(role)]
        item = self.incident.item
        if step.kind is ActionKind.DRIVE:
            assert step.place is not None
            dest, where = self._place(step.place, where)
            if dest is None:
                return None
            if dest == at:
                return (), where
            distance = self.maps.distance(at, dest)
            if distance < 0 or dest == where.pos[1 - _i(role)]:
                return None
            action = drive(name, at, dest)
            return (action,), _moved(where, role, dest, distance, action)
        if step.kind is ActionKind.PICK:
            if where.holder or where.item_cell != at:
                return None
            action = pick(name, item)
            return (action,), _acted(replace(where, holder=name), role, PICK_TICKS, action)
        if step.kind is ActionKind.DROP:
            if where.holder != name:
                return None
            action = drop(name, item)
            dropped = replace(where, holder="", item_cell=at)
            return (action,), _acted(dropped, role, DROP_TICKS, action)
        assert step.other is not None
        taker = self.robot(step.other)
        assert taker is not None
        if where.holder != name or not adjacent(at, where.pos[_i(step.other)]):
            return None
        done = max(where.clock) + HANDOVER_TICKS
        action = handover(name, taker.name, item)
        plans = list(where.plans)
        plans[_i(role)] += (action,)
        plans[_i(step.other)] += (action,)
        return (action,), replace(
            where, clock=(done, done), holder=taker.name, plans=(plans[0], plans[1])
        )

    def complete(self, scope: Scope, where: Where) -> bool:
        """Whether the walk reached what the template's scope replaces: the item delivered
        (``task``), the item in ``r1``'s hands (``fetch``), ``r1`` at the failing drive's target
        (``action``)."""
        task = self.world.scenario.task(self.incident.item) if self.incident.item else None
        if scope is Scope.TASK:
            return task is not None and not where.holder and where.item_cell == task.dropoff
        if scope is Scope.FETCH:
            return where.holder == self.r1.name
        return where.pos[0] == self.incident.entry.action.target

    def _place(self, place: Place, where: Where) -> tuple[Cell | None, Where]:
        """The cell ``place`` binds to at ``where`` (``None``: none), and ``where`` with the
        meeting cells or the cell next to ``r1`` once chosen."""
        here = self.r1.pose.cell
        task = self.world.scenario.task(self.incident.item) if self.incident.item else None
        if place is Place.ITEM:
            return (where.item_cell if not where.holder else None), where
        if place is Place.DROPOFF:
            return (task.dropoff if task else None), where
        if place is Place.TARGET:
            return self.incident.entry.action.target, where
        if place is Place.HERE:
            return here, where
        if place is Place.NEXT:
            where = self._next(here, where)
            return where.next_cell, where
        if place is Place.AWAY:
            return self._away(here, task.dropoff if task else None, where), where
        if place is Place.WAY:
            return self._waypoint(here), where
        if place in (Place.MEET1, Place.MEET2):
            if where.meet is None:
                where = replace(where, meet=self._meeting(where))
            if where.meet is None:
                return None, where
            return (where.meet[0] if place is Place.MEET1 else where.meet[1]), where
        return None, where

    def _free_sides(self, cell: Cell) -> Iterator[Cell]:
        x, y = cell
        for dx, dy in _SIDES:
            if self.maps.maze.is_free(x + dx, y + dy):
                yield (x + dx, y + dy)

    def _next(self, here: Cell, where: Where) -> Where:
        if where.next_cell is None and self.r2 is not None:
            start = where.pos[1]
            options = [
                (d, c) for c in self._free_sides(here) if (d := self.maps.distance(start, c)) >= 0
            ]
            return replace(where, next_cell=min(options)[1] if options else None)
        return where

    def _away(self, here: Cell, dropoff: Cell | None, where: Where) -> Cell | None:
        taken = {where.next_cell, dropoff, where.item_cell}
        return next((c for c in self._free_sides(here) if c not in taken), None)

    def _waypoint(self, here: Cell) -> Cell | None:
        target = self.incident.entry.action.target
        if target is None:
            return None
        path = self.maps.path(here, target)
        return path[len(path) // 2] if len(path) >= 3 else None

    def _meeting(self, where: Where) -> tuple[Cell, Cell] | None:
        """Adjacent cells on a shortest path between the two robots, split so that neither
        waits long for the other."""
        path = self.maps.path(where.pos[0], where.pos[1])
        if len(path) < 2:
            return None
        k = len(path) - 1
        c1, c2 = where.clock
        best = min(range(k), key=lambda i: (max(c1 + i, c2 + k - i - 1), i))
        return path[best], path[best + 1]


def _moved(where: Where, role: Role, dest: Cell, distance: int, action: TeamAction) -> Where:
    """``where`` after ``role`` drove ``distance`` cells to ``dest``."""
    i = _i(role)
    pos, clock, plans = list(where.pos), list(where.clock), list(where.plans)
    pos[i], clock[i], plans[i] = dest, clock[i] + distance, plans[i] + (action,)
    return replace(
        where, pos=(pos[0], pos[1]), clock=(clock[0], clock[1]), plans=(plans[0], plans[1])
    )


def _acted(where: Where, role: Role, ticks: int, action: TeamAction) -> Where:
    """``where`` after ``role`` did ``action``, taking ``ticks``."""
    i = _i(role)
    clock, plans = list(where.clock), list(where.plans)
    clock[i], plans[i] = clock[i] + ticks, plans[i] + (action,)
    return replace(where, clock=(clock[0], clock[1]), plans=(plans[0], plans[1]))


def adjacent(a: Cell, b: Cell) -> bool:
    """Whether cells ``a`` and ``b`` share a side."""
    return abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1
