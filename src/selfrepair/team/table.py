"""Team replacement tables: higher-level replacements made of several robots' actions.

A single-robot table maps a faulty action to sub-plans of the same robot. A team table maps a
*situation* - the kind of the failing higher-level action, why it failed and whether the robot
carries an item, a :data:`Key` - to :class:`Template` candidates (as a robot's table maps an
action and its known faults: both are looked up through the replacement core's
:class:`~selfrepair.repair.core.CandidateTable`): short sequences of steps by
two roles, the robot with the incident (``r1``) and a teammate (``r2``), at symbolic places:

=====  =======================================================================================
``A``  where the item lies (its pickup cell, or wherever it was dropped)
``B``  the item's drop-off cell
``T``  the target of the failing drive
``H``  the cell of ``r1``
``N``  a free cell next to ``r1`` (where ``r2`` stands for a handover with ``r1`` in place)
``X``  another free cell next to ``r1`` (where ``r1`` moves to clear its cell)
``W``  a waypoint for a detour around what blocks the failing drive
``M1`` ``M2``  two adjacent cells where ``r1`` and ``r2`` meet for a handover
=====  =======================================================================================

A candidate also has a :class:`Scope`, the part of ``r1``'s queue it replaces: the failing action
only (``action``), the failing action up to and including the item's pick (``fetch``: ``r1``
then goes on with the item from the meeting point), or the rest of the delivery (``task``: every
queued action about the item, in every robot's queue). Where the single-robot table stores
concrete actions, a team table stores roles and places; :mod:`selfrepair.team.binding` binds them
to robots and cells when an incident happens and checks validity there.

Two tables (:class:`~selfrepair.team.model.TeamTableName`):

``handwritten``
    :data:`HANDWRITTEN`, the candidates a designer would write (the issue's examples: an item
    fetched and handed to the robot that could not reach it; the rest of a delivery taken over
    through a handover; a detour through a waypoint), in order of preference.
``generated``
    :func:`generate_table`: every minimal sequence of at most :data:`MAX_STEPS` steps that
    reaches the scope's goal in an abstract model of the situation (robots at places, who holds
    the item, what ``r1`` can still do), without the failing action. Minimal: leaving out any
    step breaks it. Ordered by scope (``action`` first: it disturbs least), then length.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass
from enum import StrEnum

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import choice
from selfrepair.team.model import ActionKind, IncidentKind, Load, TeamTableName

__all__ = [
    "HANDWRITTEN",
    "KEYS",
    "MAX_STEPS",
    "Key",
    "Known",
    "Place",
    "Role",
    "Scope",
    "Step",
    "TeamTable",
    "Template",
    "generate_table",
    "get_team_table",
    "markdown_team_table",
]

MAX_STEPS = 5
"""The longest generated candidate (a handover counts once)."""


class Role(StrEnum):
    """The robot with the incident (``r1``) and the teammate recruited (``r2``)."""

    FAULTY = "r1"
    HELPER = "r2"


class Place(StrEnum):
    """Symbolic places of a template (see the module docstring)."""

    ITEM = "A"
    DROPOFF = "B"
    TARGET = "T"
    HERE = "H"
    NEXT = "N"
    AWAY = "X"
    WAY = "W"
    MEET1 = "M1"
    MEET2 = "M2"
    START2 = "S"


class Scope(StrEnum):
    """How much of ``r1``'s queue a candidate replaces (see the module docstring)."""

    ACTION = "action"
    FETCH = "fetch"
    TASK = "task"


Known = tuple[IncidentKind, Load]
"""What is known to be wrong when a team action fails: why it failed, and whether ``r1`` carries
the item (a team table's counterpart of a robot's known faults)."""

Key = tuple[ActionKind, IncidentKind, Load]
"""What a team table is indexed by: failing action kind, incident kind, load of ``r1`` (the
action and what is :data:`Known`)."""


@dataclass(frozen=True, slots=True)
class Step:
    """One step of a template: ``kind`` by ``role`` (the giver, for a handover, with ``other``
    the taker), at ``place`` (drives only)."""

    kind: ActionKind
    role: Role
    place: Place | None = None
    other: Role | None = None

    def __str__(self) -> str:
        if self.kind is ActionKind.DRIVE:
            return f"drive({self.role},{self.place})"
        if self.kind is ActionKind.HANDOVER:
            return f"handover({self.role},{self.other})"
        return f"{self.kind}({self.role})"


