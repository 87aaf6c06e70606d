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

Computation (:mod:`selfrepair.repair.tolerance_book`): a :class:`MaskBook` per (table, actions,
model, mode) answers each neighbourhood pattern once per process, through the compiled look-ups.
The term :func:`tolerance_term` gives the planner holds the counts **by pattern**
(:class:`~selfrepair.search.term.PatternSource`): the compiled search reads a cell's pattern and
its row in the book when it first expands the cell, and has the book answer a pattern it has not
met, so a plan on a new map pays for the cells it expands, not for the map. The dense masks of
every pose (:func:`tolerance_masks`: the gather of every free cell's pattern, numpy) are made
only when asked for: by the pure-Python search, a plan's cost check, or a caller. Both are kept
per (book, grid) in bounded caches.
"""

from __future__ import annotations

from fractions import Fraction

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import FreeGrid
from selfrepair.limits import MAX_LOOKUP_PATTERNS
from selfrepair.repair.replacement import DEFAULT_MAX_DEPTH, DEFERRING, RecursionMode
from selfrepair.repair.tolerance import FaultModel
from selfrepair.repair.tolerance_book import MaskBook, ToleranceMasks
from selfrepair.robots.domain import A, F
from selfrepair.search.term import PatternSource, PatternTable, StepTerm
from selfrepair.tables.model import ReplacementTable

__all__ = ["ToleranceMasks", "tolerance_masks", "tolerance_term"]


def tolerance_masks(
    table: ReplacementTable[A, F],
    grid: FreeGrid,
    actions: tuple[A, ...],
    model: FaultModel,
    *,
    mode: RecursionMode | str = RecursionMode.FLAT,
    max_depth: int = DEFAULT_MAX_DEPTH,
    max_patterns: int = MAX_LOOKUP_PATTERNS,
) -> ToleranceMasks:
    """The masks of ``actions`` on ``grid`` under ``model`` (see the module docstring; kept in a
    bounded cache). ``grid`` needs a margin of at least the table's reach, as a mission's has."""
    book = _book(table, actions, model, RecursionMode(mode), max_depth, max_patterns)
    return _masks(book, grid)


def _book(
    table: ReplacementTable[A, F],
    actions: tuple[A, ...],
    model: FaultModel,
    recursion: RecursionMode,
    max_depth: int,
    max_patterns: int,
) -> MaskBook:
    key = (table, actions, model, recursion, max_depth, max_patterns)
    return _BOOKS.get(
        key, lambda: MaskBook(table, actions, model, recursion, max_depth, max_patterns)
    )


def _masks(book: MaskBook, grid: FreeGrid) -> ToleranceMasks:
    return _MASKS.get((book, grid), lambda: book.masks(grid))


_MASKS: BoundedCache[tuple[MaskBook, FreeGrid], ToleranceMasks] = BoundedCache(
    "tolerance masks", 16, kind=CacheKind.REPAIR, per_map=True
)

_BOOKS: BoundedCache[tuple[object, ...], MaskBook] = BoundedCache(
    "tolerance mask books", 16, kind=CacheKind.REPAIR
)


def tolerance_term(
    table: ReplacementTable[A, F],
    grid: FreeGrid,
    actions: tuple[A, ...],
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
    book = _book(table, actions, model, recursion, max_depth, max_patterns)
    label = (
        f"tolerant {model.label}" if penalty is None else f"tolerant soft {penalty} {model.label}"
    )
    return _TERMS.get((book, grid, penalty), lambda: _term(book, grid, penalty, label))


def _term(book: MaskBook, grid: FreeGrid, penalty: Fraction | None, label: str) -> StepTerm:
    """The term of ``book`` on ``grid``: by pattern when the compiled search can read the
    book's patterns (the masks of a cell found when the search first expands it), else dense."""
    if book.pattern_table is None:
        return StepTerm(book.actions, _masks(book, grid).counts, penalty, label)

    def table() -> PatternTable:
        current = book.pattern_table
        assert current is not None  # a book's union, hence its table's use, never changes
        return current

    def fill(x: int, y: int, code: int) -> None:
        book.fill(grid, x, y, code)

    source = PatternSource(
        grid, table, fill, lambda: _masks(book, grid).counts, len(book.model.fault_sets)
    )
    return StepTerm(book.actions, None, penalty, label, source)


_TERMS: BoundedCache[tuple[MaskBook, FreeGrid, Fraction | None], StepTerm] = BoundedCache(
    "tolerance terms", 16, kind=CacheKind.REPAIR, per_map=True
)
