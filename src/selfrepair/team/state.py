"""The mutable state of one team mission while it runs: robots, items, the known map and the
records kept for the result.

Only the engine (:mod:`selfrepair.team.engine`) and the team strategies
(:mod:`selfrepair.team.strategies`) touch it, within one call of
:func:`selfrepair.team.engine.run_team`; nothing of it outlives the mission. What the team
*knows* (the known map: walls, blocked cells met so far, robots believed unable to move) is kept
apart from what is *true* (every active blocked cell, every robot's active faults), as the
single-robot simulator keeps the true faults apart from the executor's.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.execution.result import StepSource
from selfrepair.geometry import Cell, Pose
from selfrepair.repair.strategies import Repairer
from selfrepair.team.model import ActionKind, RobotSpec, TeamAction, TeamScenario, drive
from selfrepair.team.reservations import Reservations, TimedStep
from selfrepair.team.result import (
    ActRecord,
    FaultRecord,
    IncidentRecord,
    MoveRecord,
    OwnRepairRecord,
    TeamOptions,
    TeamRepairRecord,
    TeamSource,
)
from selfrepair.world.maze import Maze

__all__ = ["Drive", "Entry", "ItemState", "RobotState", "TeamWorld", "known_maze"]


@dataclass(slots=True)
class Entry:
    """One queued higher-level action: where it came from, and the actions it helps replace
    (the recursion guard: none of them may be used again to replace it)."""

    action: TeamAction
    source: TeamSource = TeamSource.PLAN
    guard: frozenset[TeamAction] = frozenset()


@dataclass(slots=True)
class Drive:
    """A drive being carried out: the robot's own remaining primitive plan, its placement in
    time (one step per primitive action), and the robot's single-robot repairer for it."""

    entry: Entry
    target: Cell
    primitives: list[tuple[Any, StepSource]]
    steps: list[TimedStep]
    repairer: Repairer | None


@dataclass(slots=True)
class RobotState:
    """One robot now: pose, queue, load, what it is doing and its true faults.

    ``busy_until`` is the unit at which its current primitive action or act ends (its
    ``footprint`` is held until then); ``pending`` is the act whose effect applies at that
    moment. ``faults`` are its active domain faults (sensed at once, so also known) and
    ``stuck`` whether the team believes it cannot drive (set by a ``stuck`` incident, cleared
    when it can move again). ``retry_at`` is when a robot that could not plan tries again;
    ``deferred`` the incident it is waiting out (the same incident is not reported again).
    """

    spec: RobotSpec
    pose: Pose
    queue: deque[Entry]
    holding: str = ""
    busy_until: int = 0
    footprint: tuple[Cell, ...] = ()
    pending: TeamAction | None = None
    drive: Drive | None = None
    faults: frozenset[Any] = frozenset()
    gripper_ok: bool = True
    stuck: bool = False
    retry_at: int = 0
    stale: bool = False
    first_pick: int | None = None
    deferred: tuple[TeamAction, str] | None = None
    failures: int = 0

    @property
    def name(self) -> str:
        """The robot's name."""
        return self.spec.name

    @property
    def load(self) -> str:
        """The item it carries, counting a pick or a taking in progress (empty: none)."""
        if self.holding:
            return self.holding
        action = self.pending
        if action is not None and (
            action.kind is ActionKind.PICK
            or (action.kind is ActionKind.HANDOVER and action.taker == self.name)
        ):
            return action.item
        return ""

    @property
    def can_grip(self) -> bool:
        """Whether it has a gripper and the gripper works."""
        return self.spec.gripper and self.gripper_ok

    def occupancy(self, now: int) -> tuple[Cell, ...]:
        """The cells the robot holds at ``now``: its action's footprint while moving, else its
        cell."""
        return self.footprint if self.busy_until > now and self.footprint else (self.pose.cell,)


@dataclass(slots=True)
class ItemState:
    """Where an item is: on the floor at ``cell``, or carried by ``holder``; delivered at a unit,
    or given up."""

    cell: Cell | None
    holder: str = ""
    delivered_at: int | None = None
    lost: bool = False


