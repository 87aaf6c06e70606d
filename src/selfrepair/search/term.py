"""A cost term per (pose, planning action), as data: what the tolerant planner adds to a plan's
cost (:class:`StepTerm`). It sits in a module of its own, free of mazes and robots, so that the
generic repair layer can build one (:mod:`selfrepair.repair.tolerance_masks`) and the planners
(:mod:`selfrepair.search.lattice`, the kernels) read it.

A term holds its counts either **densely** (an array over every pose) or **by pattern**
(:class:`PatternSource`): the count of a step then depends only on the occupancy of a fixed set
of cells around the step's start cell (its *pattern*), and a :class:`PatternTable` maps each
pattern met so far to a *row* of counts per (heading, action). The compiled search reads a
cell's pattern and its row only when it expands that cell, and asks the source for a pattern it
has not met (:meth:`PatternSource.fill`, with the code it read), so a first plan on a map pays
for the cells it expands, not for the whole map.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, FreeGrid

__all__ = [
    "MAX_PATTERN_CELLS",
    "PART_STEP",
    "PATTERN_MIX",
    "PatternSource",
    "PatternTable",
    "StepTerm",
    "part_slot",
    "pattern_slot",
]

MAX_PATTERN_CELLS = 63
"""Cells a pattern may have for the search to read it per expanded cell (one ``int64`` code,
never negative); a wider pattern makes the planner read the dense counts instead."""

PATTERN_MIX = 0x2545F4914F6CDD1D
"""Odd multiplier of :func:`pattern_slot` (below ``2**63``, so the kernel's ``int64`` product
wraps to the same low bits as Python's exact one)."""


PART_STEP = 0x9E3779B1
"""Odd step between the first slots of the same part for two ``(heading, action)`` numbers
(:func:`part_slot`; small, so ``i * PART_STEP`` never overflows ``int64``)."""


def part_slot(part: int, i: int, mask: int) -> int:
    """The first slot probed for part ``part`` of ``(heading, action)`` number ``i`` in the
    parts index of a :class:`PatternTable` (``mask + 1`` slots; the compiled search computes the
    same)."""
    return (pattern_slot(part, mask) + i * PART_STEP) & mask


def pattern_slot(code: int, mask: int) -> int:
    """The first slot probed for pattern ``code`` in a :class:`PatternTable` of ``mask + 1``
    slots (a power of two). The compiled search computes the same with wrapping ``int64``
    arithmetic, whose low bits equal these."""
    mixed = code ^ (code >> 7) ^ (code >> 19)
    return (mixed * PATTERN_MIX) & mask


class PatternTable:
    """Rows of counts per neighbourhood pattern, and an open-addressing index from pattern code
    to row that the compiled search probes (mutable by nature: it grows as patterns are met).

    Bit ``j`` of a pattern code is set when the cell ``cells[j]`` (relative to a step's start
    cell, cells beyond the grid being walls) is free. ``counts[row, heading, k]`` is the count of
    action ``k`` started facing ``heading`` at a cell of that row's pattern. ``keys[slot]`` holds
    a code (``-1``: empty slot) and ``rows[slot]`` its row; slots are probed linearly from
    :func:`pattern_slot`. ``codes[row]`` is the code of each row.

    **Parts.** The count of ``(heading, k)`` depends only on the cells of the code that
    ``project[i]`` keeps, ``i = heading * n_actions + k`` (the **part** ``code & project[i]``).
    Each part met so far has an **answer** (:meth:`add_part`): ``acounts[answer]`` is its count.
    ``parts[slot]`` holds ``(part, i, answer)`` (``part`` ``-1``: empty slot), probed linearly
    from :func:`part_slot`. So the compiled search can add the row of a pattern it has not met
    itself when every part of it is known (:func:`selfrepair.search._kernels._assemble`), writing
    ``counts``, ``answers[row, heading, k]`` (the answer of each part), ``codes``, the index and
    ``meta``; only a pattern with a part never met goes back to the caller.

    ``meta[0]`` is the number of rows and ``meta[1]`` the number the compiled search may reach by
    adding rows (the room of the arrays and :attr:`limit`). The arrays are replaced, never resized
    in place, when they grow; ``meta`` is replaced with them and the old one left without room,
    so that a search still holding old arrays adds nothing to them."""

    __slots__ = (
        "acounts",
        "answers",
        "cells",
        "codes",
        "counts",
        "dx",
        "dy",
        "keys",
        "limit",
        "meta",
        "n_parts",
        "parts",
        "project",
        "reach",
        "rows",
    )

    def __init__(
        self,
        cells: tuple[Cell, ...],
        headings: int,
        n_actions: int,
        project: Sequence[int] = (),
        limit: int = 1 << 62,
    ) -> None:
        if len(cells) > MAX_PATTERN_CELLS:
            raise ProblemError(f"a pattern has at most {MAX_PATTERN_CELLS} cells, got {len(cells)}")
        if project and len(project) != headings * n_actions:
            raise ProblemError(
                f"a pattern table needs {headings * n_actions} part projections, got {len(project)}"
            )
        self.cells = cells
        self.dx = np.array([c[0] for c in cells], dtype=np.int64)  # the cells as arrays, and how
        self.dy = np.array([c[1] for c in cells], dtype=np.int64)  # far the farthest one lies
        self.reach = max((max(abs(x), abs(y)) for x, y in cells), default=0)
        self.limit = limit
        self.counts = np.zeros((64, headings, n_actions), dtype=np.int32)
        self.answers = np.zeros((64, headings, n_actions), dtype=np.int32)
        self.codes = np.zeros(64, dtype=np.int64)
        self.keys = np.full(256, -1, dtype=np.int64)
        self.rows = np.zeros(256, dtype=np.int32)
        self.project = np.array(list(project) or [0] * (headings * n_actions), dtype=np.int64)
        self.acounts = np.zeros(16, dtype=np.int32)
        self.parts = np.full((64 if project else 1, 3), -1, dtype=np.int64)  # none: never added
        self.n_parts = 0
        self.meta = np.zeros(2, dtype=np.int64)
        self._room()

    @property
    def size(self) -> int:
        """Rows stored (by :meth:`add` or by the compiled search)."""
        return int(self.meta[0])

    def set_limit(self, limit: int) -> None:
        """Let the compiled search add rows up to ``limit`` rows in all (fewer if the arrays are
        full)."""
        self.limit = limit
        self._room()

    def retire(self) -> None:
        """Leave no room to the compiled search (the table's owner has started a new one)."""
        self.meta[1] = 0

    def _room(self) -> None:
        rows = min(len(self.counts), len(self.keys) // 4, self.limit)  # a quarter full at most
        self.meta[1] = rows if len(self.parts) > 1 else 0

    def _new_meta(self) -> None:
        """A new ``meta`` for new arrays (the old one left without room)."""
        old = self.meta
        self.meta = old.copy()
        old[1] = 0

    def find(self, code: int) -> int:
        """The row of pattern ``code``, or -1 when it has none yet."""
        mask = len(self.keys) - 1
        slot = pattern_slot(code, mask)
        while True:
            key = int(self.keys[slot])
            if key == code:
                return int(self.rows[slot])
            if key < 0:
                return -1
            slot = (slot + 1) & mask

    def add(
        self,
        code: int,
        counts: npt.NDArray[np.int32],
        answers: npt.NDArray[np.int32] | None = None,
    ) -> int:
        """Store the row ``counts`` (per heading and action; ``answers``: the answer of each
        part, when the parts are kept) of a pattern not stored yet; returns its row."""
        row = self.size
        if row == len(self.counts):
            self._new_meta()
            self.counts = np.concatenate([self.counts, np.zeros_like(self.counts)])
            self.answers = np.concatenate([self.answers, np.zeros_like(self.answers)])
            self.codes = np.concatenate([self.codes, np.zeros_like(self.codes)])
        self.counts[row] = counts
        if answers is not None:
            self.answers[row] = answers
        self.codes[row] = code
        self.meta[0] = row + 1
        if 4 * (row + 1) > len(self.keys):  # at most a quarter full: short probes
            self._new_meta()
            self._index(2 * len(self.keys))
        self._put(code, row)
        self._room()
        return row

    def add_part(self, i: int, part: int, answer: int, count: int) -> None:
        """Keep ``answer`` (``count`` fault sets) for part ``part`` of ``(heading, k)`` number
        ``i`` (not kept yet)."""
        if len(self.parts) == 1:  # made without projections: parts are not kept
            return
        if answer >= len(self.acounts):
            grown = np.zeros(max(2 * len(self.acounts), answer + 1), dtype=np.int32)
            grown[: len(self.acounts)] = self.acounts
            self.acounts = grown
        self.acounts[answer] = count
        self.n_parts += 1
        if 2 * self.n_parts > len(self.parts):  # at most half full
            old = self.parts[self.parts[:, 0] >= 0].tolist()
            self.parts = np.full((2 * len(self.parts), 3), -1, dtype=np.int64)
            for entry in old:
                self._put_part(*entry)
        self._put_part(part, i, answer)

    def _put_part(self, part: int, i: int, answer: int) -> None:
        mask = len(self.parts) - 1
        slot = part_slot(part, i, mask)
        while self.parts[slot, 0] >= 0:
            slot = (slot + 1) & mask
        self.parts[slot] = (part, i, answer)

    def _put(self, code: int, row: int) -> None:
        mask = len(self.keys) - 1
        slot = pattern_slot(code, mask)
        while self.keys[slot] >= 0:
            slot = (slot + 1) & mask
        self.keys[slot] = code
        self.rows[slot] = row

    def _index(self, slots: int) -> None:
        """Rebuild the index with ``slots`` slots (new arrays)."""
        used = np.flatnonzero(self.keys >= 0)
        codes, rows = self.keys[used].tolist(), self.rows[used].tolist()
        self.keys = np.full(slots, -1, dtype=np.int64)
        self.rows = np.zeros(slots, dtype=np.int32)
        for code, row in zip(codes, rows, strict=True):
            self._put(code, row)


@dataclass(frozen=True, slots=True, eq=False)
class PatternSource:
    """The counts of a term by pattern, on one grid (see the module docstring).

    ``table()`` is the current :class:`PatternTable` (a source may start a new one, which makes
    every row read before stale); ``fill(x, y, code)`` stores the row of ``code``, the pattern
    around cell ``(x, y)`` of ``grid`` as the compiled search read it, which the table did not
    have; ``dense()`` gives the counts of every
    pose, ``dense()[y, x, heading, k]`` (the reference, for the pure-Python search and for
    checking a plan's cost). ``max_count`` bounds every count."""

    grid: FreeGrid
    table: Callable[[], PatternTable]
    fill: Callable[[int, int, int], None]
    dense: Callable[[], npt.NDArray[np.int32]]
    max_count: int


@dataclass(frozen=True, slots=True, eq=False)
class StepTerm:
    """A cost term per (pose, planning action), as data: ``counts[y, x, heading, k]`` is a
    non-negative count for ``actions[k]`` started at ``(x, y, heading)`` (for the tolerant
    planner: the fault sets under which that step would need a replan, see
    :mod:`selfrepair.repair.tolerance_masks`). The counts are held densely (``counts``) or by
    pattern (``source``, ``counts`` ``None``): :meth:`dense_counts` gives them either way.

    ``penalty`` ``None`` is the **hard** mode: a step with a count above 0 is never taken, so
    the plan found is the cheapest one whose every step counts 0 (``UNSOLVABLE``: none exists).
    A :class:`~fractions.Fraction` is the **soft** mode: each counted unit costs ``penalty``
    ticks, exactly (like the clearance weight). ``actions`` are the planning actions the counts
    were made for (those of :func:`selfrepair.search.lattice.planning_actions` for the faults the
    planner knows); the planner refuses a term made for others. Equality is identity (arrays).
    """

    actions: tuple[object, ...]
    counts: npt.NDArray[np.int32] | None
    penalty: Fraction | None = None
    label: str = "tolerant"
    source: PatternSource | None = None

    def __post_init__(self) -> None:
        if (self.counts is None) == (self.source is None):
            raise ProblemError("a step term has either dense counts or a pattern source")
        if self.counts is not None:
            shape = self.counts.shape
            if len(shape) != 4 or shape[2] != 4 or shape[3] != len(self.actions):
                raise ProblemError(
                    f"step term counts must have shape (height, width, 4, {len(self.actions)}), "
                    f"got {shape}"
                )
            if self.counts.size and int(self.counts.min()) < 0:
                raise ProblemError("step term counts must be >= 0")
        if self.penalty is not None and self.penalty < 0:
            raise ProblemError(f"a step term penalty must be >= 0, got {self.penalty}")

    @property
    def hard(self) -> bool:
        """Whether counted steps are forbidden (rather than penalised)."""
        return self.penalty is None

    @property
    def size(self) -> tuple[int, int]:
        """The ``(height, width)`` of the map the counts are for."""
        if self.counts is not None:
            return int(self.counts.shape[0]), int(self.counts.shape[1])
        assert self.source is not None
        return self.source.grid.height, self.source.grid.width

    def dense_counts(self) -> npt.NDArray[np.int32]:
        """The counts of every pose, ``[y, x, heading, k]`` (made by the source when the term
        holds them by pattern)."""
        if self.counts is not None:
            return self.counts
        assert self.source is not None
        return self.source.dense()
