"""The replacement core: the first valid candidate of a table, for any kind of action.

A replacement table maps an action, under what is known to be broken, to candidates in order of
preference. A candidate is a sequence of steps; it is **valid** at a state when

1. *healthy*: every step can be done by whoever does it, under the known faults;
2. *executable where it is used*: every step can be done from the state the steps before it
   lead to (for a robot: its footprint is free; for a team: its places bind to reachable cells);
3. *not being replaced*: none of the concrete actions it binds to is the failing action or one
   that an enclosing replacement is still replacing (the **guard**, which keeps recursion from
   cycling).

One robot's primitive actions and a team's higher-level actions (drive, pick, drop, handover,
bound to teammates and cells) are two :class:`LiftedWorld` values over the same test: the robot's
world (:class:`selfrepair.repair.replacement.RobotWorld`) says what an action does to a pose, the
team's (:mod:`selfrepair.team.binding`) what a template step does to the positions, clocks and
item of the two robots. The three conditions are written once, in :func:`walk` (the validity test
of one candidate) and :class:`CoreSearch` (the first valid candidate, with the recursion modes
of :mod:`selfrepair.repair.replacement`: a step that is not healthy may itself be replaced in
turn, when the mode's rule allows it at that depth, or left for later when it is deferrable).
Every search answers with the one repair record, :class:`Replacement`.

This module knows no robot, no map and no team: worlds bring those in.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Sequence, Set
from dataclasses import dataclass, field
from typing import Any, Generic, NamedTuple, Protocol

from typing_extensions import TypeVar

from selfrepair.geometry import Pose

__all__ = [
    "CandidateTable",
    "CoreSearch",
    "LiftedWorld",
    "RecurseRule",
    "Replacement",
    "walk",
]

ActionT = TypeVar("ActionT", contravariant=True)
KnownT = TypeVar("KnownT", contravariant=True)
CandidateT = TypeVar("CandidateT", covariant=True)
StepT = TypeVar("StepT", contravariant=True)
StateT = TypeVar("StateT")
Step = TypeVar("Step")
State = TypeVar("State", default=Pose)
End = TypeVar("End", default=Pose)


class CandidateTable(Protocol[ActionT, KnownT, CandidateT]):
    """A replacement table: candidates keyed by (action, what is known to be broken), in order of
    preference (:class:`selfrepair.tables.model.ReplacementTable` for a robot's actions and its
    known faults, :class:`selfrepair.team.table.TeamTable` for a team action's kind and the
    incident)."""

    def candidates(self, action: ActionT, known: KnownT) -> Sequence[CandidateT]:
        """The candidates for ``action`` under ``known``, best first (empty: none)."""
        ...


class LiftedWorld(Protocol[StepT, StateT]):
    """What the core needs to know of a world to test a candidate's steps."""

    def healthy(self, step: StepT, state: StateT) -> bool:
        """Condition 1: whether ``step`` can be done under the known faults."""
        ...

    def advance(self, step: StepT, state: StateT) -> tuple[tuple[Hashable, ...], StateT] | None:
        """Condition 2: ``None`` when the (healthy) ``step`` cannot be done from ``state``; else the
        concrete actions it binds to (checked against the guard) and the state after it."""
        ...


RecurseRule = Callable[[Any, Any, int], bool]
"""Whether faulty action ``b`` inside a candidate for ``a`` may be replaced at depth ``d``."""


class Replacement(NamedTuple, Generic[End]):
    """A valid replacement found at run time: the one repair record of the core.

    ``candidate`` is the table's candidate (index ``position`` in the looked-up list);
    ``actions`` the executable sequence after nested replacements are expanded (equal to
    ``candidate`` when ``depth`` is 0). ``depth`` counts nested replacement levels below this
    one; ``examined`` the candidates looked at in total, nested ones included. ``end`` is the
    state reached (a pose for one robot). ``deferred`` lists the positions in ``actions`` of
    faulty complex actions left unreplaced (``primitive`` mode only; never position 0): they are
    replaced when the robot reaches them. An immutable ``NamedTuple`` (cheaper to build than a
    frozen dataclass on the hot path).
    """

    action: object
    candidate: tuple[object, ...]
    actions: tuple[object, ...]
    position: int
    depth: int
    examined: int
    end: End
    deferred: tuple[int, ...] = ()