@dataclass(slots=True)
class TeamWorld:
    """Everything one running team mission keeps (see the module docstring)."""

    scenario: TeamScenario
    options: TeamOptions
    scale: int
    robots: dict[str, RobotState]
    items: dict[str, ItemState]
    reservations: Reservations = field(default_factory=Reservations)
    now: int = 0
    blocked: set[Cell] = field(default_factory=set)
    known_blocked: set[Cell] = field(default_factory=set)
    moves: list[MoveRecord] = field(default_factory=list)
    acts: list[ActRecord] = field(default_factory=list)
    fault_log: list[FaultRecord] = field(default_factory=list)
    incidents: list[IncidentRecord] = field(default_factory=list)
    repairs: list[TeamRepairRecord] = field(default_factory=list)
    own_repairs: list[OwnRepairRecord] = field(default_factory=list)
    messages: int = 0
    plans: int = 0
    expansions: int = 0
    yields: int = 0
    last_progress: int = 0
    dirty: set[str] = field(default_factory=set)

    def robot_list(self) -> Iterator[RobotState]:
        """The robots in priority order (scenario order)."""
        return iter(self.robots.values())

    def known_extra(self, exclude: str = "") -> frozenset[Cell]:
        """Free cells of the maze the team treats as walls: known blocked cells and cells of
        robots believed stuck (but robot ``exclude``, which plans for itself)."""
        return frozenset(self.known_blocked) | frozenset(
            r.pose.cell for r in self.robots.values() if r.stuck and r.name != exclude
        )

    def known_map(self, exclude: str = "") -> Maze:
        """The map the team plans on: the maze with :meth:`known_extra` as walls."""
        return known_maze(self.scenario.maze, self.known_extra(exclude))

    def item_cell(self, item: str) -> Cell:
        """Where ``item`` is now: its floor cell or its carrier's cell."""
        state = self.items[item]
        if state.holder:
            return self.robots[state.holder].pose.cell
        assert state.cell is not None
        return state.cell

    def carrier(self, item: str) -> str:
        """The robot that carries ``item`` (counting a pick or a taking in progress), or ``""``."""
        for robot in self.robots.values():
            if robot.load == item:
                return robot.name
        return ""

    def open_items(self) -> list[str]:
        """Items neither delivered nor given up, in task order."""
        return [t.item for t in self.scenario.tasks if self._open(t.item)]

    def _open(self, item: str) -> bool:
        state = self.items[item]
        return state.delivered_at is None and not state.lost

    def broadcast(self, sender: str) -> None:
        """Count one message from ``sender`` to every other robot."""
        self.messages += len(self.robots) - 1


_KNOWN: BoundedCache[tuple[Maze, frozenset[Cell]], Maze] = BoundedCache(
    "team known maps", 64, kind=CacheKind.PLAN
)


def known_maze(maze: Maze, extra: frozenset[Cell]) -> Maze:
    """``maze`` with the cells of ``extra`` (those on the grid) turned into walls (kept)."""
    if not extra:
        return maze

    def make() -> Maze:
        walls = maze.walls.copy()
        for x, y in extra:
            if maze.in_bounds(x, y):
                walls[y, x] = True
        return Maze(np.asarray(walls), name=maze.name)

    return _KNOWN.get((maze, extra), make)


def item_task_of(robot: RobotState) -> str:
    """The item the robot is working on: the one it carries, else the first item its queue
    picks or takes; empty when none."""
    if robot.load:
        return robot.load
    for entry in robot.queue:
        a = entry.action
        if a.kind is ActionKind.PICK and a.robot == robot.name:
            return a.item
        if a.kind is ActionKind.HANDOVER and a.taker == robot.name:
            return a.item
    return ""


def resource(robot: RobotState, start: Cell | None = None) -> None:
    """Make the drives of ``robot``'s queue start where the robot will be (after a splice)."""
    here = start if start is not None else robot.pose.cell
    fixed: deque[Entry] = deque()
    for entry in robot.queue:
        a = entry.action
        if a.kind is ActionKind.DRIVE and a.robot == robot.name:
            assert a.target is not None
            if a.target == here:
                continue  # already there: nothing to drive
            if a.source != here:
                entry = Entry(drive(robot.name, here, a.target), entry.source, entry.guard)
            here = a.target
        fixed.append(entry)
    robot.queue = fixed
