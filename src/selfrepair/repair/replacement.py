"""Run-time replacement: the first valid candidate from a table, in one of three recursion modes.

A replacement for action ``a`` at state ``s`` is a sub-plan without ``a`` whose actions are each
executable in turn from ``s`` and which ends where ``a`` would have ended. Table candidates end in
the right place by construction (tables are re-simulated when built), so at run time a candidate
is **valid** when

1. every action in it is available under the known faults, or can itself be replaced (how, depends
   on the recursion mode below);
2. every step is executable from its state: the domain's footprint cells are all free;
3. it uses no action that is currently being replaced (the guard that stops recursion from
   deadlocking, e.g. ``R -> L L L`` and ``L -> R R R`` calling each other for ever).

Recursion modes (:class:`RecursionMode`; registry :data:`RECURSION_MODES` of their rules):

``flat``
    Only candidates whose actions are all healthy. Never recurses, cheapest, always terminates.
    Gives up: every candidate that would need a faulty action replaced in turn, so with two faults
    it fails more often than the others.
``guarded``
    A faulty action inside a candidate is replaced recursively, carrying down the set of actions
    being replaced so that none of them is reused at any depth, and stopping at ``max_depth``
    nested levels. Gives up: completeness beyond the depth bound, and its worst-case cost grows
    exponentially with the depth (each level may scan every candidate of the table).
``primitive``
    The original paper's primitive/complex scheme (its section 4). An action is **primitive** in
    a table when it has candidates and every one of them is made of at most two different actions
    (``L -> R R R``; forward as turn round + back up + turn round); every other action is
    **complex** (:func:`complex_actions`; under the known faults, as the table looks them up).
    When a candidate is tested, a faulty primitive action inside it is replaced recursively, as
    in ``guarded`` (guard set, ``max_depth``); a faulty complex action is **not checked unless it
    comes first**: it stays in the replacement unreplaced (``Replacement.deferred``), and is
    replaced when the robot reaches it, as any faulty action met during execution (the
    ``replacement`` strategy carries the guard set over to that later repair). A complex action
    that comes first is checked like any action: it must be available, since it runs next.
    Healthy actions are always checked for walls, complex ones included: executing one blind
    could drive the robot into a wall. Gives up: a deferred action may turn out to have no
    valid replacement when it is reached, and then the robot replans from wherever it is, after
    executing part of a replacement it cannot finish.
``layered``
    Actions are split into levels by the domain (``Domain.level``: primitive 0, complex higher).
    A faulty action inside a candidate may be replaced recursively only when its level is lower
    than that of the action being replaced, so recursion ends after at most as many steps as there
    are levels, whatever the table holds. Gives up: a faulty action of the same or a higher level
    can never be replaced inside a candidate (for the four-wheel robot, a faulty turn inside a turn
    replacement, or a faulty arc inside anything), and a faulty primitive action has only its
    all-healthy candidates, as in ``flat``.

The search is the replacement core's (:mod:`selfrepair.repair.core`, the same validity test a team's
replacement uses) over :class:`RobotWorld`, the robot's primitive actions. It is greedy but
complete within each mode: every sub-replacement of an action ``b`` from a
state ends in the same state, so the first valid sub-replacement found is as good as any other for
the rest of the candidate.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from enum import StrEnum
from typing import Generic, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError, choice
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.core import CoreSearch, RecurseRule, Replacement
from selfrepair.robots.domain import A, Domain, F, SomeDomain
from selfrepair.tables.model import ReplacementTable

__all__ = [
    "DEFAULT_MAX_DEPTH",
    "RECURSION_MODES",
    "FreeTest",
    "RecurseRule",
    "RecursionMode",
    "Replacement",
    "RobotWorld",
    "complex_actions",
    "find_replacement",
    "flat_replacement",
    "is_valid_replacement",
    "table_reach",
]

DEFAULT_MAX_DEPTH = 2
"""Nested replacement levels allowed in ``guarded`` mode by default."""

FreeTest = Callable[[tuple[Cell, ...]], bool]
"""Whether every cell of a footprint is free (e.g. ``FreeGrid.all_free``)."""


class RecursionMode(StrEnum):
    """How a faulty action inside a candidate may itself be replaced (see the module docstring)."""

    FLAT = "flat"
    GUARDED = "guarded"
    LAYERED = "layered"
    PRIMITIVE = "primitive"


ModeRule = Callable[[SomeDomain, int], RecurseRule]
"""A recursion mode: given the domain and the depth bound, its recursion rule."""


def _flat(domain: Domain[A, F], max_depth: int) -> RecurseRule:
    """Never recurse: only candidates whose actions are all healthy."""
    return lambda b, a, d: False


def _guarded(domain: Domain[A, F], max_depth: int) -> RecurseRule:
    """Recurse while shallower than ``max_depth`` (the guard set is carried by the search)."""
    return lambda b, a, d: d < max_depth


def _layered(domain: Domain[A, F], max_depth: int) -> RecurseRule:
    """Recurse only into strictly lower-level actions, so recursion always terminates."""
    level = domain.level
    return lambda b, a, d: level(b) < level(a)


RECURSION_MODES: dict[RecursionMode, ModeRule] = {
    RecursionMode.FLAT: _flat,
    RecursionMode.GUARDED: _guarded,
    RecursionMode.LAYERED: _layered,
    RecursionMode.PRIMITIVE: _guarded,  # for primitive actions; complex ones are deferred
}
"""The rule of each recursion mode (see the module docstring for what each gives up). In
``primitive`` mode the rule applies to primitive actions; :data:`DEFERRING` modes also leave
faulty complex actions (:func:`complex_actions`) to be replaced when they are reached."""

DEFERRING = frozenset({RecursionMode.PRIMITIVE})
"""Modes whose replacements may keep faulty complex actions for later (``Replacement.deferred``);
the replacement strategy's whole-plan rewriting does not model them, so in these modes it reads
look-ups per guard set (:class:`~selfrepair.repair.strategies.replacement.DeferringRepairer`; the
compiled mission loop does the same)."""

PRIMITIVE_DISTINCT = 2
"""An action is primitive when every candidate for it uses at most this many different actions."""


def complex_actions(table: ReplacementTable[A, F], known: frozenset[F]) -> frozenset[A]:
    """The actions that are complex in ``table`` under the faults ``known`` (see the module
    docstring, ``primitive`` mode): no candidate, or some candidate made of more than
    :data:`PRIMITIVE_DISTINCT` different actions. Computed once per (table, faults)."""
    # keyed by the table: the value holds its actions
    return cast("frozenset[A]", _COMPLEX.get((table, known), lambda: _complex(table, known)))


def _complex(table: ReplacementTable[A, F], known: frozenset[F]) -> frozenset[A]:
    out: set[A] = set()
    for action in table.domain.actions:
        candidates = table.candidates(action, known)
        if not candidates or any(len(set(c)) > PRIMITIVE_DISTINCT for c in candidates):
            out.add(action)
    return frozenset(out)


_COMPLEX: BoundedCache[tuple[object, frozenset[object]], frozenset[object]] = BoundedCache(
    "complex actions", 256, kind=CacheKind.REPAIR
)


@dataclass(frozen=True, slots=True)
class RobotWorld(Generic[A, F]):
    """One robot's primitive actions as the replacement core sees them
    (:class:`~selfrepair.repair.core.LiftedWorld`): an action is healthy when the known faults
    leave it available, and executable from a pose when its footprint there is free; it binds to
    itself and leads to the pose the domain says."""

    domain: Domain[A, F]
    known: frozenset[F]
    free: FreeTest

    def healthy(self, action: A, state: Pose) -> bool:
        """Whether the known faults leave ``action`` available."""
        return self.domain.available(action, self.known)

    def advance(self, action: A, state: Pose) -> tuple[tuple[A, ...], Pose] | None:
        """``((action,), end)`` when ``action``'s footprint at ``state`` is free, else ``None``."""
        domain = self.domain
        if not self.free(domain.footprint(state, action)):
            return None
        return (action,), domain.apply(state, action)


