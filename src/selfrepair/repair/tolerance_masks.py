"""Tolerance masks: per (pose, planning action), the fault sets under which that step would need a
replan, for the tolerant planner (:class:`~selfrepair.search.problem.StepTerm`).

Bit ``b`` of the mask of action ``actions[k]`` started at ``(x, y, heading)`` is set when the
action is unavailable under ``model.fault_sets[b]`` and the ``replacement`` strategy finds no
valid replacement for it there (the local test of :mod:`selfrepair.repair.tolerance`, through
the same compiled look-ups the strategy reads). A plan whose steps all have empty masks covers
every (step, fault set) pair of the model; this is exact in non-deferring recursion modes, where
``(i, F)`` is covered exactly when no step from ``i`` on needs a replan under ``F``. So:

* **hard mode** (only steps with an empty mask): the cheapest plan that is tolerant of every
  fault set of the model, or ``UNSOLVABLE``, a proof that none exists among the planner's plans
  (the fastest action of each motion class; a slower one of the same motion may avoid a fault,
  and is not searched);
* **soft mode** (``penalty`` per set bit): the cheapest plan for duration plus ``penalty`` times
  the number of (step, fault set) pairs at which *the step itself* needs a replan. That is exact
  for its own objective but only approximates the share of uncovered pairs of
  :func:`~selfrepair.repair.tolerance.plan_tolerance`, which counts for each fault set every
  step up to the last step that needs a replan under it (a global, not a local, quantity);
  ``experiment tolerance`` measures the gap.

In the deferring ``primitive`` mode a replacement may keep a faulty action for later, so a step's
fate depends on the replacement it came from: the masks are then the per-encounter test and only
approximate even the hard mode. :func:`tolerance_term` refuses that mode.

Computation: per fault set, per faulty planning action and heading, the occupancy of the action's
neighbourhood around every free cell, packed into one integer per cell by numpy (shared by every
fault set whose neighbourhood is the same); each distinct pattern is answered once through the
compiled look-ups (a dictionary look-up, or the reference search the first time), and the answers
are spread back to the cells. Terms are kept per (table, mode, grid, actions, model) in a
bounded cache: a second plan on the same map pays nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.limits import MAX_LOOKUP_PATTERNS
from selfrepair.repair.lookups import MISSING, action_index, fault_lookups, occupancy_rows
from selfrepair.repair.replacement import DEFAULT_MAX_DEPTH, DEFERRING, RecursionMode, Replacement
from selfrepair.repair.tolerance import FaultModel
from selfrepair.search.term import StepTerm
from selfrepair.tables.model import ReplacementTable

__all__ = ["ToleranceMasks", "tolerance_masks", "tolerance_term"]


@dataclass(frozen=True, slots=True, eq=False)
class ToleranceMasks:
    """``masks[y, x, heading, k, w]``: bits ``64 w ..`` of the fault sets (``model`` order) under
    which ``actions[k]`` started at ``(x, y, heading)`` needs a replan; ``counts`` the number of
    set bits (the planner's cost term)."""

    actions: tuple[Any, ...]
    model: FaultModel
    masks: npt.NDArray[np.uint64]
    counts: npt.NDArray[np.int32]

    def fault_sets_at(self, pose: Pose, k: int) -> tuple[frozenset[Any], ...]:
        """The fault sets whose bit is set for ``actions[k]`` at ``pose`` (model order)."""
        words = self.masks[pose.y, pose.x, pose.heading, k]
        return tuple(
            f for b, f in enumerate(self.model.fault_sets) if int(words[b >> 6]) >> (b & 63) & 1
        )


def _valid(found: Replacement) -> bool:
    """The stored answer of a pattern with a valid replacement (``None`` when there is none)."""
    return True


def _patterns(
    free: npt.NDArray[np.bool_], pad: int, cells: frozenset[Cell], ys: Any, xs: Any
) -> tuple[npt.NDArray[Any], npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    """The distinct occupancy patterns of ``cells`` (relative to each free cell ``(xs, ys)``) as
    one integer per pattern: their first cell's index and, per cell, its pattern's index (as
    ``np.unique`` gives them). ``free`` is the grid padded by ``pad`` wall cells."""
    ordered = sorted(cells)
    if len(ordered) < 63:
        packed = np.zeros(len(ys), dtype=np.int64)
        for j, (dx, dy) in enumerate(ordered):
            packed |= free[ys + pad + dy, xs + pad + dx].astype(np.int64) << j
    else:  # a neighbourhood too wide for one word: Python integers (slower, any width)
        packed = np.zeros(len(ys), dtype=object)
        for j, (dx, dy) in enumerate(ordered):
            packed |= free[ys + pad + dy, xs + pad + dx].astype(object) * (1 << j)
    _, first, inverse = np.unique(packed, return_index=True, return_inverse=True)
    return packed, first, inverse.ravel()


def _free(grid: FreeGrid) -> npt.NDArray[np.bool_]:
    m = grid.margin
    data = np.frombuffer(grid.data, dtype=np.uint8).reshape(grid.height + 2 * m, grid.stride)
    free: npt.NDArray[np.bool_] = data[m : m + grid.height, m : m + grid.width] == 1
    return free


def tolerance_masks(
    table: ReplacementTable,
    grid: FreeGrid,
    actions: tuple[Any, ...],
    model: FaultModel,
    *,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
    max_patterns: int = MAX_LOOKUP_PATTERNS,
) -> ToleranceMasks:
    """The masks of ``actions`` on ``grid`` under ``model`` (see the module docstring; kept in a
    bounded cache). ``grid`` needs a margin of at least the table's reach, as a mission's has."""
    recursion = RecursionMode(mode)
    key = (table, grid, actions, model, recursion, max_depth, max_patterns)
    return _MASKS.get(
        key, lambda: _masks(table, grid, actions, model, recursion, max_depth, max_patterns)
    )


_MASKS: BoundedCache[tuple[Any, ...], ToleranceMasks] = BoundedCache(
    "tolerance masks", 16, kind=CacheKind.REPAIR
)


def _masks(
    table: ReplacementTable,
    grid: FreeGrid,
    actions: tuple[Any, ...],
    model: FaultModel,
    mode: RecursionMode,
    max_depth: int,
    max_patterns: int,
) -> ToleranceMasks:
    domain = table.domain
    index = action_index(domain)
    height, width = grid.height, grid.width
    words = (len(model.fault_sets) + 63) >> 6
    masks = np.zeros((height, width, 4, len(actions), words), dtype=np.uint64)
    free = _free(grid)
    ys, xs = np.nonzero(free)
    padded: dict[int, npt.NDArray[np.bool_]] = {}
    distinct: dict[tuple[int, frozenset[Cell]], tuple[Any, Any, Any]] = {}
    for b, faults in enumerate(model.fault_sets):
        word, bit = b >> 6, np.uint64(1 << (b & 63))
        lookups = fault_lookups(
            table, faults, mode=mode, max_depth=max_depth, answer=_valid,
            max_patterns=max_patterns,
        )  # fmt: skip
        for k, action in enumerate(actions):
            if domain.available(action, faults):
                continue
            lookup = lookups.action(index.of(action))
            radius = lookup.radius
            if radius not in padded:
                padded[radius] = np.pad(free, radius)
            rows = occupancy_rows(grid, radius)
            for heading in Heading:
                cells = lookup.cells[heading]
                if (radius, cells) not in distinct:
                    distinct[radius, cells] = _patterns(padded[radius], radius, cells, ys, xs)
                _, first, inverse = distinct[radius, cells]
                mask, answers = lookup.masks[heading], lookup.answers[heading]
                valid = np.zeros(len(first), dtype=bool)
                for u, at in enumerate(first.tolist()):
                    x, y = int(xs[at]), int(ys[at])
                    key = rows[y][x] & mask
                    found = answers.get(key, MISSING)
                    if found is MISSING:
                        found = lookups.fill(lookup, Pose(x, y, heading), key, grid)
                    valid[u] = found is not None
                bad = ~valid[inverse]
                masks[ys[bad], xs[bad], int(heading), k, word] |= bit
    counts = np.zeros((height, width, 4, len(actions)), dtype=np.int32)
    for w in range(words):
        counts += _popcount(masks[..., w])
    masks.setflags(write=False)
    counts.setflags(write=False)
    return ToleranceMasks(actions, model, masks, counts)


def _popcount(values: npt.NDArray[np.uint64]) -> npt.NDArray[np.int32]:
    """Set bits per element (SWAR, so it works on any numpy version)."""
    v = values.copy()
    v = v - ((v >> np.uint64(1)) & np.uint64(0x5555555555555555))
    v = (v & np.uint64(0x3333333333333333)) + ((v >> np.uint64(2)) & np.uint64(0x3333333333333333))
    v = (v + (v >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return ((v * np.uint64(0x0101010101010101)) >> np.uint64(56)).astype(np.int32)


def tolerance_term(
    table: ReplacementTable,
    grid: FreeGrid,
    actions: tuple[Any, ...],
    model: FaultModel,
    *,
    penalty: Fraction | None = None,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
    max_patterns: int = MAX_LOOKUP_PATTERNS,
) -> StepTerm:
    """The planner's cost term of the masks: hard (``penalty`` ``None``) or soft (``penalty``
    ticks per (step, fault set) pair that needs a replan). Refuses deferring recursion modes,
    where the local test is not exact (see the module docstring)."""
    recursion = RecursionMode(mode)
    if recursion in DEFERRING:
        raise ProblemError(
            f"tolerant planning needs a non-deferring recursion mode, not {recursion} (a "
            "step's replacement there depends on the replacement it came from)"
        )
    found = tolerance_masks(
        table, grid, actions, model, mode=recursion, max_depth=max_depth,
        max_patterns=max_patterns,
    )  # fmt: skip
    label = (
        f"tolerant {model.label}" if penalty is None else f"tolerant soft {penalty} {model.label}"
    )
    return _TERMS.get((found, penalty), lambda: StepTerm(actions, found.counts, penalty, label))


_TERMS: BoundedCache[tuple[ToleranceMasks, Fraction | None], StepTerm] = BoundedCache(
    "tolerance terms", 16, kind=CacheKind.REPAIR
)
