"""Detour tables: local sub-plans from a pose to a nearby end pose, for plans whose next actions
sweep a cell that became blocked (a changing world, :mod:`selfrepair.world.events`).

A replacement table answers "this action is broken, what else gets me to the same end pose?"; a
detour table answers "these next actions sweep a blocked cell, what else gets me to the same end
pose?". An entry is keyed by the start heading and the end pose relative to the start cell
(``(h0, dx, dy, h1)``, the end within Chebyshev ``radius`` cells) and holds candidate sub-plans of
the robot's actions in order of preference (cheapest first), each staying within the ``window``
(every cell it sweeps at most ``window`` cells from the start cell, Chebyshev). At run time the
first candidate that is valid where it is needed is taken, with the replacement core's test
(:mod:`selfrepair.repair.core`, through :mod:`selfrepair.repair.detours`): healthy under the
known faults, executable in turn, and here also sweeping no cell believed blocked.

Generation works for any domain, as the replacement tables' (it needs only ``Domain.apply``,
``footprint``, ``duration`` and the motion classes): one action per motion class (the fastest,
with no fault; under faults the look-up binds each step to the fastest available action of its
class), and per start heading a Dijkstra search over the poses of the window, once with the
window free and once with each cell of the window forbidden in turn, and once with every cell
of the unconstrained path forbidden (a wider obstacle). Every distinct path found to an end pose
is a candidate, so for any one blocked cell of the window the cheapest path round it is in the
table. Candidates are sorted by cost, then length, then the order of their actions in the
domain; generation is deterministic. Tables are made once per (domain, radius, window) and kept.
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Generic, TypeAlias, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import A, Domain, F, primitive_by_motion

__all__ = [
    "DEFAULT_RADIUS",
    "DEFAULT_WINDOW",
    "DetourKey",
    "DetourTable",
    "SomeDetours",
    "detour_table",
]

DEFAULT_RADIUS = 2
"""Chebyshev cells between the start cell and the end cell of a detour."""

DEFAULT_WINDOW = 4
"""Chebyshev cells from the start cell that a detour's footprints may reach."""

DetourKey = tuple[int, int, int, int]
"""``(start heading, dx, dy, end heading)``: what a detour table is keyed by."""


@dataclass(frozen=True, slots=True, eq=False)
class DetourTable(Generic[A, F]):
    """Detour candidates by :data:`DetourKey`, best first (see the module docstring).

    ``classes`` are the motion classes in the order of ``actions`` (one action per class, the
    fastest with no fault); each candidate is a tuple of indices into them. ``cells[key][i]``
    is the set of cells candidate ``i`` of ``key`` sweeps, relative to the start cell.
    """

    domain: Domain[A, F]
    radius: int
    window: int
    classes: tuple[str, ...]
    actions: tuple[A, ...]
    entries: dict[DetourKey, tuple[tuple[int, ...], ...]]
    cells: dict[DetourKey, tuple[frozenset[Cell], ...]]

    def candidates(self, key: DetourKey) -> tuple[tuple[int, ...], ...]:
        """The candidates of ``key`` as class indices (empty: none, or ``key`` out of range)."""
        return self.entries.get(key, ())

    def size(self) -> int:
        """Candidates over all keys."""
        return sum(len(c) for c in self.entries.values())


SomeDetours: TypeAlias = "DetourTable[Any, Any]"
"""A detour table of a robot known only at run time (see
:data:`~selfrepair.robots.domain.SomeDomain`)."""


def detour_table(
    domain: Domain[A, F], radius: int = DEFAULT_RADIUS, window: int = DEFAULT_WINDOW
) -> DetourTable[A, F]:
    """The detour table of ``domain`` (made on first use, then kept)."""
    if radius < 1 or window < radius:
        raise ProblemError(f"expected 1 <= radius <= window, got {radius} and {window}")
    table = _TABLES.get((domain, radius, window), lambda: _generate(domain, radius, window))
    return cast("DetourTable[A, F]", table)  # keyed by the domain: the value is its table


_TABLES: BoundedCache[tuple[object, int, int], object] = BoundedCache(
    "detour tables", 16, kind=CacheKind.PREFILLED
)

_Move = tuple[int, int, int, tuple[Cell, ...], int]
"""``(dx, dy, end heading, footprint cells, duration in time units)`` of one class from one
heading."""

_Found = dict[tuple[int, int, int], tuple[tuple[int, ...], int]]
"""Per end pose ``(x, y, heading)``: the class indices of the cheapest path and its cost."""