def find_replacement(
    table: ReplacementTable[A, F],
    action: A,
    state: Pose,
    known_faults: Iterable[F],
    free: FreeTest,
    *,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
    guard: Iterable[A] = (),
) -> Replacement | None:
    """The first valid replacement for ``action`` at ``state``, or ``None`` when there is none.

    ``free`` tells whether a footprint is executable (all cells free), e.g. ``FreeGrid.all_free``.
    Every action of the returned ``actions`` is available under ``known_faults`` and executable in
    turn from ``state``, except those at ``deferred`` positions (``primitive`` mode); none of them
    is ``action`` or in ``guard`` (actions an outer replacement is still replacing).
    """
    chosen = choice(RecursionMode, mode, "recursion mode")
    rule = RECURSION_MODES[chosen]
    if action not in table.domain.action_set:
        raise ProblemError(f"{action!r} is not an action of domain {table.domain.name!r}")
    if max_depth < 0:
        raise ProblemError(f"max_depth must be at least 0, got {max_depth}")
    known = frozenset(known_faults)
    deferrable = complex_actions(table, known) if chosen in DEFERRING else frozenset()
    domain = table.domain
    search: CoreSearch[A, Pose] = CoreSearch(
        RobotWorld(domain, known, free),
        lambda a: table.candidates(a, known),
        rule(domain, max_depth),
        deferrable,
        domain.apply,
    )
    return search.replace(action, state, frozenset(guard) | {action}, 0)


def is_valid_replacement(
    domain: Domain[A, F],
    action: A,
    state: Pose,
    actions: Iterable[A],
    known_faults: Iterable[F],
    free: FreeTest,
    *,
    deferred: Iterable[int] = (),
) -> bool:
    """Check the definition directly: no ``action``, each step available and executable in turn,
    and the end state equal to ``action``'s end state. Steps at ``deferred`` positions (never the
    first) are only followed, not checked: they are replaced when reached. Used by tests and trace
    checks."""
    known = frozenset(known_faults)
    later = frozenset(deferred)
    target = domain.apply(state, action)
    seq = tuple(actions)
    if not seq or action in seq or 0 in later:
        return False
    for i, b in enumerate(seq):
        if i in later:
            state = domain.apply(state, b)
            continue
        if not domain.available(b, known) or not free(domain.footprint(state, b)):
            return False
        state = domain.apply(state, b)
    return bool(state == target)


