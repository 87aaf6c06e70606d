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

This module keeps the look-ups (the bounded cache, :func:`fault_lookups`, :func:`lookup_memory`)
and is where callers take every name from; the maps themselves are
:mod:`selfrepair.repair.lookup_maps` (:class:`ActionLookup`, :class:`FaultLookups`) and their
reading on one grid :mod:`selfrepair.repair.grid_lookups` (:class:`GridLookups`).
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable
from typing import TypeVar, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError, choice
from selfrepair.geometry import FreeGrid, Pose
from selfrepair.repair.grid_lookups import GridLookups, grid_lookups
from selfrepair.repair.lookup_maps import (
    ENUMERATE_BITS,
    MAX_FAULT_LOOKUPS,
    MAX_PATTERNS,
    MISSING,
    ActionLookup,
    Answer,
    FaultLookups,
    LookupMemory,
    Missing,
    depth_key,
)
from selfrepair.repair.neighbourhood import (
    MAX_CODE_GRIDS,
    ActionIndex,
    action_index,
    neighbourhood,
    occupancy_rows,
)
from selfrepair.repair.replacement import (
    DEFAULT_MAX_DEPTH,
    RecursionMode,
    Replacement,
)
from selfrepair.robots.domain import A, F
from selfrepair.tables.model import ReplacementTable

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
    depth = depth_key(recursion, max_depth)
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


def lookup_memory() -> tuple[LookupMemory, ...]:
    """The memory of every compiled look-up kept now, largest first."""
    items = [v.memory() for v in _LOOKUPS.values() if isinstance(v, FaultLookups)]  # all are
    return tuple(sorted(items, key=lambda m: (-m.bytes, m.table, m.faults, m.mode)))