def _generate(domain: Domain[A, F], radius: int, window: int) -> DetourTable[A, F]:
    fastest = primitive_by_motion(domain, frozenset())
    moving = {
        name: action
        for name, action in fastest.items()
        if any(domain.apply(Pose(0, 0, h), action) != Pose(0, 0, h) for h in Heading)
    }
    classes = tuple(moving)
    actions = tuple(moving.values())
    unit = domain.time_unit
    moves: list[list[_Move]] = [[] for _ in Heading]
    for heading in Heading:
        origin = Pose(0, 0, heading)
        for action in actions:
            end = domain.apply(origin, action)
            cells = tuple(domain.footprint(origin, action))
            units = int(Fraction(domain.duration(action)) * unit)
            moves[heading].append((end.x, end.y, int(end.heading), cells, units))
    near = [
        (x, y)
        for y in range(-radius, radius + 1)
        for x in range(-radius, radius + 1)
        if (x, y) != (0, 0)
    ]
    square = [(x, y) for y in range(-window, window + 1) for x in range(-window, window + 1)]
    bands = [
        frozenset(c for c in square if not lo <= c[axis] <= hi)
        for axis in (0, 1)
        for lo, hi in ((-1, 0), (0, 1), (-1, 1))
    ]
    found: dict[DetourKey, dict[tuple[int, ...], int]] = {}
    for h0 in map(int, Heading):
        free = _paths(moves, h0, window, frozenset())
        forbidden_sets = dict.fromkeys(frozenset({c}) for c in near)
        for outside in bands:  # round one cell in a corridor two or three cells wide
            for c in near:
                if c not in outside:
                    forbidden_sets[outside | {c}] = None
        for (x, y, _), (path, _) in free.items():
            if max(abs(x), abs(y)) <= radius and path:
                forbidden_sets[_path_cells(moves, h0, path) - {(0, 0), (x, y)}] = None
        for paths in (free, *(_paths(moves, h0, window, f) for f in forbidden_sets if f)):
            for (x, y, h1), (path, cost) in paths.items():
                if max(abs(x), abs(y)) > radius or (x, y, h1) == (0, 0, h0) or not path:
                    continue
                found.setdefault((h0, x, y, h1), {})[path] = cost
    entries: dict[DetourKey, tuple[tuple[int, ...], ...]] = {}
    cells_of: dict[DetourKey, tuple[frozenset[Cell], ...]] = {}
    for key in sorted(found):
        ranked = sorted(found[key].items(), key=lambda kv: (kv[1], len(kv[0]), kv[0]))
        entries[key] = tuple(path for path, _ in ranked)
        cells_of[key] = tuple(_path_cells(moves, key[0], path) for path, _ in ranked)
    return DetourTable(domain, radius, window, classes, actions, entries, cells_of)


def _path_cells(moves: list[list[_Move]], h0: int, path: tuple[int, ...]) -> frozenset[Cell]:
    x, y, h = 0, 0, h0
    cells: set[Cell] = set()
    for k in path:
        dx, dy, h1, footprint, _ = moves[h][k]
        cells.update((x + cx, y + cy) for cx, cy in footprint)
        x, y, h = x + dx, y + dy, h1
    return frozenset(cells)


def _paths(moves: list[list[_Move]], h0: int, window: int, forbidden: frozenset[Cell]) -> _Found:
    """Cheapest paths from ``(0, 0, h0)`` to every pose of the window whose footprints avoid
    ``forbidden`` (Dijkstra on integer costs; ties to the fewer actions, then to the path
    pushed first, moves in class order)."""
    parent: dict[tuple[int, int, int], tuple[tuple[int, int, int], int] | None] = {}
    cost_of: dict[tuple[int, int, int], int] = {}
    heap: list[tuple[int, int, int, tuple[int, int, int], tuple[int, int, int] | None, int]]
    heap = [(0, 0, 0, (0, 0, h0), None, -1)]
    counter = 0
    while heap:
        cost, length, _, pose, before, k = heapq.heappop(heap)
        if pose in parent:
            continue
        parent[pose] = None if before is None else (before, k)
        cost_of[pose] = cost
        x, y, h = pose
        for index, (dx, dy, h1, footprint, units) in enumerate(moves[h]):
            nxt = (x + dx, y + dy, h1)
            if nxt in parent:
                continue
            ok = True
            for cx, cy in footprint:
                c = (x + cx, y + cy)
                if abs(c[0]) > window or abs(c[1]) > window or c in forbidden:
                    ok = False
                    break
            if ok:
                counter += 1
                heapq.heappush(heap, (cost + units, length + 1, counter, nxt, pose, index))
    out: _Found = {}
    for pose in parent:
        path: list[int] = []
        at: tuple[int, int, int] = pose
        while (link := parent[at]) is not None:
            at, k = link
            path.append(k)
        out[pose] = (tuple(reversed(path)), cost_of[pose])
    return out
