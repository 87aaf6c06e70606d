"""Explicit, bounded caches: the only place where selfrepair keeps derived data between calls.

Some values are expensive to derive and cheap to keep: a loaded table, the compiled look-ups of a
table under a fault set, a maze's occupancy grid, the exact optimum of a fault set. Each such cache
is a :class:`BoundedCache` made here with a name and a maximum number of entries, evicting the least
recently used one. Nothing hides scratch space inside frozen values; :func:`cache_stats` lists
every cache with its size, so a user can see what the process keeps, and :func:`clear_caches`
empties them all (the tests use it to measure cold behaviour).

Keys must be hashable with a cheap hash: values such as mazes and tables cache their own hash.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

__all__ = ["BoundedCache", "CacheStats", "cache_stats", "clear_caches"]

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")


@dataclass(frozen=True, slots=True)
class CacheStats:
    """One cache's name, bound, current size and hit/miss counts since it was made or cleared."""

    name: str
    maxsize: int
    size: int
    hits: int
    misses: int


class BoundedCache(Generic[K, V]):
    """A named least-recently-used cache of at most ``maxsize`` entries (mutable by nature)."""

    __slots__ = ("_data", "hits", "maxsize", "misses", "name")

    def __init__(self, name: str, maxsize: int) -> None:
        if maxsize < 1:
            raise ValueError(f"cache {name!r}: maxsize must be at least 1, got {maxsize}")
        self.name = name
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
        return CacheStats(self.name, self.maxsize, len(self._data), self.hits, self.misses)


_ALL: list[BoundedCache[Any, Any]] = []


def cache_stats() -> tuple[CacheStats, ...]:
    """Every cache made so far, by name."""
    return tuple(sorted((c.stats() for c in _ALL), key=lambda s: s.name))


def clear_caches(keep: Iterable[str] = ()) -> None:
    """Empty every cache (e.g. to measure the first, cold call of something), except those named
    in ``keep``."""
    spared = frozenset(keep)
    for cache in _ALL:
        if cache.name not in spared:
            cache.clear()
