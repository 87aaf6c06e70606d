"""The compiled look-ups of one fault set as read on one grid: what a hit of the compiled mission
loop or of a strategy reads for one (action, heading), filled on first use and shared by every
mission on the same grid under the same faults (see :mod:`selfrepair.repair.lookups`).
"""

from __future__ import annotations

from typing import Generic, TypeVar, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import FreeGrid, Heading, Pose
from selfrepair.repair.lookup_maps import MAX_FAULT_LOOKUPS, FaultLookups
from selfrepair.repair.neighbourhood import occupancy_rows

__all__ = ["GridLookups", "Slot", "grid_lookups"]

T = TypeVar("T")

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
    "compiled look-ups on grids", MAX_FAULT_LOOKUPS, kind=CacheKind.REPAIR, per_map=True
)


def grid_lookups(lookups: FaultLookups[T], grid: FreeGrid) -> GridLookups[T]:
    """``lookups`` as read on ``grid`` (kept per fault set and grid, a bounded number)."""
    found = _ON_GRIDS.get((lookups, grid), lambda: GridLookups(lookups, grid))
    return cast("GridLookups[T]", found)  # keyed by ``lookups``: its answers
