"""Where a table look-up looks: a domain's actions by index, the neighbourhood of cells a search
for a replacement could test, and the occupancy codes of a grid (one integer per cell, the bits of
the free cells in a window around it).

These are the inputs of the compiled look-ups (:mod:`selfrepair.repair.lookups`): a hit masks the
occupancy code of the pose to the faulty action's neighbourhood and looks the result up. See that
module's docstring for what is kept and how much memory it takes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Generic, cast

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError, choice
from selfrepair.geometry import Cell, FreeGrid, Heading
from selfrepair.repair.replacement import (
    DEFAULT_MAX_DEPTH,
    DEFERRING,
    RECURSION_MODES,
    RecurseRule,
    RecursionMode,
    complex_actions,
)
from selfrepair.robots.domain import A, Domain, F
from selfrepair.search.openmoves import open_moves
from selfrepair.tables.model import ReplacementTable

__all__ = [
    "BAND",
    "MAX_CODE_GRIDS",
    "ActionIndex",
    "NeighbourhoodWalk",
    "action_index",
    "neighbourhood",
    "neighbourhood_walk",
    "occupancy_bit",
    "occupancy_rows",
]

MAX_CODE_GRIDS = 16
"""Occupancy code lists (grid and radius) kept per process."""


# --- actions by index -------------------------------------------------------------------------


@dataclass(frozen=True, slots=True, eq=False)
class ActionIndex(Generic[A, F]):
    """A domain's actions by position, with their moves, found without hashing an action.

    ``ids`` maps ``id(action)`` of the domain's own action objects to their index (``quads``
    to four times it: the first of the action's four per-heading slots); ``positions`` maps
    actions by equality (for equal copies). ``moves[i][h]`` is ``(dx, dy, heading)``: what
    action ``i`` does from heading ``h`` on an open plane; ``footprints[i][h]`` its footprint
    cells relative to the start cell. ``slot_moves[4 * i + h]`` is ``moves[i][h]`` (one index
    per step in a walk over a plan).
    """

    domain: Domain[A, F]
    ids: dict[int, int]
    positions: dict[A, int]
    moves: tuple[tuple[tuple[int, int, int], ...], ...]
    footprints: tuple[tuple[tuple[Cell, ...], ...], ...]
    quads: dict[int, int]
    slot_moves: tuple[tuple[int, int, int], ...]

    def of(self, action: A) -> int:
        """The index of ``action`` in ``domain.actions``; :class:`ProblemError` if it has none."""
        found = self.ids.get(id(action))
        if found is not None:
            return found
        found = self.positions.get(action)
        if found is None:
            raise ProblemError(f"{action!r} is not an action of domain {self.domain.name!r}")
        return found


def _action_index(domain: Domain[A, F]) -> ActionIndex[A, F]:
    moves = open_moves(domain)  # shared with the planner's set-up in the same run
    return ActionIndex(
        domain,
        moves.ids,
        {a: i for i, a in enumerate(domain.actions)},
        moves.ends,
        moves.footprints,
        {id(a): 4 * i for i, a in enumerate(domain.actions)},
        tuple(move for per in moves.ends for move in per),
    )


_INDEX: BoundedCache[object, object] = BoundedCache("action index", 16, kind=CacheKind.REPAIR)


def action_index(domain: Domain[A, F]) -> ActionIndex[A, F]:
    """The :class:`ActionIndex` of ``domain`` (built once per domain)."""
    # keyed by the domain itself: the value is its index
    return cast("ActionIndex[A, F]", _INDEX.get(domain, lambda: _action_index(domain)))


# --- neighbourhoods -----------------------------------------------------------------------------


def neighbourhood(
    table: ReplacementTable[A, F],
    action: A,
    known: frozenset[F],
    heading: Heading,
    *,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
) -> frozenset[Cell]:
    """Every cell, relative to a pose at the origin facing ``heading``, whose occupancy the search
    for a replacement of ``action`` could test: the answer depends on these cells only."""
    walk = neighbourhood_walk(
        table, frozenset(known), choice(RecursionMode, mode, "recursion mode"), max_depth
    )
    return walk.cells(action, int(heading), frozenset({action}), 0)


def neighbourhood_walk(
    table: ReplacementTable[A, F], known: frozenset[F], mode: RecursionMode, max_depth: int
) -> NeighbourhoodWalk[A, F]:
    """The walk of :func:`neighbourhood` for ``table`` under ``known`` in ``mode`` (the compiled
    look-ups keep one per (table, faults, mode) to find each action's neighbourhood)."""
    rule = RECURSION_MODES[mode](table.domain, max_depth)
    deferrable: frozenset[A] = complex_actions(table, known) if mode in DEFERRING else frozenset()
    return NeighbourhoodWalk(table, known, rule, action_index(table.domain), deferrable)


@dataclass(slots=True)
class NeighbourhoodWalk(Generic[A, F]):
    """The symbolic search behind :func:`neighbourhood` (mutable: memoises sub-neighbourhoods).

    It mirrors the core's search (:class:`~selfrepair.repair.core.CoreSearch`) but follows every
    candidate whatever the walls: a candidate is followed until a step must fail in any case (a
    guarded action, a faulty one that may not be replaced, or a deferrable one that would run
    first). A deferred action (``deferrable``: the faulty complex actions of a deferring mode
    such as ``primitive``) adds
    no cell, as the search does not test it, but the walk goes on after it. Sub-neighbourhoods
    are relative to their start cell (actions commute with translation), so each (action,
    heading, guard set, depth, whether it runs first) is walked once.
    """

    table: ReplacementTable[A, F]
    known: frozenset[F]
    rule: RecurseRule
    index: ActionIndex[A, F]
    deferrable: frozenset[A] = frozenset()
    memo: dict[tuple[A, int, frozenset[A], int, bool], frozenset[Cell]] = field(
        default_factory=dict
    )
    usable: dict[int, bool] = field(default_factory=dict)
    """Per action index: whether the action is available under ``known`` (asked once)."""

    def cells(
        self, action: A, heading: int, replacing: frozenset[A], depth: int, first: bool = True
    ) -> frozenset[Cell]:
        key = (action, heading, replacing, depth, first)
        found = self.memo.get(key)
        if found is None:
            found = self._walk(action, heading, replacing, depth, first)
            self.memo[key] = found
        return found

    def _walk(
        self, action: A, heading: int, replacing: frozenset[A], depth: int, first: bool
    ) -> frozenset[Cell]:
        index = self.index
        ids, footprints, moves = index.ids, index.footprints, index.moves
        known = self.known
        usable = self.usable
        available = self.table.domain.available
        out: set[Cell] = set()
        for candidate in self.table.candidates(action, known):
            x = y = 0
            h = heading
            for k, b in enumerate(candidate):
                if b in replacing:
                    break
                i = ids.get(id(b))
                if i is None:
                    i = index.of(b)
                ok = usable.get(i)
                if ok is None:
                    ok = usable[i] = available(b, known)
                runs_first = first and k == 0
                if ok:
                    cells = footprints[i][h]
                    out.update(cells if x == y == 0 else [(x + cx, y + cy) for cx, cy in cells])
                elif b in self.deferrable:
                    if runs_first:
                        break
                elif self.rule(b, action, depth):
                    sub = self.cells(b, h, replacing | {b}, depth + 1, runs_first)
                    out.update(sub if x == y == 0 else [(x + cx, y + cy) for cx, cy in sub])
                else:
                    break
                dx, dy, h = moves[i][h]  # a nested replacement ends where b ends
                x += dx
                y += dy
        return frozenset(out)


def occupancy_bit(cell: Cell, radius: int) -> int:
    """The bit of a relative cell in the occupancy code of radius ``radius``."""
    side = 2 * radius + 1
    return (cell[1] + radius) * side + cell[0] + radius


# --- occupancy codes ----------------------------------------------------------------------------


BAND = 64
"""Grid rows whose codes are computed at once: bounds the temporary arrays to a band, so that a
large grid's codes do not need several times their own size while they are made."""


def _rows(grid: FreeGrid, radius: int) -> list[list[int]]:
    rows, cols, margin = grid.height + 2 * grid.margin, grid.stride, grid.margin
    free = np.frombuffer(grid.data, dtype=np.uint8).reshape(rows, cols)
    padded = np.pad(free, radius)  # zeros: cells beyond the margin are walls
    side = 2 * radius + 1
    shared: dict[int, int] = {}  # one int object per distinct code: 8 bytes a cell
    out: list[list[int]] = []
    for top in range(margin, margin + grid.height, BAND):
        band = min(BAND, margin + grid.height - top)
        codes = _band_codes(padded, top, band, margin, grid.width, side)
        out.extend([shared.setdefault(code, code) for code in row] for row in codes)
    return out


def _band_codes(
    padded: npt.NDArray[np.uint8],
    top: int,
    band: int,
    left: int,
    width: int,
    side: int,
) -> list[list[int]]:
    """The codes of the cells of rows ``top`` to ``top + band - 1`` (buffer rows) and columns
    ``left`` to ``left + width - 1``, as Python integers by row (64 bits per numpy chunk)."""
    chunks = []
    for first in range(0, side * side, 64):
        chunk = np.zeros((band, width), dtype=np.uint64)
        for bit in range(first, min(first + 64, side * side)):
            dy, dx = divmod(bit, side)
            window = padded[top + dy : top + dy + band, left + dx : left + dx + width]
            chunk |= window.astype(np.uint64) << np.uint64(bit - first)
        chunks.append(chunk.tolist())
    if len(chunks) == 1:
        found: list[list[int]] = chunks[0]
        return found
    return [[_join(cell) for cell in zip(*row, strict=True)] for row in zip(*chunks, strict=True)]


def _join(parts: tuple[int, ...]) -> int:
    """One code from its 64-bit parts, lowest first."""
    return sum(part << (64 * k) for k, part in enumerate(parts))


_ROWS: BoundedCache[tuple[FreeGrid, int], list[list[int]]] = BoundedCache(
    "occupancy codes", MAX_CODE_GRIDS, kind=CacheKind.REPAIR, per_map=True
)


def occupancy_rows(grid: FreeGrid, radius: int) -> list[list[int]]:
    """Per cell ``(x, y)`` of ``grid`` (its own cells, not the margin), ``rows[y][x]``: the bits of
    the free cells in the ``(2 radius + 1)``-wide window around it; bit
    ``(dy + r) * (2r + 1) + dx + r`` is cell ``(x + dx, y + dy)`` (cells beyond the grid's
    margin count as walls). Built once per grid and radius (a few are kept), a band of rows at a
    time; equal codes share one integer object."""
    if radius < 0:
        raise ProblemError(f"radius must be at least 0, got {radius}")
    return _ROWS.get((grid, radius), lambda: _rows(grid, radius))