@dataclass(frozen=True, slots=True)
class Template:
    """One candidate of a team table."""

    name: str
    steps: tuple[Step, ...]
    scope: Scope

    def __str__(self) -> str:
        return " ".join(str(s) for s in self.steps)

    @property
    def needs_helper(self) -> bool:
        """Whether a teammate takes part."""
        return any(s.role is Role.HELPER or s.other is Role.HELPER for s in self.steps)


@dataclass(frozen=True, slots=True)
class TeamTable:
    """A team replacement table: candidates per situation, in order of preference."""

    name: TeamTableName
    entries: dict[Key, tuple[Template, ...]]

    def candidates(self, action: ActionKind, known: Known) -> tuple[Template, ...]:
        """The candidates for the failing action's kind ``action`` under what is known to be
        wrong, ``known`` (none when the table has no entry): the replacement core's
        :class:`~selfrepair.repair.core.CandidateTable`, as a robot's table answers for an
        action and its known faults."""
        return self.entries.get((action, *known), ())

    def rows(self) -> Iterator[tuple[Key, Template]]:
        """Every (key, candidate) in key order, then preference order."""
        for key in KEYS:
            for template in self.entries.get(key, ()):
                yield key, template


def _d(role: Role, place: Place) -> Step:
    return Step(ActionKind.DRIVE, role, place)


def _pick(role: Role) -> Step:
    return Step(ActionKind.PICK, role)


def _drop(role: Role) -> Step:
    return Step(ActionKind.DROP, role)


def _give(giver: Role, taker: Role) -> Step:
    return Step(ActionKind.HANDOVER, giver, other=taker)


R1, R2 = Role.FAULTY, Role.HELPER
P = Place

_DETOUR = Template("detour", (_d(R1, P.WAY), _d(R1, P.TARGET)), Scope.ACTION)
_HAND_DELIVER = Template(
    "handover-deliver", (_d(R2, P.NEXT), _give(R1, R2), _d(R2, P.DROPOFF), _drop(R2)), Scope.TASK
)
_FETCH_DELIVER = Template(
    "fetch-deliver", (_d(R2, P.ITEM), _pick(R2), _d(R2, P.DROPOFF), _drop(R2)), Scope.TASK
)
_FETCH_HAND = Template(
    "fetch-hand",
    (_d(R2, P.ITEM), _pick(R2), _d(R2, P.MEET2), _d(R1, P.MEET1), _give(R2, R1)),
    Scope.FETCH,
)
_RELAY = Template(
    "relay",
    (_d(R1, P.MEET1), _d(R2, P.MEET2), _give(R1, R2), _d(R2, P.DROPOFF), _drop(R2)),
    Scope.TASK,
)
_CLEAR_FETCH = Template(
    "clear-fetch-deliver",
    (_d(R1, P.AWAY), _d(R2, P.ITEM), _pick(R2), _d(R2, P.DROPOFF), _drop(R2)),
    Scope.TASK,
)
_HAND_CLEAR_DROP = Template(
    "hand-clear-drop",
    (_d(R2, P.NEXT), _give(R1, R2), _d(R1, P.AWAY), _d(R2, P.DROPOFF), _drop(R2)),
    Scope.TASK,
)
_GIVER_DELIVERS = Template("giver-delivers", (_d(R2, P.DROPOFF), _drop(R2)), Scope.TASK)

KEYS: tuple[Key, ...] = (
    (ActionKind.DRIVE, IncidentKind.STUCK, Load.CARRYING),
    (ActionKind.DRIVE, IncidentKind.STUCK, Load.EMPTY),
    (ActionKind.DRIVE, IncidentKind.BLOCKED, Load.CARRYING),
    (ActionKind.DRIVE, IncidentKind.BLOCKED, Load.EMPTY),
    (ActionKind.PICK, IncidentKind.GRIPPER, Load.EMPTY),
    (ActionKind.DROP, IncidentKind.GRIPPER, Load.CARRYING),
    (ActionKind.HANDOVER, IncidentKind.GRIPPER, Load.EMPTY),
)
"""Every situation a team table can hold (a pick or drop never fails for want of motion or a
free path, and a drive never for want of a gripper)."""

