"""The tolerance masks' pattern book: each neighbourhood pattern answered once per process.

Whether a planning action started at a pose needs a replan under a fault set depends only on the
occupancy of the action's neighbourhood (:mod:`selfrepair.repair.neighbourhood`) for that fault
set, the same cells the compiled look-ups read. A :class:`MaskBook` (one per table, planning
actions, fault model, recursion mode, depth bound and pattern budget) takes the union of those
neighbourhoods over every fault set, action and heading, and gives each cell of a grid one
integer: the occupancy of that union around it (its **pattern**). A pattern's **row** holds, per
heading and action, the number of fault sets under which the step needs a replan and their bits.
It is found once, through the compiled look-ups (:func:`~selfrepair.repair.lookups.fault_lookups`,
so the answer is the ``replacement`` strategy's own), and kept for every later cell, grid and maze
with the same pattern; each (heading, action) part of a row is also kept by the part's own,
smaller, pattern, so a new row mostly reuses parts already found. The book's
:class:`~selfrepair.search.term.PatternTable` (what the compiled planner reads) keeps the parts'
answers too, so the planner adds the row of a new pattern whose parts are all known itself,
without leaving the compiled search; the book takes those rows in (:meth:`MaskBook.sync`) before
it next answers or makes masks. Only a pattern with a part never met runs the strategy's search.

So making the masks of a grid costs one gather of the union's cells around every free cell (numpy),
one ``np.unique`` over the patterns, one dictionary look-up per distinct pattern and one gather of
the rows; only patterns never met before run the strategy's search. The book is append-only
(masks already made keep views of its arrays) and bounded: past :data:`MAX_BOOK_ROWS` rows it
starts afresh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.lookups import MISSING, ActionLookup, action_index, fault_lookups
from selfrepair.repair.neighbourhood import occupancy_bit
from selfrepair.repair.replacement import RecursionMode, Replacement
from selfrepair.repair.tolerance import FaultModel
from selfrepair.search.term import MAX_PATTERN_CELLS, PatternTable
from selfrepair.tables.model import SomeTable

__all__ = ["MAX_BOOK_ROWS", "MaskBook", "ToleranceMasks"]

MAX_BOOK_ROWS = 8192
"""Distinct neighbourhood patterns a :class:`MaskBook` keeps before it starts afresh (a row is
``4 x actions`` counts and fault-set words: about 0.6 kB for the four-wheel robot under every single
and double fault, so at most about 5 MB per book; the bundled mazes have a few hundred patterns)."""


@dataclass(frozen=True, slots=True, eq=False)
class ToleranceMasks:
    """The masks of ``actions`` under ``model`` on one grid.

    ``counts[y, x, heading, k]`` is the number of fault sets under which ``actions[k]`` started
    at ``(x, y, heading)`` needs a replan (the planner's cost term; 0 on walls). The fault sets
    themselves are kept per distinct neighbourhood pattern: ``rows[y, x]`` is the pattern row of
    cell ``(x, y)`` (-1 on walls) and ``words[row, heading, k, w]`` holds bits ``64 w ..`` of the
    fault sets (``model`` order) of that row; :attr:`masks` spreads them to every cell."""

    actions: tuple[object, ...]
    model: FaultModel
    counts: npt.NDArray[np.int32]
    rows: npt.NDArray[np.int32]
    words: npt.NDArray[np.uint64]

    @property
    def masks(self) -> npt.NDArray[np.uint64]:
        """``masks[y, x, heading, k, w]``: bits ``64 w ..`` of the fault sets under which
        ``actions[k]`` started at ``(x, y, heading)`` needs a replan (made on each call)."""
        height, width = self.rows.shape
        out = np.zeros((height, width, *self.words.shape[1:]), dtype=np.uint64)
        ys, xs = np.nonzero(self.rows >= 0)
        out[ys, xs] = self.words[self.rows[ys, xs]]
        return out

    def fault_sets_at(self, pose: Pose, k: int) -> tuple[frozenset[object], ...]:
        """The fault sets whose bit is set for ``actions[k]`` at ``pose`` (model order)."""
        row = int(self.rows[pose.y, pose.x])
        if row < 0:
            return ()
        words = self.words[row, pose.heading, k]
        return tuple(
            f for b, f in enumerate(self.model.fault_sets) if int(words[b >> 6]) >> (b & 63) & 1
        )


def _valid(found: Replacement) -> bool:
    """The stored answer of a pattern with a valid replacement (``None`` when there is none)."""
    return True


def free_cells(grid: FreeGrid) -> npt.NDArray[np.bool_]:
    """The grid's own cells (not its margin) as a boolean array, ``True`` where free."""
    m = grid.margin
    data = np.frombuffer(grid.data, dtype=np.uint8).reshape(grid.height + 2 * m, grid.stride)
    free: npt.NDArray[np.bool_] = data[m : m + grid.height, m : m + grid.width] == 1
    return free


@dataclass(frozen=True, slots=True, eq=False)
class _Patterns:
    """A grid's free cells ``(xs[i], ys[i])``, its distinct patterns ``codes`` (one cell of
    each: ``first[u]``) and each cell's pattern index ``inverse[i]``."""

    ys: npt.NDArray[np.intp]
    xs: npt.NDArray[np.intp]
    codes: list[int]
    first: npt.NDArray[np.intp]
    inverse: npt.NDArray[np.intp]


class MaskBook:
    """The rows of every neighbourhood pattern met so far, for one (table, planning actions,
    fault model, recursion mode, depth bound, pattern budget); mutable by nature (it grows).

    ``cells`` is the union neighbourhood (bit ``j`` of a pattern is ``cells[j]``, relative to
    the pose); ``faulty[k]`` lists, for ``actions[k]``, each fault set that makes it unavailable
    (its index in the model) with its compiled look-up.
    """

    __slots__ = (
        "_answer_counts",
        "_answer_of",
        "_answer_words",
        "_counts",
        "_grow",
        "_keys",
        "_parts",
        "_row_of",
        "_size",
        "_table",
        "_words",
        "actions",
        "cells",
        "faulty",
        "lookups",
        "model",
        "project",
        "radius",
        "table",
    )

    def __init__(
        self,
        table: SomeTable,
        actions: tuple[object, ...],
        model: FaultModel,
        mode: RecursionMode,
        max_depth: int,
        max_patterns: int,
    ) -> None:
        domain = table.domain
        index = action_index(domain)
        self.table = table
        self.actions = actions
        self.model = model
        self.lookups = tuple(
            fault_lookups(
                table, faults, mode=mode, max_depth=max_depth, answer=_valid,
                max_patterns=max_patterns,
            )
            for faults in model.fault_sets
        )  # fmt: skip
        self.faulty: tuple[tuple[tuple[int, ActionLookup[bool]], ...], ...] = tuple(
            tuple(
                (b, self.lookups[b].action(index.of(action)))
                for b, faults in enumerate(model.fault_sets)
                if not domain.available(action, faults)
            )
            for action in actions
        )
        union: dict[Cell, None] = {}
        for per in self.faulty:
            for _, lookup in per:
                for heading in Heading:
                    union.update(dict.fromkeys(sorted(lookup.cells[heading])))
        self.cells: tuple[Cell, ...] = tuple(sorted(union))
        self.radius = max((max(abs(x), abs(y)) for x, y in self.cells), default=0)
        bit = {c: 1 << j for j, c in enumerate(self.cells)}
        self.project = tuple(
            tuple(
                sum(bit[c] for c in set().union(*(lk.cells[h] for _, lk in per)))
                for per in self.faulty
            )
            for h in Heading
        )
        self._grow = 64
        self._start()

    def _start(self) -> None:
        """Forget every row (new arrays: masks made before keep theirs)."""
        words = (len(self.model.fault_sets) + 63) >> 6
        shape = (self._grow, len(Heading), len(self.actions))
        self._counts = np.zeros(shape, dtype=np.int32)
        self._words = np.zeros((*shape, words), dtype=np.uint64)
        self._size = 0
        self._row_of: dict[int, int] = {}
        old: PatternTable | None = getattr(self, "_table", None)
        if old is not None:  # a search still holding it adds no rows to it
            old.retire()
        project = [self.project[h][k] for h in Heading for k in range(len(self.actions))]
        self._table = (  # the rows again, indexed for the compiled search (patterns it can read)
            PatternTable(self.cells, len(Heading), len(self.actions), project, MAX_BOOK_ROWS)
            if len(self.cells) <= MAX_PATTERN_CELLS
            else None
        )
        self._parts: tuple[tuple[dict[int, int], ...], ...] = tuple(  # part code: answer
            tuple({} for _ in self.actions) for _ in Heading
        )
        self._keys = tuple(  # per (heading, action) in row order: its parts and projection
            (self._parts[h][k], self.project[h][k])
            for h in Heading
            for k in range(len(self.actions))
        )
        self._answer_of: dict[tuple[int, int], int] = {}  # (count, bits): answer
        self._answer_counts = np.zeros(16, dtype=np.int32)  # per answer: count, bits as words
        self._answer_words = np.zeros((16, words), dtype=np.uint64)

    @property
    def rows(self) -> int:
        """Rows (distinct patterns) kept now."""
        self.sync()
        return self._size

    @property
    def pattern_table(self) -> PatternTable | None:
        """The rows as a :class:`~selfrepair.search.term.PatternTable` the compiled search reads
        per expanded cell (row numbers are this book's; the rows it added taken in first), or
        ``None`` when the union has more than :data:`~selfrepair.search.term.MAX_PATTERN_CELLS`
        cells; a new one after the book starts afresh."""
        self.sync()
        return self._table

    def sync(self) -> None:
        """Take in the rows the compiled search added to the pattern table (their counts, fault
        sets from their parts' answers, and codes), and give it room up to
        :data:`MAX_BOOK_ROWS` rows."""
        table = self._table
        if table is None:
            return
        size = table.size
        start = self._size
        if size > start:
            while len(self._counts) < size:
                self._counts = np.concatenate([self._counts, np.zeros_like(self._counts)])
                self._words = np.concatenate([self._words, np.zeros_like(self._words)])
            self._counts[start:size] = table.counts[start:size]
            self._words[start:size] = self._answer_words[table.answers[start:size]]
            for row, code in enumerate(table.codes[start:size].tolist(), start):
                self._row_of[code] = row
            self._size = size
        if table.limit != MAX_BOOK_ROWS:
            table.set_limit(MAX_BOOK_ROWS)

    def code(self, grid: FreeGrid, x: int, y: int) -> int:
        """The pattern of cell ``(x, y)`` of ``grid`` (bit ``j``: ``cells[j]`` around it free)."""
        return sum(
            1 << j for j, (dx, dy) in enumerate(self.cells) if grid.is_free(x + dx, y + dy)
        )

    def fill(self, grid: FreeGrid, x: int, y: int, code: int | None = None) -> int:
        """The row of the pattern around cell ``(x, y)`` of ``grid`` (``code``, when the caller
        has read it already), found now if it is new (the book starts afresh first when it is
        full)."""
        self.sync()
        if code is None:
            code = self.code(grid, x, y)
        row = self._row_of.get(code)
        if row is None:
            if self._size + 1 > MAX_BOOK_ROWS:
                self._start()
            row = self._add(code, x, y, grid)
        return row

    def patterns(self, grid: FreeGrid) -> _Patterns:
        """The free cells of ``grid``, their distinct patterns and which cell has which."""
        r = self.radius
        padded = np.pad(free_cells(grid), r)  # cells beyond the grid are walls
        side = padded.shape[1]
        flat = padded.ravel()
        at = np.flatnonzero(flat)  # free cells, as indices into ``padded``
        offsets = np.array([dy * side + dx for dx, dy in self.cells], dtype=np.intp)
        packed = np.packbits(flat[at[:, None] + offsets], axis=1, bitorder="little")
        nbytes = packed.shape[1]
        if nbytes <= 8:
            wide = np.zeros((len(at), 8), dtype=np.uint8)
            wide[:, :nbytes] = packed
            keys: npt.NDArray[np.uint64] = wide.view("<u8").ravel()
            distinct, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
            codes = [int(v) for v in distinct.tolist()]
        else:  # a union wider than 64 cells: compare the bytes
            raw = np.ascontiguousarray(packed).view(np.dtype((np.void, nbytes))).ravel()
            distinct, first, inverse = np.unique(raw, return_index=True, return_inverse=True)
            codes = [int.from_bytes(bytes(v), "little") for v in distinct]
        ys, xs = np.divmod(at, side)
        return _Patterns(ys - r, xs - r, codes, first, inverse.ravel())

    def masks(self, grid: FreeGrid) -> ToleranceMasks:
        """The :class:`ToleranceMasks` of ``grid`` (rows of new patterns found on the way)."""
        found = self.patterns(grid)
        self.sync()
        if self._size + len(found.codes) > MAX_BOOK_ROWS:
            self._start()
        known = self._row_of
        rows = np.array([known.get(code, -1) for code in found.codes], dtype=np.intp)
        for u in np.flatnonzero(rows < 0).tolist():
            at = int(found.first[u])
            x, y = int(found.xs[at]), int(found.ys[at])
            rows[u] = self._add(found.codes[u], x, y, grid)
        cell_rows = rows[found.inverse]
        height, width = grid.height, grid.width
        cells = found.ys * width + found.xs
        flat_counts = np.zeros((height * width, len(Heading), len(self.actions)), dtype=np.int32)
        flat_counts[cells] = self._counts[cell_rows]
        flat_rows = np.full(height * width, -1, dtype=np.int32)
        flat_rows[cells] = cell_rows
        words = self._words[: self._size]
        counts = flat_counts.reshape(height, width, len(Heading), len(self.actions))
        by_cell = flat_rows.reshape(height, width)
        for array in (counts, by_cell, words):
            array.setflags(write=False)
        return ToleranceMasks(self.actions, self.model, counts, by_cell, words)

    def _add(self, code: int, x: int, y: int, grid: FreeGrid) -> int:
        """The row of a pattern met for the first time at cell ``(x, y)`` of ``grid``."""
        if self._size == len(self._counts):
            self._counts = np.concatenate([self._counts, np.zeros_like(self._counts)])
            self._words = np.concatenate([self._words, np.zeros_like(self._words)])
        row = self._size
        found = [parts.get(code & project, -1) for parts, project in self._keys]
        if -1 in found:  # parts never met: the strategy's search
            full: dict[int, int] = {}  # the pattern as an occupancy code of each radius needed
            n = len(self.actions)
            for i, (parts, project) in enumerate(self._keys):
                if found[i] < 0:
                    h, k = divmod(i, n)
                    count, bits = self._part(self.faulty[k], Heading(h), code, x, y, grid, full)
                    found[i] = parts[code & project] = answer = self._answer(count, bits)
                    if self._table is not None:
                        self._table.add_part(i, code & project, answer, count)
        at = np.array(found, dtype=np.intp)
        self._counts[row] = self._answer_counts[at].reshape(self._counts.shape[1:])
        self._words[row] = self._answer_words[at].reshape(self._words.shape[1:])
        self._size += 1
        self._row_of[code] = row
        if self._table is not None:
            self._table.add(code, self._counts[row], at.reshape(self._counts.shape[1:]))
        return row

    def _answer(self, count: int, bits: int) -> int:
        """The index of a part's answer: ``count`` fault sets, those of ``bits``."""
        answer = self._answer_of.get((count, bits))
        if answer is None:
            answer = self._answer_of[count, bits] = len(self._answer_of)
            if answer == len(self._answer_counts):  # full: twice the room (new arrays)
                self._answer_counts = np.concatenate(
                    [self._answer_counts, np.zeros_like(self._answer_counts)]
                )
                self._answer_words = np.concatenate(
                    [self._answer_words, np.zeros_like(self._answer_words)]
                )
            self._answer_counts[answer] = count
            for w in range(self._answer_words.shape[1]):
                self._answer_words[answer, w] = (bits >> (64 * w)) & 0xFFFFFFFFFFFFFFFF
        return answer

    def _part(
        self,
        per: tuple[tuple[int, ActionLookup[bool]], ...],
        heading: Heading,
        code: int,
        x: int,
        y: int,
        grid: FreeGrid,
        full: dict[int, int],
    ) -> tuple[int, int]:
        """How many fault sets, and which (bits), make one action need a replan at ``(x, y)``
        facing ``heading``: each faulty look-up asked with its own key (the strategy's search
        runs for a key it has not stored)."""
        count = bits = 0
        pose = Pose(x, y, heading)
        for b, lookup in per:
            radius = lookup.radius
            occupancy = full.get(radius)
            if occupancy is None:
                occupancy = full[radius] = sum(  # cells beyond the radius: not in the mask
                    1 << occupancy_bit(c, radius)
                    for j, c in enumerate(self.cells)
                    if code >> j & 1 and max(abs(c[0]), abs(c[1])) <= radius
                )
            key = occupancy & lookup.masks[heading]
            answer = lookup.answers[heading].get(key, MISSING)
            if answer is MISSING:
                answer = self.lookups[b].fill(lookup, pose, key, grid)
            if answer is None:
                count += 1
                bits |= 1 << b
        return count, bits
