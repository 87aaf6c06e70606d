"""Compiled replacement look-ups: a table hit as one integer-keyed dictionary look-up.

Whether a candidate is valid at a pose depends only on the replaced action, the known faults, the
recursion mode (with its guard set and depth bound) and which cells around the pose are free. The
cells that matter form the action's **neighbourhood**: the union of every cell the search of
:func:`~selfrepair.repair.replacement.find_replacement` could test, relative to the pose, for each
heading (the footprints of every candidate's steps, nested candidates included, up to where a
candidate must stop whatever the walls). So per (table, action, known faults, recursion mode) the
search is compiled into a map from the neighbourhood's occupancy bits to its answer:

* the map's key is the **occupancy code** of the pose masked to the neighbourhood: every cell of
  a ``(2r+1) x (2r+1)`` window around a cell is one bit, precomputed once per
  :class:`~selfrepair.geometry.FreeGrid` and radius (:func:`occupancy_rows`, ``rows[y][x]``;
  cells beyond the grid's margin count as walls). A hit is then two list indices (row, column),
  one ``&`` and one dictionary look-up with an integer key;
* the map's value is the reference search's answer for that pattern, made pose-independent (the
  end pose is kept relative to the start cell). In flat mode, small neighbourhoods (at most
  :data:`ENUMERATE_BITS` cells besides the robot's own, which is always free) are enumerated on
  first use, all ``2^n`` patterns, by bit tests (the first candidate whose cells are all free);
  larger ones, and recursive modes, are filled lazily: the reference search runs once for each
  pattern actually met. Either way the answer equals the reference search's, including the
  candidate index, the nested depth and the number of candidates examined (a property test
  checks this over random mazes, poses, faults, tables and recursion modes).

What is kept, and the limits (all in :mod:`selfrepair.caching` caches, see :func:`cache_stats`):

* ``compiled replacement look-ups``: at most :data:`MAX_FAULT_LOOKUPS` (512)
  :class:`FaultLookups` (one per table, fault set, recursion mode, depth bound and answer kind),
  least recently used evicted. Each holds at most ``max_patterns`` stored patterns (default
  :data:`~selfrepair.limits.MAX_LOOKUP_PATTERNS`, 4096; ``--max-lookup-patterns``)
  over all its actions and headings; past that, answers are still correct but computed by the
  search each time.
* ``compiled look-ups on grids``: at most :data:`MAX_FAULT_LOOKUPS` :class:`GridLookups`, the
  per-(action, heading) references a hit reads on one grid (one list of ``4 x actions`` slots
  each; they may keep an evicted :class:`FaultLookups` or code list alive until evicted too).
* ``occupancy codes``: at most :data:`MAX_CODE_GRIDS` (16) code row lists (one per grid and
  radius), one pointer per cell plus one list per row and one integer object per distinct code
  (8 bytes a cell: a few kilobytes on the bundled mazes, about 2.1 MB on a 512x512 map, so at
  most 16 x 8 bytes x the largest grid's cells). They are made a band of
  :data:`~selfrepair.repair.neighbourhood.BAND` rows at a time, so making them needs little more
  than the lists themselves (:mod:`selfrepair.repair.neighbourhood` makes them).

Memory is measured by :func:`lookup_memory` with ``sys.getsizeof``: per :class:`FaultLookups`,
its per-action lists, each per-heading map (hash table), its integer keys and each distinct
answer with its action tuple (shallow: the action objects belong to the domain and are shared).
A stored pattern costs about 100 bytes, so one :class:`FaultLookups` stays below about 0.5 MB and
all of them below about 230 MB; typical ones hold 10 to 25 KB (``benchmarks/repair_latency.py``
prints them), about 2 MB for the whole paper experiment.

Action objects are found by identity first (``id(action)`` to the action's index in
``domain.actions``; the domain keeps those objects alive) and by equality only when a domain hands
out equal copies, because hashing a frozen-dataclass action costs more than the whole look-up.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass
from enum import Enum
from typing import Final, Generic, Literal, TypeVar, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError, choice
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.limits import MAX_LOOKUP_PATTERNS
from selfrepair.repair.neighbourhood import (
    MAX_CODE_GRIDS,
    ActionIndex,
    action_index,
    neighbourhood,
    neighbourhood_walk,
    occupancy_bit,
    occupancy_rows,
)
from selfrepair.repair.replacement import (
    DEFAULT_MAX_DEPTH,
    RecursionMode,
    Replacement,
    find_replacement,
    table_reach,
)
from selfrepair.robots.domain import A, F
from selfrepair.tables.model import ReplacementTable, SomeTable

__all__ = [
    "ENUMERATE_BITS",
    "MAX_CODE_GRIDS",
    "MAX_FAULT_LOOKUPS",
    "MAX_PATTERNS",
    "MISSING",
    "ActionIndex",
    "ActionLookup",
    "FaultLookups",
    "GridLookups",
    "LookupMemory",
    "Missing",
    "action_index",
    "compiled_replacement",
    "fault_lookups",
    "grid_lookups",
    "lookup_memory",
    "neighbourhood",
    "occupancy_rows",
    "same_replacement",
]

T = TypeVar("T")

ENUMERATE_BITS = 4
"""Flat-mode neighbourhoods of at most this many cells besides the robot's own are enumerated in
full (``2^n`` patterns) on first use; larger ones, and every neighbourhood of a recursive mode,
are filled per pattern met."""

MAX_PATTERNS = MAX_LOOKUP_PATTERNS
"""The default of stored patterns per :class:`FaultLookups` (all actions and headings together;
see :data:`selfrepair.limits.MAX_LOOKUP_PATTERNS`)."""

MAX_FAULT_LOOKUPS = 512
"""Compiled (table, fault set, recursion mode) look-ups kept per process: enough for a sweep's
working set (the paper experiment uses 3 tables x 12 fault sets x 3 modes)."""


class Missing(Enum):
    """The marker of a pattern not met yet (distinct from ``None``, "no valid candidate").

    It is false, like ``None``, so that a caller whose answers are always true (a strategy's
    :class:`tuple`-based repairs) tells a stored answer from both by one truth test."""

    MISSING = 0

    def __bool__(self) -> Literal[False]:
        return False


MISSING: Final = Missing.MISSING

Answer = Callable[[Replacement], T]
"""Turns a found replacement (end pose relative to the start cell) into the stored answer."""


# --- compiled look-ups --------------------------------------------------------------------------


class ActionLookup(Generic[T]):
    """The compiled look-up of one action under one fault set and recursion mode.

    ``radius`` is the window of the occupancy codes it reads (the table's reach, or more when
    nested candidates reach further, so that most look-ups of a table share one code list),
    ``masks[h]`` the neighbourhood bits
    for heading ``h`` and ``answers[h]`` the map from masked codes to answers (``None``: no valid
    candidate). Filled lazily (mutable by nature; bounded by the owner's ``max_patterns``).
    """

    __slots__ = ("action", "answers", "cells", "masks", "radius")

    def __init__(self, action: object, cells: tuple[frozenset[Cell], ...], radius: int) -> None:
        self.action = action
        self.cells = cells
        reach = max((max(abs(x), abs(y)) for per in cells for x, y in per), default=0)
        self.radius = max(reach, radius)
        self.masks = tuple(sum(1 << occupancy_bit(c, self.radius) for c in per) for per in cells)
        self.answers: tuple[dict[int, T | None], ...] = tuple({} for _ in cells)

    def patterns(self) -> int:
        """Patterns stored, over every heading."""
        return sum(len(a) for a in self.answers)


class FaultLookups(Generic[T]):
    """The compiled look-ups of one table under one fault set, recursion mode and depth bound.

    ``faulty[i]`` tells whether action ``i`` of the domain is unavailable under the faults
    (``faulty_slots[4 * i + heading]`` the same, per action and heading);
    :meth:`action` compiles an action's :class:`ActionLookup` on first use and :meth:`fill`
    answers a pattern met for the first time. ``answer`` turns a found replacement (end pose
    relative to the start cell) into what the maps store.
    """

    __slots__ = (
        "answer",
        "faulty",
        "faulty_slots",
        "guard",
        "index",
        "known",
        "lookups",
        "max_depth",
        "max_patterns",
        "mode",
        "radius",
        "stored",
        "table",
    )

    def __init__(
        self,
        table: SomeTable,
        known: frozenset[object],
        mode: RecursionMode,
        max_depth: int,
        answer: Answer[T],
        guard: frozenset[object] = frozenset(),
        max_patterns: int = MAX_PATTERNS,
    ) -> None:
        domain = table.domain
        self.table = table
        self.known = known
        self.mode = mode
        self.max_depth = max_depth
        self.answer = answer
        self.guard = guard
        self.index = action_index(domain)
        self.faulty = tuple(not domain.available(a, known) for a in domain.actions)
        self.faulty_slots = tuple(bad for bad in self.faulty for _ in Heading)
        self.lookups: list[ActionLookup[T] | None] = [None] * len(domain.actions)
        self.stored = 0
        self.max_patterns = max_patterns
        self.radius = table_reach(table)

    def action(self, i: int) -> ActionLookup[T]:
        """The look-up of action ``i`` (compiled, and enumerated when small, on first use)."""
        lookup = self.lookups[i]
        if lookup is None:
            lookup = self._compile(i)
            self.lookups[i] = lookup
        return lookup

    def _compile(self, i: int) -> ActionLookup[T]:
        action = self.table.domain.actions[i]
        walk = neighbourhood_walk(self.table, self.known, self.mode, self.max_depth)
        replacing = self.guard | {action}
        cells = tuple(walk.cells(action, h, replacing, 0) for h in range(len(Heading)))
        lookup: ActionLookup[T] = ActionLookup(action, cells, self.radius)
        if self.mode is RecursionMode.FLAT:
            for heading in Heading:
                others = sorted(cells[heading] - {(0, 0)})
                budget = self.stored + (1 << len(others)) <= self.max_patterns
                if len(others) <= ENUMERATE_BITS and budget:
                    self._enumerate(lookup, heading, others, (0, 0) in cells[heading])
        return lookup

    def _enumerate(
        self, lookup: ActionLookup[T], heading: Heading, others: list[Cell], own: bool
    ) -> None:
        """Answer every pattern of a flat-mode neighbourhood (the robot's own cell free).

        In flat mode a candidate is valid exactly when it does not use the replaced action, all
        its actions are available and all its cells are free, so each pattern's answer is the
        first candidate whose cells it contains: bit tests, no search. (Recursive modes are
        filled per pattern met instead: enumerating them would run an exhaustive recursive
        search for every pattern, tens of milliseconds for one action.)
        """
        dom = self.table.domain
        action = lookup.action
        bit_of = {c: 1 << k for k, c in enumerate(others)}
        usable = []
        replacing = self.guard | {action}
        for position, candidate in enumerate(self.table.candidates(action, self.known)):
            if not replacing.isdisjoint(candidate) or not all(
                dom.available(b, self.known) for b in candidate
            ):
                continue
            state, need = Pose(0, 0, heading), 0
            for b in candidate:
                need |= sum(bit_of.get(c, 0) for c in dom.footprint(state, b))
                state = dom.apply(state, b)
            found = Replacement(action, candidate, candidate, position, 0, position + 1, state)
            usable.append((need, self.answer(found)))
        radius = lookup.radius
        answers = lookup.answers[heading]
        own_bit = 1 << occupancy_bit((0, 0), radius) if own else 0
        for pattern in range(1 << len(others)):
            bits = (1 << occupancy_bit(c, radius) for c, b in bit_of.items() if pattern & b)
            key = own_bit | sum(bits)
            answers[key] = next((value for need, value in usable if need & ~pattern == 0), None)
            self.stored += 1

    def fill(self, lookup: ActionLookup[T], pose: Pose, key: int, grid: FreeGrid) -> T | None:
        """The answer at ``pose`` for a pattern not stored yet: the reference search, kept for
        the next pose with the same pattern (while the pattern budget lasts)."""
        found = find_replacement(
            self.table,
            lookup.action,
            pose,
            self.known,
            grid.all_free,
            mode=self.mode,
            max_depth=self.max_depth,
            guard=self.guard,
        )
        value = None if found is None else self.answer(_relative(found, pose))
        if self.stored < self.max_patterns:
            lookup.answers[pose.heading][key] = value
            self.stored += 1
        return value

    def get(self, action: object, pose: Pose, grid: FreeGrid) -> T | None:
        """The answer for ``action`` at ``pose`` on ``grid`` (the convenient, slower entry: the
        strategies inline this)."""
        lookup = self.action(self.index.of(action))
        rows = occupancy_rows(grid, lookup.radius)
        key = rows[pose.y][pose.x] & lookup.masks[pose.heading]
        value = lookup.answers[pose.heading].get(key, MISSING)
        if value is MISSING:
            return self.fill(lookup, pose, key, grid)
        return value

    def memory(self) -> LookupMemory:
        """What this look-up holds now (see :func:`lookup_memory`)."""
        compiled = [lk for lk in self.lookups if lk is not None]
        size = sys.getsizeof(self.lookups) + sys.getsizeof(self.faulty)
        seen: set[int] = set()
        for lookup in compiled:
            size += sys.getsizeof(lookup.masks) + sys.getsizeof(lookup.answers)
            for answers in lookup.answers:
                size += sys.getsizeof(answers)
                for key, value in answers.items():
                    size += sys.getsizeof(key)
                    if value is not None and id(value) not in seen:
                        seen.add(id(value))
                        size += _answer_size(value)
        dom = self.table.domain
        return LookupMemory(
            self.table.source,
            dom.format_faults(self.known),
            self.mode,
            _key(self.mode, self.max_depth),
            len(compiled),
            sum(lk.patterns() for lk in compiled),
            size,
        )


def _answer_size(value: object) -> int:
    size = sys.getsizeof(value)
    actions = getattr(value, "actions", None)
    if isinstance(actions, tuple):
        size += sys.getsizeof(actions)
    return size


def _relative(found: Replacement, pose: Pose) -> Replacement:
    end = found.end
    return found._replace(end=Pose(end.x - pose.x, end.y - pose.y, end.heading))


_DEPTH_BOUNDED = frozenset({RecursionMode.GUARDED, RecursionMode.PRIMITIVE})
"""Recursion modes whose rule reads the depth bound (``primitive`` recurses as ``guarded``)."""


def _key(mode: RecursionMode, max_depth: int) -> int:
    """The depth bound matters in depth-bounded modes only; others share one compiled look-up."""
    return max_depth if mode in _DEPTH_BOUNDED else 0


_LOOKUPS: BoundedCache[
    tuple[object, frozenset[object], RecursionMode, int, Hashable, frozenset[object], int], object
] = BoundedCache("compiled replacement look-ups", MAX_FAULT_LOOKUPS, kind=CacheKind.REPAIR)


def fault_lookups(
    table: ReplacementTable[A, F],
    known: Iterable[F],
    *,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
    answer: Answer[T],
    guard: frozenset[A] = frozenset(),
    max_patterns: int = MAX_PATTERNS,
) -> FaultLookups[T]:
    """The compiled look-ups of ``table`` under ``known`` faults in recursion ``mode`` (made on
    first use, kept in a bounded cache). ``answer`` must be a module-level function: it is part
    of the cache key. ``guard``: actions an outer replacement is still replacing (none of them
    is used; see :func:`~selfrepair.repair.replacement.find_replacement`). ``max_patterns``:
    patterns stored at most (see :data:`~selfrepair.limits.MAX_LOOKUP_PATTERNS`)."""
    if max_patterns < 0:
        raise ProblemError(f"max_patterns must be at least 0, got {max_patterns}")
    recursion = (
        mode if type(mode) is RecursionMode else choice(RecursionMode, mode, "recursion mode")
    )
    if max_depth < 0:
        raise ProblemError(f"max_depth must be at least 0, got {max_depth}")
    faults = known if type(known) is frozenset else frozenset(known)
    depth = _key(recursion, max_depth)
    key = (table, faults, recursion, depth, answer, guard, max_patterns)
    args = (table, faults, recursion, max_depth, answer, guard, max_patterns)
    # the key holds ``answer``, so the value's answers are of its type T
    return cast("FaultLookups[T]", _LOOKUPS.get(key, lambda: FaultLookups(*args)))


def same_replacement(found: Replacement) -> Replacement:
    """The answer that is the replacement found itself (every field, ``deferred`` included): one
    module-level function, so every reader of these look-ups shares one cache entry."""
    return found


def compiled_replacement(
    table: ReplacementTable[A, F],
    action: A,
    pose: Pose,
    known_faults: Iterable[F],
    grid: FreeGrid,
    *,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
    guard: Iterable[A] = (),
    max_patterns: int = MAX_PATTERNS,
) -> Replacement | None:
    """:func:`~selfrepair.repair.replacement.find_replacement` through the compiled look-ups:
    the same answer (every field, ``deferred`` included), from one look-up once the pattern has
    been met."""
    lookups = fault_lookups(
        table,
        known_faults,
        mode=mode,
        max_depth=max_depth,
        answer=same_replacement,
        guard=frozenset(guard),
        max_patterns=max_patterns,
    )
    found: Replacement | None = lookups.get(action, pose, grid)
    if found is None:
        return None
    end = found.end
    return found._replace(end=Pose(pose.x + end.x, pose.y + end.y, end.heading))


# --- look-ups read on one grid -------------------------------------------------------------------

Slot = tuple[int, dict[int, T | None], list[list[int]]]
"""What a hit reads for one (action, heading): the neighbourhood mask, the map from masked codes
to answers, and the grid's occupancy codes at the look-up's radius by row
(:func:`occupancy_rows`: ``rows[y][x]``)."""


class GridLookups(Generic[T]):
    """The compiled look-ups of one fault set (:class:`FaultLookups`) as read on one grid.

    ``slots[4 * i + heading]`` holds what a hit of action ``i`` from ``heading`` reads
    (:data:`Slot`), filled on first use, for all four headings at once. Shared by every mission
    on the same grid under the same faults, so a mission does not refill them (mutable by
    nature; bounded by the number of slots).
    """

    __slots__ = ("grid", "lookups", "slots")

    def __init__(self, lookups: FaultLookups[T], grid: FreeGrid) -> None:
        self.lookups = lookups
        self.grid = grid
        self.slots: list[Slot[T] | None] = [None] * len(lookups.faulty_slots)

    def slot(self, slot: int) -> Slot[T]:
        """Fill the four slots of the action of ``slot`` (compiling its look-up if need be)."""
        first = slot & ~3
        lookup = self.lookups.action(first >> 2)
        rows = occupancy_rows(self.grid, lookup.radius)
        for heading in range(4):
            self.slots[first + heading] = (lookup.masks[heading], lookup.answers[heading], rows)
        return (lookup.masks[slot & 3], lookup.answers[slot & 3], rows)

    def fill(self, slot: int, x: int, y: int, key: int) -> T | None:
        """Answer a pattern met for the first time at cell ``(x, y)`` (see
        :meth:`FaultLookups.fill`)."""
        lookups = self.lookups
        pose = Pose(x, y, Heading(slot & 3))
        found: T | None = lookups.fill(lookups.action(slot >> 2), pose, key, self.grid)
        return found


_ON_GRIDS: BoundedCache[tuple[object, FreeGrid], object] = BoundedCache(
    "compiled look-ups on grids", MAX_FAULT_LOOKUPS, kind=CacheKind.REPAIR
)


def grid_lookups(lookups: FaultLookups[T], grid: FreeGrid) -> GridLookups[T]:
    """``lookups`` as read on ``grid`` (kept per fault set and grid, a bounded number)."""
    found = _ON_GRIDS.get((lookups, grid), lambda: GridLookups(lookups, grid))
    return cast("GridLookups[T]", found)  # keyed by ``lookups``: its answers


# --- memory -------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class LookupMemory:
    """What one compiled (table, fault set, mode) look-up holds: compiled actions, stored
    patterns and approximate bytes (``sys.getsizeof``, see the module docstring). ``max_depth``
    is 0 except in the modes it changes (guarded, primitive)."""

    table: str
    faults: str
    mode: RecursionMode
    max_depth: int
    actions: int
    patterns: int
    bytes: int


def lookup_memory() -> tuple[LookupMemory, ...]:
    """The memory of every compiled look-up kept now, largest first."""
    items = [v.memory() for v in _LOOKUPS.values() if isinstance(v, FaultLookups)]  # all are
    return tuple(sorted(items, key=lambda m: (-m.bytes, m.table, m.faults, m.mode)))
