"""The compiled look-up maps of one replacement table: per action, heading, fault set and
recursion mode, a map from a pose's masked occupancy code to the reference search's answer.

:class:`FaultLookups` holds them for one (table, fault set, recursion mode, depth bound, answer
kind) and :class:`ActionLookup` for one action of it; what they store, how they are filled
(enumerated when small, per pattern met otherwise) and their limits are described in
:mod:`selfrepair.repair.lookups`, which keeps them in a bounded cache
(:func:`~selfrepair.repair.lookups.fault_lookups`) and is where callers take them from.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import Final, Generic, Literal, TypeVar

from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.limits import MAX_LOOKUP_PATTERNS
from selfrepair.repair.neighbourhood import (
    NeighbourhoodWalk,
    action_index,
    neighbourhood_walk,
    occupancy_bit,
    occupancy_rows,
)
from selfrepair.repair.replacement import (
    RecursionMode,
    Replacement,
    find_replacement,
    table_reach,
)
from selfrepair.tables.model import SomeTable

__all__ = [
    "ENUMERATE_BITS",
    "MAX_FAULT_LOOKUPS",
    "MAX_PATTERNS",
    "MISSING",
    "ActionLookup",
    "Answer",
    "FaultLookups",
    "LookupMemory",
    "Missing",
    "depth_key",
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
        "walk",
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
        # one walk for every action: its memo of sub-neighbourhoods is shared between them
        self.walk: NeighbourhoodWalk[object, object] | None = None

    def action(self, i: int) -> ActionLookup[T]:
        """The look-up of action ``i`` (compiled, and enumerated when small, on first use)."""
        lookup = self.lookups[i]
        if lookup is None:
            lookup = self._compile(i)
            self.lookups[i] = lookup
        return lookup

    def _compile(self, i: int) -> ActionLookup[T]:
        action = self.table.domain.actions[i]
        walk = self.walk
        if walk is None:
            walk = neighbourhood_walk(self.table, self.known, self.mode, self.max_depth)
            self.walk = walk
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
        """What this look-up holds now (see :func:`selfrepair.repair.lookups.lookup_memory`)."""
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
            depth_key(self.mode, self.max_depth),
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


def depth_key(mode: RecursionMode, max_depth: int) -> int:
    """The depth bound matters in depth-bounded modes only; others share one compiled look-up."""
    return max_depth if mode in _DEPTH_BOUNDED else 0


@dataclass(frozen=True, slots=True)
class LookupMemory:
    """What one compiled (table, fault set, mode) look-up holds: compiled actions, stored
    patterns and approximate bytes (``sys.getsizeof``, see :mod:`selfrepair.repair.lookups`).
    ``max_depth`` is 0 except in the modes it changes (guarded, primitive)."""

    table: str
    faults: str
    mode: RecursionMode
    max_depth: int
    actions: int
    patterns: int
    bytes: int