def walk(
    world: LiftedWorld[Step, State], steps: Iterable[Step], state: State, replacing: Set[object]
) -> tuple[tuple[Hashable, ...], State] | None:
    """The validity test of one candidate, without recursion: ``None`` when a step is not
    healthy, not executable from where the steps before it lead, or binds to an action in
    ``replacing``; else the concrete actions in order and the state at the end."""
    out: list[Hashable] = []
    for step in steps:
        moved = world.healthy(step, state) and _executable(world, step, state, replacing)
        if not moved:
            return None
        bound, state = moved
        out.extend(bound)
    return tuple(out), state


def _executable(
    world: LiftedWorld[Step, State], step: Step, state: State, replacing: Set[object]
) -> tuple[tuple[Hashable, ...], State] | None:
    """Conditions 2 and 3 for a healthy ``step``: its actions and the state after it, or
    ``None`` when it cannot be done from ``state`` or binds to an action being replaced."""
    moved = world.advance(step, state)
    if moved is None or not replacing.isdisjoint(moved[0]):
        return None
    return moved


Expanded = tuple[tuple[object, ...], Any, int, tuple[int, ...]]
"""A valid candidate's actions (nested replacements expanded), end state, nested depth and
deferred positions."""


@dataclass(slots=True)
class CoreSearch(Generic[Step, State]):
    """One look-up in progress: the first valid candidate of ``candidates(action)`` in a world,
    with recursion (mutable: counts candidates and memoises sub-problems).

    ``may_recurse(b, a, depth)`` says whether a step ``b`` that is not healthy inside a candidate
    for ``a`` may be replaced in turn (the recursion mode's rule); ``deferrable`` holds the steps
    that may instead stay unreplaced, unless they run first (``primitive`` mode), and
    ``follow(state, b)`` is the state after such a step, which is not checked. A step that is not
    healthy is its own action (only a robot's primitive steps recurse)."""

    world: LiftedWorld[Step, State]
    candidates: Callable[[Step], Sequence[Sequence[Step]]]
    may_recurse: RecurseRule
    deferrable: frozenset[Step] = frozenset()
    follow: Callable[[State, Step], State] | None = None
    examined: int = 0
    memo: dict[tuple[Step, State, frozenset[Step], int, bool], Replacement[State] | None] = field(
        default_factory=dict
    )

    def replace(
        self, action: Step, state: State, replacing: frozenset[Step], depth: int, first: bool = True
    ) -> Replacement[State] | None:
        """The first valid replacement; nested results are memoised per (action, state, guard set,
        depth, whether it runs first), so a sub-problem met again in another candidate is not
        searched twice."""
        key = (action, state, replacing, depth, first)
        if key in self.memo:
            return self.memo[key]
        found = self._first(action, state, replacing, depth, first)
        self.memo[key] = found
        return found

    def _first(
        self, action: Step, state: State, replacing: frozenset[Step], depth: int, first: bool
    ) -> Replacement[State] | None:
        for position, candidate in enumerate(self.candidates(action)):
            self.examined += 1
            found = self._expand(action, candidate, state, replacing, depth, first)
            if found is not None:
                actions, end, nested, deferred = found
                return Replacement(
                    action, tuple(candidate), actions, position, nested, self.examined, end,
                    deferred,
                )  # fmt: skip
        return None

    def _expand(
        self,
        action: Step,
        candidate: Sequence[Step],
        state: State,
        replacing: frozenset[Step],
        depth: int,
        first: bool,
    ) -> Expanded | None:
        """:func:`walk` with recursion: a step that is not healthy is replaced in turn (guard
        set extended, one level deeper) or deferred, as the mode allows."""
        world = self.world
        out: list[object] = []
        deferred: list[int] = []
        nested = 0
        for b in candidate:
            runs_first = first and not out
            if world.healthy(b, state):
                moved = _executable(world, b, state, replacing)
                if moved is None:
                    return None
                bound, state = moved
                out.extend(bound)
            elif b in replacing:  # condition 3 for a step that would be replaced again
                return None
            elif b in self.deferrable:  # a faulty complex action: replaced when reached
                if runs_first or self.follow is None:
                    return None
                deferred.append(len(out))
                out.append(b)
                state = self.follow(state, b)
            elif self.may_recurse(b, action, depth):
                sub = self.replace(b, state, replacing | {b}, depth + 1, runs_first)
                if sub is None:
                    return None
                deferred.extend(len(out) + i for i in sub.deferred)
                out.extend(sub.actions)
                state = sub.end
                nested = max(nested, sub.depth + 1)
            else:
                return None
        return tuple(out), state, nested, tuple(deferred)