# --- fast path: flat mode on a free grid --------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Geometry:
    """A candidate's cells relative to its start cell, and its end pose relative to the start,
    for each start heading."""

    cells: tuple[tuple[Cell, ...], ...]
    ends: tuple[Pose, ...]
    reach: int


def _geometry(domain: Domain[A, F], candidate: tuple[A, ...]) -> _Geometry:
    cells_by_heading = []
    ends = []
    for heading in Heading:
        state = Pose(0, 0, heading)
        cells: dict[Cell, None] = {}
        for b in candidate:
            cells.update(dict.fromkeys(domain.footprint(state, b)))
            state = domain.apply(state, b)
        cells_by_heading.append(tuple(cells))
        ends.append(state)
    reach = max(max(abs(x), abs(y)) for per in cells_by_heading for x, y in per)
    return _Geometry(tuple(cells_by_heading), tuple(ends), reach)


_GEOMETRY: BoundedCache[tuple[object, tuple[object, ...]], _Geometry] = BoundedCache(
    "candidate geometry", 1 << 16, kind=CacheKind.PREFILLED
)


def _candidate_geometry(domain: Domain[A, F], candidate: tuple[A, ...]) -> _Geometry:
    return _GEOMETRY.get((domain, candidate), lambda: _geometry(domain, candidate))


def table_reach(table: ReplacementTable[A, F]) -> int:
    """How many cells (Chebyshev) from its start cell any candidate of ``table`` reaches: the
    margin a :class:`~selfrepair.geometry.FreeGrid` needs for :func:`flat_replacement`.

    The first call for a table also computes the fault-independent geometry of every candidate,
    so that a first look-up under new faults only filters candidates by availability.
    """
    return _REACH.get(table, lambda: _reach(table))


def _reach(table: ReplacementTable[A, F]) -> int:
    return max(
        (
            _candidate_geometry(table.domain, c).reach
            for entry in table.entries
            for c in entry.candidates
        ),
        default=0,
    )


_REACH: BoundedCache[object, int] = BoundedCache("table reach", 64, kind=CacheKind.PREFILLED)


@dataclass(frozen=True, slots=True)
class _Compiled(Generic[A]):
    """A healthy candidate, ready to test: its cells as buffer offsets per heading."""

    position: int
    candidate: tuple[A, ...]
    offsets: tuple[tuple[int, ...], ...]
    ends: tuple[Pose, ...]


def _compile_flat(
    table: ReplacementTable[A, F], action: A, known: frozenset[F], stride: int
) -> tuple[_Compiled[A], ...]:
    domain = table.domain
    compiled: list[_Compiled[A]] = []
    for position, candidate in enumerate(table.candidates(action, known)):
        if action in candidate or not all(domain.available(b, known) for b in candidate):
            continue
        geometry = _candidate_geometry(domain, candidate)
        offsets = tuple(tuple(y * stride + x for x, y in cells) for cells in geometry.cells)
        compiled.append(_Compiled(position, candidate, offsets, geometry.ends))
    return tuple(compiled)


_COMPILED: BoundedCache[tuple[object, object, frozenset[object], int], tuple[object, ...]] = (
    BoundedCache("compiled flat look-ups", 1 << 14, kind=CacheKind.REPAIR)
)


def flat_replacement(
    table: ReplacementTable[A, F],
    action: A,
    pose: Pose,
    known_faults: frozenset[F],
    grid: FreeGrid,
) -> Replacement | None:
    """``find_replacement(..., mode="flat")`` on a :class:`~selfrepair.geometry.FreeGrid`, at a
    fraction of the cost.

    Per (table, action, known faults, grid stride) the healthy candidates are compiled once into
    buffer offsets per heading; a look-up is then a few byte reads per candidate. ``grid`` must
    have a margin of at least :func:`table_reach` cells. Returns the same replacement as the
    general flat search (a property test checks this).
    """
    stride = grid.stride
    key = (table, action, known_faults, stride)

    def compile_flat() -> tuple[_Compiled[A], ...]:
        return _compile_flat(table, action, known_faults, stride)

    # keyed by the table: the value is compiled from its candidates
    compiled = cast("tuple[_Compiled[A], ...]", _COMPILED.get(key, compile_flat))
    data = grid.data
    base = grid.index(pose.x, pose.y)
    heading = pose.heading
    for item in compiled:
        for offset in item.offsets[heading]:
            if not data[base + offset]:
                break
        else:
            end = item.ends[heading]
            return Replacement(
                action,
                item.candidate,
                item.candidate,
                item.position,
                0,
                item.position + 1,
                Pose(pose.x + end.x, pose.y + end.y, end.heading),
            )
    return None
