"""The protocol of a repair strategy: its lifecycle, what it is asked and what it answers.

A strategy has a lifecycle. At the start of a mission the caller (the executor, the Gymnasium
environment, the team engine) calls the strategy's factory with the mission's context and gets a
:class:`Repairer`; then, each time the next action cannot go on, it calls
``repairer.repair(request)`` and applies the answer; when the mission ends it drops the repairer.
A repairer may keep state between repairs (an incremental planner keeps its search; the
``replacement`` strategy keeps the mission's compiled look-ups); a stateless one is a plain
function wrapped by :func:`stateless`.

:class:`Repairer` is one protocol for every kind of mission (:class:`~.names.MissionKind`),
generic in what it is asked and what it answers. For one robot (the default parameters) the
context is a :class:`MissionContext` (the robot, the goal, the table, and the world as functions:
a planner, a free-cell test, an edge cost), the request a :class:`RepairRequest` (the pose, the
queued actions and the known faults) and the answer a :class:`Repair` that the caller splices into
its queue. A team strategy is started with the team's world and answers incidents with decisions
(:mod:`selfrepair.team.strategies`). Factories of both kinds live in one registry
(:mod:`selfrepair.repair.strategies.registry`).

:class:`RepairRequest` and :class:`Repair` are immutable ``NamedTuple`` values rather than frozen
dataclasses: they are built on every repair, inside the measured latency, and a frozen dataclass
costs several times more to construct. A :class:`Repair` says which queued actions to drop
(``consumed``, counted from the faulty one) and what to run instead (``actions``); every action in
it is available under the known faults, so the repaired queue starts with an executable action.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Generic, NamedTuple, Protocol

from typing_extensions import TypeVar

from selfrepair.diagnosis.cooperative import Observer
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.replacement import FreeTest
from selfrepair.repair.strategies.names import RepairSource
from selfrepair.repair.strategies.options import StrategyOptions
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.astar import PlanResult
from selfrepair.status import RepairStatus
from selfrepair.tables.model import SomeTable

__all__ = [
    "Assumption",
    "Belief",
    "FunctionRepairer",
    "MissionContext",
    "PlanFn",
    "Repair",
    "RepairRequest",
    "Repairer",
    "StrategyFactory",
    "chained",
    "stateless",
]


PlanFn = Callable[[Pose, Cell, Heading | None, frozenset[object], int | None], PlanResult]
"""``plan(start, goal, goal_heading, known_faults, max_expansions)``: an exact plan on the
mission's map with the mission's planner settings."""


@dataclass(slots=True)
class Belief:
    """The cells the robot believes blocked by world events (a changing world, see
    :mod:`selfrepair.world.events`); empty when the world never changes. Mutable: the stepper
    updates it as the robot senses or bumps into cells, and the mission's planner
    (``MissionContext.plan``) plans around them."""

    blocked: frozenset[Cell] = frozenset()


@dataclass(frozen=True, slots=True)
class MissionContext:
    """What a strategy knows about its mission from the start.

    ``plan`` plans on the mission's map; ``replan_budget`` is the node budget of a full replan
    (``None``: unbounded). ``free`` tests a footprint, ``grid`` is the same map as a
    :class:`~selfrepair.geometry.FreeGrid` with a margin of at least the table's reach, and
    ``cost(pose, action)`` is the exact cost of one step (duration plus clearance term), and
    ``cost * cost_scale`` is an integer for every step. ``world``
    is the map itself (a :class:`selfrepair.world.maze.Maze`), typed loosely so that this layer does
    not depend on the world layer; only strategies that must read the map (e.g. to export it)
    use it. ``start`` is the mission's start pose (``None`` when unknown): a strategy that searches
    ahead of its first repair, as D* Lite does, starts there. ``belief`` holds the cells the
    robot believes blocked by world events (the stepper keeps it up to date; ``plan`` plans
    around them, ``grid`` and ``free`` know only the maze's walls). ``clearance_weight``,
    ``clearance_radius`` and ``backend`` are the mission's planner settings, for a strategy that
    searches with its own planner (D* Lite).
    """

    domain: SomeDomain
    goal: Cell
    goal_heading: Heading | None
    options: StrategyOptions
    table: SomeTable | None
    plan: PlanFn
    replan_budget: int | None
    free: FreeTest
    grid: FreeGrid
    cost: Callable[[Pose, object], Fraction]
    world: object = None
    cost_scale: int = 1
    start: Pose | None = None
    clearance_weight: Fraction = Fraction(0)
    clearance_radius: int = 2
    backend: str = "auto"
    belief: Belief = field(default_factory=Belief)
    behaviour: str | None = None
    """The fault-behaviour model the robot assumes for its hidden faults (the domain's default
    when ``None``; the simulator uses the same one: the model is taken to be right)."""
    observers: tuple[Observer, ...] = ()
    """The teammates that watch the robot when its faults are hidden, following it
    (:func:`selfrepair.diagnosis.cooperative.following`): active diagnosis counts their
    readings when it plans a probe."""

    def at_goal(self, pose: Pose) -> bool:
        """Whether ``pose`` satisfies the mission's goal."""
        return pose.cell == self.goal and (
            self.goal_heading is None or pose.heading == self.goal_heading
        )


class RepairRequest(NamedTuple):
    """What a repairer looks at: the world as the executor believes it to be.

    ``queue`` holds the remaining actions, the faulty one first (a read-only sequence; the
    executor passes a view, not a copy, so that building a request costs O(1)). It is empty for
    the defensive replan made when the queue runs out away from the goal. ``step`` is the number
    of steps executed so far.
    """

    pose: Pose
    queue: Sequence[object]
    known: frozenset[object]
    step: int = 0


class Repair(NamedTuple):
    """A strategy's answer.

    ``status`` says whether the queue was repaired; ``source`` is the step source of the new
    actions. ``attempts`` lists the strategies tried, in order. ``replans`` counts full replans;
    ``candidate_length``/``depth``/``candidate_index`` describe a table replacement (the index in
    the looked-up candidate list); ``examined`` counts table candidates looked at;
    ``expansions`` the search nodes expanded by planning. An attempt that gave up may say why
    after a colon: ``("lpg-adapt:timeout", "replan")`` means LPG-adapt ran out of time and the
    strategy fell back to replanning. ``rewritten`` counts the later queued actions a whole-plan
    rewrite substituted (their replacements are in ``actions``, which then runs up to the last
    substituted one, and ``consumed`` covers them); 0 for any other repair.
    """

    status: RepairStatus
    source: RepairSource
    actions: tuple[object, ...] = ()
    consumed: int = 0
    replans: int = 0
    candidate_length: int | None = None
    depth: int | None = None
    examined: int = 0
    expansions: int = 0
    attempts: tuple[str, ...] = ()
    candidate_index: int | None = None
    rewritten: int = 0


RequestT = TypeVar("RequestT", contravariant=True, default=RepairRequest)
"""What a repairer is asked (a robot's :class:`RepairRequest` unless said otherwise)."""
AnswerT = TypeVar("AnswerT", covariant=True, default=Repair)
"""What a repairer answers (a robot's :class:`Repair` unless said otherwise)."""
ContextT = TypeVar("ContextT", default=MissionContext)
"""What a strategy is started with (a robot's :class:`MissionContext` unless said otherwise)."""
Request = TypeVar("Request", default=RepairRequest)
Answer = TypeVar("Answer", default=Repair)


class Assumption(NamedTuple):
    """What an observing repairer (one with ``observe``, faults hidden) wants the stepper to take
    as given: the faults it assumes (``known``: the queue's actions are checked against them)
    and the actions it takes to be unusable whatever the faults (``unusable``: a strategy
    without a fault model that saw them misbehave)."""

    known: frozenset[object]
    unusable: frozenset[object] = frozenset()


class Repairer(Protocol[RequestT, AnswerT]):
    """A strategy started for one mission: answers requests, possibly keeping state.

    ``Repairer`` alone is a robot's repairer (``Repairer[RepairRequest, Repair]``); a team's is
    ``Repairer[Incident, Decision]`` (:mod:`selfrepair.team.strategies`).

    A robot's repairer may also have an integer attribute ``horizon`` (0 when absent): then the
    executor asks it for a repair as soon as one of the next ``horizon`` queued actions after the
    first is faulty under the known faults, not only when the first one is (the first faulty
    action is then not at the front of ``RepairRequest.queue``; see
    :func:`~selfrepair.repair.strategies.lookahead.lookahead`).

    In a changing world (:mod:`selfrepair.world.events`) a robot's repairer may also have a
    method ``repair_blocked(request)``: asked when the first queued action is available but
    sweeps a cell believed blocked (``MissionContext.belief``), it answers with actions that
    avoid those cells; one that declares ``sees_cells = True`` instead is asked through
    :meth:`repair`, which then also sees the cells; any other is answered by a replan there. It
    may have
    ``expect_blocked()`` too, called once before the mission's clock runs when the world
    changes (to prepare what ``repair_blocked`` needs outside the timed repairs).

    With the faults hidden (detection ``hidden``), a robot's repairer may also *observe*: a
    method ``observe(observation, deviated, moved) -> bool`` is given every
    :class:`~selfrepair.diagnosis.Observation` after each command, with whether the robot truly
    left the pose its command should have reached (``deviated``) and whether it moved; it answers
    whether it must be asked for a repair before the next command even if the front is available
    (the queue was planned from a pose the robot is not at). Such a repairer also has
    ``assumption() -> Assumption``, which the stepper reads after each observation and each
    repair (see :mod:`selfrepair.execution.stepper`). One that declares ``hears_teammates =
    True`` takes the readings of observing teammates too, as a fourth argument of ``observe``
    (a sequence of observations of the same command); one with a ``belief`` attribute (a
    :class:`~selfrepair.diagnosis.FaultBelief`) has its bit set recorded after each command.
    """

    def repair(self, request: RequestT) -> AnswerT:
        """The answer to ``request`` (for a robot: its first queued action is faulty)."""
        ...


StrategyFactory = Callable[[MissionContext], Repairer]
"""Starts a robot's strategy for one mission."""


@dataclass(frozen=True, slots=True)
class FunctionRepairer(Generic[ContextT, Request, Answer]):
    """A stateless strategy: a plain function of (context, request)."""

    context: ContextT
    fn: Callable[[ContextT, Request], Answer]
    horizon: int = 0

    def repair(self, request: Request) -> Answer:
        """``fn(context, request)``."""
        return self.fn(self.context, request)


def stateless(
    fn: Callable[[ContextT, Request], Answer],
) -> Callable[[ContextT], Repairer[Request, Answer]]:
    """The factory of a strategy that keeps no state between repairs."""

    def start(context: ContextT) -> Repairer[Request, Answer]:
        return FunctionRepairer(context, fn)

    start.__doc__ = fn.__doc__
    return start


def chained(
    repair: Repair, before: tuple[str, ...], *, examined: int = 0, expansions: int = 0
) -> Repair:
    """``repair`` with the strategies tried before it prepended and their work added (a
    fallback's answer, as the strategy that fell back returns it)."""
    return repair._replace(
        examined=repair.examined + examined,
        expansions=repair.expansions + expansions,
        attempts=before + repair.attempts,
    )
