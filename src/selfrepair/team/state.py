"""The mutable state of one team mission while it runs: robots, items, the known map and the
records kept for the result.

Only the engine (:mod:`selfrepair.team.engine`) and the team strategies
(:mod:`selfrepair.team.strategies`) touch it, within one call of
:func:`selfrepair.team.engine.run_team`; nothing of it outlives the mission. What the team
*knows* (the known map: walls, blocked cells met so far, cells seen blocked by world events,
robots believed unable to move, each robot's known faults) is kept apart from what is *true*
(every active blocked cell, and each robot's true faults, held by the robot's own
:class:`~selfrepair.execution.simulator.Simulator` with a :class:`RobotFaultClock`), as a single
robot's simulator keeps the true faults apart from what the robot knows.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.execution.faults import FaultEvent, Persistence
from selfrepair.execution.simulator import Simulator
from selfrepair.execution.stepper import Stepper
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.team.model import (
    ActionKind,
    IncidentKind,
    RobotSpec,
    TeamAction,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    drive,
)
from selfrepair.team.reservations import Reservations, TimedStep
from selfrepair.team.result import (
    ActRecord,
    DiscoveryRecord,
    FaultRecord,
    IncidentRecord,
    MoveRecord,
    OwnRepairRecord,
    TeamOptions,
    TeamRepairRecord,
    TeamSource,
)
from selfrepair.world.maze import Maze

__all__ = [
    "Drive",
    "Entry",
    "FaultState",
    "ItemState",
    "RobotFaultClock",
    "RobotState",
    "TeamWorld",
    "known_maze",
]


@dataclass(slots=True)
class FaultState:
    """When team fault number ``index`` starts and ends, in units (``None``: not known yet), and
    whether it is active now (set by the engine at each event time)."""

    index: int
    fault: TeamFault
    on: int | None
    off: int | None = None
    active: bool = False
    done: bool = False


class RobotFaultClock:
    """The true domain faults of one robot over time: the effects of its active team faults
    (``immobilised``: every domain fault; ``wheels``: its wheel faults). An ``intermittent`` team
    fault, while active, is present at the robot's step ``k`` with its probability, drawn as a
    single robot's intermittent fault event is (:meth:`FaultEvent.active
    <selfrepair.execution.faults.FaultEvent.active>`: ``default_rng([seed, index, k])``), so
    replay computes the same. Team faults can start at a robot's first pick, a time no schedule
    knows in advance, so the engine sets when each starts and clears (:class:`FaultState`) and this
    clock answers the robot's :class:`~selfrepair.execution.simulator.Simulator` from them.
    Mutable (it keeps the set of each combination met)."""

    __slots__ = ("_draws", "_effects", "_seed", "_sets", "_states")

    def __init__(
        self, domain: SomeDomain, states: list[FaultState], robot: str, seed: int
    ) -> None:
        self._states = [s for s in states if s.fault.robot == robot and _effect(domain, s.fault)]
        self._effects = {s.index: _effect(domain, s.fault) for s in self._states}
        self._draws = {
            s.index: FaultEvent(None, persistence=Persistence.INTERMITTENT,
                                probability=s.fault.probability)
            for s in self._states
            if s.fault.persistence is Persistence.INTERMITTENT
        }  # fmt: skip
        self._seed = seed
        self._sets: dict[tuple[int, ...], frozenset[object]] = {(): frozenset()}

    def at(self, step: int, units: int) -> frozenset[object]:
        """The robot's true faults at its step ``step`` (``units``: the time, unused: the engine
        keeps the team faults' stretches)."""
        present = tuple(
            s.index
            for s in self._states
            if s.active
            and ((draw := self._draws.get(s.index)) is None
                 or draw.active(s.index, step, Fraction(0), self._seed))
        )  # fmt: skip
        found = self._sets.get(present)
        if found is None:
            found = frozenset().union(*(self._effects[i] for i in present))
            self._sets[present] = found
        return found

    def effect(self, index: int) -> frozenset[object]:
        """The domain faults of the robot's team fault ``index`` (empty for another one)."""
        return self._effects.get(index, frozenset())

    def states(self) -> list[FaultState]:
        """The robot's team faults that act on its wheels, in scenario order."""
        return self._states


def _effect(domain: SomeDomain, fault: TeamFault) -> frozenset[object]:
    """The domain faults a team fault gives its robot."""
    if fault.kind is TeamFaultKind.IMMOBILISED:
        return frozenset(domain.faults)
    if fault.kind is TeamFaultKind.WHEELS:
        return frozenset(domain.parse_faults(fault.wheel_faults))
    return frozenset()


@dataclass(slots=True)
class Entry:
    """One queued higher-level action: where it came from, and the actions it helps replace
    (the recursion guard: none of them may be used again to replace it)."""

    action: TeamAction
    source: TeamSource = TeamSource.PLAN
    guard: frozenset[TeamAction] = frozenset()


@dataclass(slots=True)
class Drive:
    """A drive being carried out: the robot's :class:`~selfrepair.execution.stepper.Stepper`
    for it (its remaining primitive plan, its single-robot repairer, the record of its own
    repairs) and the plan's placement in time (one step per queued primitive action)."""

    entry: Entry
    target: Cell
    stepper: Stepper
    steps: list[TimedStep]

    def actions(self) -> list[object]:
        """The primitive actions still to run."""
        return [a for a, _ in self.stepper.queue]


@dataclass(slots=True)
class RobotState:
    """One robot now: pose, queue, load, what it is doing and what it knows of its faults.

    ``busy_until`` is the unit at which its current primitive action or act ends (its
    ``footprint`` is held until then); ``pending`` is the act whose effect applies at that
    moment. ``sim`` is its own simulator (its true faults and their clock, its step count);
    ``faults`` the domain faults it knows (sensed before every command with detection ``now``,
    learned from failed attempts with ``on-use``); ``discovered`` the team faults it has
    noticed. ``stuck`` says whether the team believes it cannot drive (set by a ``stuck``
    incident, cleared when it can move again). ``retry_at`` is when a robot that could not plan
    tries again; ``deferred`` the incident it is waiting out (the same incident is not reported
    again); ``last_incident`` its last incident and when (the same one again at the same instant
    is waited out).
    """

    spec: RobotSpec
    pose: Pose
    queue: deque[Entry]
    sim: Simulator
    clock: RobotFaultClock
    holding: str = ""
    busy_until: int = 0
    footprint: tuple[Cell, ...] = ()
    pending: TeamAction | None = None
    drive: Drive | None = None
    faults: frozenset[object] = frozenset()
    gripper_ok: bool = True
    stuck: bool = False
    retry_at: int = 0
    stale: bool = False
    first_pick: int | None = None
    deferred: tuple[TeamAction, str] | None = None
    last_incident: tuple[int, TeamAction, IncidentKind] | None = None
    failures: int = 0
    discovered: set[int] = field(default_factory=set)

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

    @property
    def settled(self) -> bool:
        """Whether the item needs nothing more: delivered, or given up."""
        return self.delivered_at is not None or self.lost


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
    seen: frozenset[Cell] = frozenset()
    """The cells the team believes blocked by world events: what the robots' sensors report
    (range sensing: the true state of the cells around each robot, shared with the team; bump
    sensing: the cells robots bumped into, for good). Every robot's stepper sees it."""
    moves: list[MoveRecord] = field(default_factory=list)
    acts: list[ActRecord] = field(default_factory=list)
    fault_log: list[FaultRecord] = field(default_factory=list)
    incidents: list[IncidentRecord] = field(default_factory=list)
    repairs: list[TeamRepairRecord] = field(default_factory=list)
    own_repairs: list[OwnRepairRecord] = field(default_factory=list)
    discoveries: list[DiscoveryRecord] = field(default_factory=list)
    faults: list[FaultState] = field(default_factory=list)
    messages: int = 0
    plans: int = 0
    expansions: int = 0
    yields: int = 0
    last_progress: int = 0
    dirty: set[str] = field(default_factory=set)

    def known_extra(self, exclude: str = "", events: bool = True) -> frozenset[Cell]:
        """Free cells of the maze the team treats as walls: known blocked cells, cells of
        robots believed stuck (but robot ``exclude``, which plans for itself) and, with
        ``events``, the cells :attr:`seen` blocked by world events (but the cell ``exclude``
        stands on: an obstacle on a robot's own cell never traps it)."""
        extra = frozenset(self.known_blocked) | frozenset(
            r.pose.cell for r in self.robots.values() if r.stuck and r.name != exclude
        )
        if events and self.seen:
            own = self.robots[exclude].pose.cell if exclude else None
            extra |= frozenset(c for c in self.seen if c != own)
        return extra

    def known_map(self, exclude: str = "", events: bool = True) -> Maze:
        """The map the team plans on: the maze with :meth:`known_extra` as walls (``events``
        false: without the world-event cells, which a robot's own planner and stepper take
        from their belief, as a single robot's do)."""
        return known_maze(self.scenario.maze, self.known_extra(exclude, events))

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
    "team known maps", 64, kind=CacheKind.PLAN, per_map=True
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
