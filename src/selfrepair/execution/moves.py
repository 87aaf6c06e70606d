"""Integer motion tables of a domain: what the simulator, the executor and the metrics look up on
every step instead of calling the domain's functions.

A :class:`~selfrepair.robots.domain.Domain` commutes with translation (its contract), so an
action's effect from any pose is its effect from ``(0, 0, heading)`` shifted: per action and
heading a :class:`Move` holds the end offset, the end heading, the footprint as offsets into a
flat, row-major free-cell buffer of a given stride (a :class:`~selfrepair.geometry.FreeGrid`),
and the duration, exact as a :class:`~fractions.Fraction` and as an integer count of time units.

Time units: a domain's *unit* is the least common multiple of its duration denominators (3 for the
four-wheel robot, whose durations are multiples of 1/3 tick), so every duration, and the one
tick a failed attempt costs, is a whole number of units of ``1 / unit`` tick. Clocks count in
units inside the mission loop and turn into fractions only at the edges (results and rows).

Tables are derived once per domain and stride and kept in named bounded caches; the available
subset under a fault set is kept per fault set.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import NamedTuple

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "Move",
    "MoveTable",
    "available_moves",
    "move_table",
]


class Move(NamedTuple):
    """One action from one heading: end offset ``(dx, dy)`` and heading, footprint offsets in the
    table's buffer stride (start cell first), duration in units and exact, and the action's index
    in ``Domain.actions`` (``action_index``). An immutable ``NamedTuple``: read on every step."""

    dx: int
    dy: int
    heading: Heading
    cells: tuple[int, ...]
    units: int
    duration: Fraction
    action_index: int


@dataclass(frozen=True, slots=True, eq=False)
class MoveTable:
    """Every action's :class:`Move` per heading (indexed by ``int(heading)``), for buffers of
    ``stride`` bytes per row; ``reach`` is the largest Chebyshev distance of a footprint cell or
    end cell from the start cell; ``unit`` the domain's time unit (see the module docstring);
    ``ends_covered`` whether every move's end cell lies in its footprint (then a move whose
    footprint is free ends on a free cell). ``moves`` is read-only by convention, as is
    ``shapes``: per action and heading, the footprint as cell offsets ``(dx, dy)`` from the start
    cell (what a caller that reports the swept cells shifts)."""

    domain: SomeDomain
    stride: int
    unit: int
    reach: int
    ends_covered: bool
    moves: dict[object, tuple[Move, ...]]
    shapes: dict[object, tuple[tuple[Cell, ...], ...]]


def move_table(domain: SomeDomain, stride: int) -> MoveTable:
    """The :class:`MoveTable` of ``domain`` for buffers of ``stride`` bytes per row."""
    return _TABLES.get((domain, stride), lambda: _move_table(domain, stride))


def _move_table(domain: SomeDomain, stride: int) -> MoveTable:
    unit = domain.time_unit
    moves: dict[object, tuple[Move, ...]] = {}
    shapes: dict[object, tuple[tuple[Cell, ...], ...]] = {}
    reach = 0
    covered = True
    for index, action in enumerate(domain.actions):
        per_heading = []
        footprints = []
        duration = Fraction(domain.duration(action))
        units = duration * unit
        assert units.denominator == 1  # the unit is a multiple of every denominator
        for heading in Heading:
            origin = Pose(0, 0, heading)
            end = domain.apply(origin, action)
            cells = domain.footprint(origin, action)
            reach = max(reach, abs(end.x), abs(end.y), *(max(abs(x), abs(y)) for x, y in cells))
            covered = covered and end.cell in cells
            offsets = tuple(y * stride + x for x, y in cells)
            footprints.append(tuple(cells))
            per_heading.append(
                Move(end.x, end.y, end.heading, offsets, units.numerator, duration, index)
            )
        moves[action] = tuple(per_heading)
        shapes[action] = tuple(footprints)
    return MoveTable(domain, stride, unit, reach, covered, moves, shapes)


_TABLES: BoundedCache[tuple[SomeDomain, int], MoveTable] = BoundedCache(
    "domain move tables", 64, kind=CacheKind.SIMULATION
)


def available_moves(table: MoveTable, faults: frozenset[object]) -> dict[object, tuple[Move, ...]]:
    """The moves of the actions available under ``faults`` (``action in result`` is the
    availability test), computed once per table and fault set."""
    return _AVAILABLE.get((table, faults), lambda: _available(table, faults))


def _available(table: MoveTable, faults: frozenset[object]) -> dict[object, tuple[Move, ...]]:
    available = table.domain.available
    return {a: m for a, m in table.moves.items() if available(a, faults)}


_AVAILABLE: BoundedCache[tuple[MoveTable, frozenset[object]], dict[object, tuple[Move, ...]]] = (
    BoundedCache("available moves per fault set", 4096, kind=CacheKind.SIMULATION)
)