HANDWRITTEN = TeamTable(
    TeamTableName.HANDWRITTEN,
    {
        KEYS[0]: (_HAND_DELIVER,),
        KEYS[1]: (_FETCH_DELIVER,),
        KEYS[2]: (_DETOUR, _RELAY, _HAND_DELIVER),
        KEYS[3]: (_DETOUR, _FETCH_HAND, _FETCH_DELIVER),
        KEYS[4]: (_CLEAR_FETCH,),
        KEYS[5]: (_HAND_CLEAR_DROP,),
        KEYS[6]: (_GIVER_DELIVERS,),
    },
)
"""The hand-written team table (see the module docstring)."""


def get_team_table(name: str) -> TeamTable:
    """The team table called ``name`` (the generated one is made once per process)."""
    table = choice(TeamTableName, name, "team table")
    if table is TeamTableName.HANDWRITTEN:
        return HANDWRITTEN
    return _GENERATED.get(MAX_STEPS, lambda: generate_table(MAX_STEPS))


_GENERATED: BoundedCache[int, TeamTable] = BoundedCache(
    "generated team tables", 2, kind=CacheKind.REPAIR
)


# --- generation -----------------------------------------------------------------------------------

_Item = str  # "r1", "r2" (carried) or a place name (on the floor there)
_State = tuple[Place, Place, _Item]


@dataclass(frozen=True, slots=True)
class _Situation:
    """The abstract model of one key: start state, what ``r1`` may do, the places in play."""

    key: Key
    start: _State
    places: tuple[Place, ...]
    here: Place
    r1_drives: bool
    r1_grips: bool
    scopes: tuple[Scope, ...]


def _situation(key: Key) -> _Situation:
    kind, incident, load = key
    if kind is ActionKind.PICK:
        here, item = P.ITEM, P.ITEM.value
    elif kind is ActionKind.DROP:
        here, item = P.DROPOFF, "r1"
    else:
        here, item = P.HERE, ("r1" if load is Load.CARRYING else P.ITEM.value)
    start2 = P.NEXT if kind is ActionKind.HANDOVER else P.START2
    if kind is ActionKind.HANDOVER:
        item = "r2"
    places = [P.ITEM, P.DROPOFF, P.NEXT, P.AWAY, P.MEET1, P.MEET2]
    if kind is ActionKind.DRIVE:
        places += [P.TARGET]
    if incident is IncidentKind.BLOCKED:
        places += [P.WAY]
    scopes: tuple[Scope, ...] = (Scope.TASK,)
    if incident is IncidentKind.BLOCKED:
        scopes = (
            (Scope.ACTION, Scope.FETCH, Scope.TASK)
            if load is Load.EMPTY
            else (
                Scope.ACTION,
                Scope.TASK,
            )
        )
    return _Situation(
        key,
        (here, start2, item),
        tuple(places),
        here,
        incident is not IncidentKind.STUCK,
        incident is not IncidentKind.GRIPPER,
        scopes,
    )


_R1_ONLY = frozenset({P.AWAY, P.WAY, P.MEET1, P.TARGET})
_R2_ONLY = frozenset({P.NEXT, P.MEET2})


def _adjacent(a: Place, b: Place, here: Place) -> bool:
    pair = {a, b}
    return pair == {here, P.NEXT} or pair == {P.MEET1, P.MEET2}


def _last_of(steps: tuple[Step, ...], role: Role) -> Step | None:
    for step in reversed(steps):
        if step.role is role or step.other is role:
            return step
    return None


def _moves(
    sit: _Situation, state: _State, steps: tuple[Step, ...]
) -> Iterator[tuple[Step, _State]]:
    """Every step applicable in ``state`` after ``steps`` (see :func:`generate_table`)."""
    pos1, pos2, item = state
    for role, here, there in ((R1, pos1, pos2), (R2, pos2, pos1)):
        if role is R1 and not sit.r1_drives:
            continue
        last = _last_of(steps, role)
        if last is not None and last.kind is ActionKind.DRIVE and last.place is not P.WAY:
            continue  # a robot's two drives in a row are one drive, except a detour's
        for place in sit.places:
            if place in (here, there) or (role is R1 and place in _R2_ONLY):
                continue
            if role is R2 and place in _R1_ONLY:
                continue
            if place is P.TARGET and here is not P.WAY:
                continue  # the failing drive itself, or a detour through another errand
            new = (place, pos2, item) if role is R1 else (pos1, place, item)
            yield _d(role, place), new
    for role, here in ((R1, pos1), (R2, pos2)):
        grips = sit.r1_grips or role is R2
        if grips and item == here.value:
            yield _pick(role), (pos1, pos2, role.value)
        if grips and item == role.value:
            yield _drop(role), (pos1, pos2, here.value)
    for giver, taker, gpos, tpos in ((R1, R2, pos1, pos2), (R2, R1, pos2, pos1)):
        can_take = sit.r1_grips or taker is R2
        if item == giver.value and can_take and _adjacent(gpos, tpos, sit.here):
            yield _give(giver, taker), (pos1, pos2, taker.value)


