"""Explicit, bounded caches: the only place where selfrepair keeps derived data between calls.

Some values are expensive to derive and cheap to keep: a loaded table, the compiled look-ups of a
table under a fault set, a maze's occupancy grid, the exact optimum of a fault set. Each such cache
is a :class:`BoundedCache` made with a name, a :class:`CacheKind` and a maximum number of entries
(evicting the least recently used one), and marked ``per_map=True`` where its keys hold a map (a
maze, its free grid, or a value made for one map). Nothing hides scratch space inside frozen
values, and no module keeps a cache any other way (no ``functools.cache``, no module-level dict
filled on demand; a test scans the sources). :func:`cache_stats` lists every cache with its kind,
mark and size, so a user can see what the process keeps, and :func:`clear_caches` empties them
all, those of some kinds (the experiment runner's cold runs clear by kind:
:mod:`selfrepair.experiment.timing`) or only the per-map ones (what a plan on a map never planned
on finds empty while the process-wide caches stay filled: ``benchmarks/tolerant_planner.py``
times its ``first`` plans so). A test plans on a fresh maze and checks that every cache whose
keys then hold it is marked.

Keys must be hashable with a cheap hash: values such as mazes and tables cache their own hash.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterable, Iterator
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Generic, TypeVar

__all__ = ["BoundedCache", "CacheKind", "CacheStats", "cache_stats", "caches", "clear_caches"]

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")


class CacheKind(StrEnum):
    """What a cache holds, which decides whether a cold run empties it.

    A cold run (the first run of a mission, timed as a fresh process would pay it) empties the
    kinds whose work belongs to what is timed and keeps the rest; the policy is
    :data:`selfrepair.experiment.timing.COLD_CLEARS`.
    """

    INPUT = "input"
    """Parsed inputs: bundled and file tables, mazes, route files, package data listings."""
    REFERENCE = "reference"
    """Reference figures computed outside every clock (the fault-free optimum of a route)."""
    SIMULATION = "simulation"
    """The simulator's own tables (time units, move tables); no plan or repair reads them."""
    PREFILLED = "prefilled"
    """Derived data every mission computes before its clocks start (a table's reach and its
    candidates' geometry, the robot's open-plane moves)."""
    PLAN = "plan"
    """Planner data: lattices, distances, occupancy and clearance grids, kernel inputs."""
    REPAIR = "repair"
    """Replacement data: compiled look-ups, merged candidates, complex actions, optima."""
    RECORD = "record"
    """Texts and figures made for rows and traces after a run."""


@dataclass(frozen=True, slots=True)
class CacheStats:
    """One cache's name, kind, bound, current size and hit/miss counts since it was made or
    cleared, and whether its keys hold a map (``per_map``)."""

    name: str
    kind: CacheKind
    maxsize: int
    size: int
    hits: int
    misses: int
    per_map: bool = False


class BoundedCache(Generic[K, V]):
    """A named least-recently-used cache of at most ``maxsize`` entries of one ``kind`` (mutable
    by nature). ``per_map``: its keys hold a map (a maze, a free grid, or a value made for one
    map such as a step term), so its entries serve that map only."""

    __slots__ = ("_data", "hits", "kind", "maxsize", "misses", "name", "per_map")

    def __init__(self, name: str, maxsize: int, *, kind: CacheKind, per_map: bool = False) -> None:
        if maxsize < 1:
            raise ValueError(f"cache {name!r}: maxsize must be at least 1, got {maxsize}")
        self.name = name
        self.kind = kind
        self.per_map = per_map
        self.maxsize = maxsize
        self._data: OrderedDict[K, V] = OrderedDict()
        self.hits = 0
        self.misses = 0
        _ALL.append(self)

    def get(self, key: K, make: Callable[[], V]) -> V:
        """The value for ``key``, made with ``make()`` (and kept) on a miss."""
        data = self._data
        try:
            value = data[key]
        except KeyError:
            self.misses += 1
            value = make()
            data[key] = value
            if len(data) > self.maxsize:
                data.popitem(last=False)
            return value
        self.hits += 1
        data.move_to_end(key)
        return value

    def __len__(self) -> int:
        return len(self._data)

    def __iter__(self) -> Iterator[K]:
        """The keys kept now, least recently used first (a snapshot: getting may reorder them)."""
        return iter(tuple(self._data))

    def values(self) -> tuple[V, ...]:
        """The values kept now, least recently used first (e.g. to report their memory)."""
        return tuple(self._data.values())

    def __contains__(self, key: object) -> bool:
        return key in self._data

    def clear(self) -> None:
        """Forget every entry and reset the counters."""
        self._data.clear()
        self.hits = self.misses = 0

    def stats(self) -> CacheStats:
        """This cache's :class:`CacheStats`."""
        return CacheStats(
            self.name,
            self.kind,
            self.maxsize,
            len(self._data),
            self.hits,
            self.misses,
            self.per_map,
        )


_ALL: list[BoundedCache[Any, Any]] = []


def cache_stats() -> tuple[CacheStats, ...]:
    """Every cache made so far, by name."""
    return tuple(sorted((c.stats() for c in _ALL), key=lambda s: s.name))


def caches() -> tuple[BoundedCache[Any, Any], ...]:
    """Every cache made so far, in the order they were made (to read their keys, e.g. in a test
    that every cache keyed by a map says so)."""
    return tuple(_ALL)


def clear_caches(kinds: Iterable[CacheKind] | None = None, *, per_map: bool = False) -> None:
    """Empty every cache of the given ``kinds`` (every kind when ``None``), e.g. to measure the
    first, cold call of something; with ``per_map`` only those of them marked per-map (what a
    plan on a new map finds empty while the process-wide caches stay filled)."""
    chosen = frozenset(CacheKind) if kinds is None else frozenset(kinds)
    for cache in _ALL:
        if cache.kind in chosen and (cache.per_map or not per_map):
            cache.clear()