def _goal(sit: _Situation, scope: Scope, state: _State) -> bool:
    pos1, _, item = state
    if scope is Scope.TASK:
        return item == P.DROPOFF.value
    if scope is Scope.FETCH:
        return item == "r1"
    return pos1 is P.TARGET and item == sit.start[2]


def _run(sit: _Situation, steps: tuple[Step, ...]) -> _State | None:
    """The state after ``steps`` from the start, or ``None`` when one does not apply."""
    state = sit.start
    for n, step in enumerate(steps):
        for move, new in _moves(sit, state, steps[:n]):
            if move == step:
                state = new
                break
        else:
            return None
    return state


def _minimal(sit: _Situation, scope: Scope, steps: tuple[Step, ...]) -> bool:
    """Whether no proper subsequence of ``steps`` also reaches the goal."""
    for keep in itertools.product((True, False), repeat=len(steps)):
        if all(keep):
            continue
        shorter = tuple(s for s, k in zip(steps, keep, strict=True) if k)
        end = _run(sit, shorter)
        if end is not None and _goal(sit, scope, end):
            return False
    return True


def _canonical(steps: tuple[Step, ...]) -> tuple[tuple[Step, ...], tuple[Step, ...]]:
    """The per-robot step lists: what a candidate *is*, whatever the interleaving."""
    mine = tuple(s for s in steps if s.role is R1 or s.other is R1)
    theirs = tuple(s for s in steps if s.role is R2 or s.other is R2)
    return mine, theirs


def _search(sit: _Situation, scope: Scope, depth: int) -> list[tuple[Step, ...]]:
    found: dict[tuple[tuple[Step, ...], tuple[Step, ...]], tuple[Step, ...]] = {}

    def dfs(state: _State, steps: tuple[Step, ...], seen: frozenset[_State]) -> None:
        if _goal(sit, scope, state):
            if _minimal(sit, scope, steps):
                found.setdefault(_canonical(steps), steps)
            return
        if len(steps) == depth:
            return
        for step, new in _moves(sit, state, steps):
            if new not in seen:
                dfs(new, (*steps, step), seen | {new})

    dfs(sit.start, (), frozenset({sit.start}))
    return sorted(found.values(), key=lambda s: (len(s), [str(x) for x in s]))


def generate_table(max_steps: int = MAX_STEPS) -> TeamTable:
    """The generated team table (see the module docstring); a candidate equal to a hand-written
    one (the same steps per robot) keeps the hand-written name, the others are called ``gN``."""
    named = {(key, _canonical(t.steps)): t.name for key, t in HANDWRITTEN.rows()}
    entries: dict[Key, tuple[Template, ...]] = {}
    for key in KEYS:
        sit = _situation(key)
        templates: list[Template] = []
        for scope in sit.scopes:
            for steps in _search(sit, scope, max_steps):
                name = named.get((key, _canonical(steps)), f"g{len(templates) + 1}")
                templates.append(Template(name, steps, scope))
        entries[key] = tuple(templates)
    return TeamTable(TeamTableName.GENERATED, entries)


def markdown_team_table(table: TeamTable) -> str:
    """``table`` as a Markdown table (docs/team.md shows the hand-written one)."""
    lines = [
        "| failing action | incident | load | candidate | scope | steps |",
        "|:---|:---|:---|:---|:---|:---|",
    ]
    for (kind, incident, load), template in table.rows():
        steps = " ".join(f"`{s}`" for s in template.steps)
        lines.append(
            f"| {kind} | {incident} | {load} | {template.name} | {template.scope} | {steps} |"
        )
    return "\n".join(lines) + "\n"
