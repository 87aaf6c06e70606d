"""Run-time replacement: the first valid candidate from a table, in one of three recursion modes.

A replacement for action ``a`` at state ``s`` is a sub-plan without ``a`` whose actions are each
executable in turn from ``s`` and which ends where ``a`` would have ended. Table candidates end in
the right place by construction (tables are re-simulated when built), so at run time a candidate
is **valid** when

1. every action in it is available under the known faults, or can itself be replaced (how, depends
   on the recursion mode below);
2. every step is executable from its state: the domain's footprint cells are all free;
3. it uses no action that is currently being replaced (the guard that stops recursion from
   deadlocking, e.g. ``R -> L L L`` and ``L -> R R R`` calling each other for ever).

Recursion modes (registry :data:`RECURSION_MODES`, selected by name):

``flat``
    Only candidates whose actions are all healthy. Never recurses, cheapest, always terminates.
    Gives up: every candidate that would need a faulty action replaced in turn, so with two faults
    it fails more often than the others.
``guarded``
    A faulty action inside a candidate is replaced recursively, carrying down the set of actions
    being replaced so that none of them is reused at any depth, and stopping at ``max_depth``
    nested levels. Gives up: completeness beyond the depth bound, and its worst-case cost grows
    exponentially with the depth (each level may scan every candidate of the table).
``layered``
    Actions are split into levels by the domain (``Domain.level``: primitive 0, complex higher).
    A faulty action inside a candidate may be replaced recursively only when its level is lower
    than that of the action being replaced, so recursion ends after at most as many steps as there
    are levels, whatever the table holds. Gives up: a faulty action of the same or a higher level
    can never be replaced inside a candidate (for the four-wheel robot, a faulty turn inside a turn
    replacement, or a faulty arc inside anything), and a faulty primitive action has only its
    all-healthy candidates, as in ``flat``.

The search is greedy but complete within each mode: every sub-replacement of an action ``b`` from a
state ends in the same state, so the first valid sub-replacement found is as good as any other for
the rest of the candidate.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import Domain
from selfrepair.tables.model import ReplacementTable
from selfrepair.world.maze import Maze

__all__ = [
    "DEFAULT_MAX_DEPTH",
    "RECURSION_MODES",
    "Replacement",
    "find_replacement",
    "flat_replacement_on_grid",
    "free_cell_set",
    "is_valid_replacement",
    "prepare_grid_geometry",
]

DEFAULT_MAX_DEPTH = 2
"""Nested replacement levels allowed in ``guarded`` mode by default."""

FreeTest = Callable[[tuple[Cell, ...]], bool]
"""Whether every cell of a footprint is free (e.g. ``maze.all_free``)."""


class Replacement(NamedTuple):
    """A valid replacement found at run time.

    ``candidate`` is the table's candidate (index ``index`` in the looked-up list); ``actions`` the
    executable sequence after nested replacements are expanded (equal to ``candidate`` when
    ``depth`` is 0). ``depth`` counts nested replacement levels below this one; ``examined`` the
    candidates looked at in total, nested ones included. ``end`` is the state reached.
    An immutable ``NamedTuple`` (cheaper to build than a frozen dataclass on the hot path).
    """

    action: Any
    candidate: tuple[Any, ...]
    actions: tuple[Any, ...]
    index: int
    depth: int
    examined: int
    end: Any


@dataclass(slots=True)
class _Search:
    domain: Domain[Any, Any]
    table: ReplacementTable
    known: frozenset[Any]
    free: FreeTest
    may_recurse: Callable[[Any, Any, int], bool]
    examined: int = 0
    memo: dict[tuple[Any, Any, frozenset[Any], int], Replacement | None] = field(
        default_factory=dict
    )

    def replace(
        self, action: Any, state: Any, replacing: frozenset[Any], depth: int
    ) -> Replacement | None:
        """The first valid replacement; nested results are memoised per (action, state, guard set,
        depth), so a sub-problem met again in another candidate is not searched twice."""
        key = (action, state, replacing, depth)
        if key in self.memo:
            return self.memo[key]
        found = self._first(action, state, replacing, depth)
        self.memo[key] = found
        return found

    def _first(
        self, action: Any, state: Any, replacing: frozenset[Any], depth: int
    ) -> Replacement | None:
        for index, candidate in enumerate(self.table.candidates(action, self.known)):
            self.examined += 1
            found = self._expand(action, candidate, state, replacing, depth)
            if found is not None:
                actions, end, nested = found
                return Replacement(action, candidate, actions, index, nested, self.examined, end)
        return None

    def _expand(
        self,
        action: Any,
        candidate: tuple[Any, ...],
        state: Any,
        replacing: frozenset[Any],
        depth: int,
    ) -> tuple[tuple[Any, ...], Any, int] | None:
        dom = self.domain
        out: list[Any] = []
        nested = 0
        for b in candidate:
            if b in replacing:
                return None
            if dom.available(b, self.known):
                if not self.free(dom.footprint(state, b)):
                    return None
                out.append(b)
                state = dom.apply(state, b)
            elif self.may_recurse(b, action, depth):
                sub = self.replace(b, state, replacing | {b}, depth + 1)
                if sub is None:
                    return None
                out.extend(sub.actions)
                state = sub.end
                nested = max(nested, sub.depth + 1)
            else:
                return None
        return tuple(out), state, nested


RecurseRule = Callable[[Any, Any, int], bool]
"""Whether faulty action ``b`` inside a candidate for ``a`` may be replaced at depth ``d``."""

ModeFn = Callable[[Domain[Any, Any], int], RecurseRule]
"""A recursion mode: given the domain and the depth bound, its recursion rule."""


def _flat(domain: Domain[Any, Any], max_depth: int) -> RecurseRule:
    """Never recurse: only candidates whose actions are all healthy."""
    return lambda b, a, d: False


def _guarded(domain: Domain[Any, Any], max_depth: int) -> RecurseRule:
    """Recurse while shallower than ``max_depth`` (the guard set is carried by the search)."""
    return lambda b, a, d: d < max_depth


def _layered(domain: Domain[Any, Any], max_depth: int) -> RecurseRule:
    """Recurse only into strictly lower-level actions, so recursion always terminates."""
    level = domain.level
    return lambda b, a, d: level(b) < level(a)


RECURSION_MODES: dict[str, ModeFn] = {"flat": _flat, "guarded": _guarded, "layered": _layered}
"""Recursion modes by name (see the module docstring for what each gives up)."""


def find_replacement(
    domain: Domain[Any, Any],
    table: ReplacementTable,
    action: Any,
    state: Any,
    known_faults: Iterable[Any],
    free: FreeTest,
    *,
    mode: str = "flat",
    max_depth: int = DEFAULT_MAX_DEPTH,
) -> Replacement | None:
    """The first valid replacement for ``action`` at ``state``, or ``None`` when there is none.

    ``free`` tells whether a footprint is executable (all cells free), e.g. ``maze.all_free``.
    Every action of the returned ``actions`` is available under ``known_faults`` and executable in
    turn from ``state``; none of them is ``action``.
    """
    fn = RECURSION_MODES.get(mode)
    if fn is None:
        raise ProblemError(
            f"unknown recursion mode {mode!r}; expected one of {', '.join(RECURSION_MODES)}"
        )
    if table.domain != domain.name:
        raise ProblemError(f"table is for domain {table.domain!r}, not {domain.name!r}")
    if max_depth < 0:
        raise ProblemError(f"max_depth must be at least 0, got {max_depth}")
    search = _Search(domain, table, frozenset(known_faults), free, fn(domain, max_depth))
    return search.replace(action, state, frozenset({action}), 0)


def is_valid_replacement(
    domain: Domain[Any, Any],
    action: Any,
    state: Any,
    actions: Iterable[Any],
    known_faults: Iterable[Any],
    free: FreeTest,
) -> bool:
    """Check the definition directly: no ``action``, each step available and executable in turn,
    and the end state equal to ``action``'s end state. Used by tests and trace checks."""
    known = frozenset(known_faults)
    target = domain.apply(state, action)
    seq = tuple(actions)
    if not seq or action in seq:
        return False
    for b in seq:
        if not domain.available(b, known) or not free(domain.footprint(state, b)):
            return False
        state = domain.apply(state, b)
    return bool(state == target)


# --- fast path: flat mode on a grid with pose states -------------------------------------------


@dataclass(frozen=True, slots=True)
class _Compiled:
    """A healthy candidate with its geometry precomputed for each start heading: the cells it
    sweeps as offsets from the start cell, and its end pose as an offset."""

    index: int
    candidate: tuple[Any, ...]
    cells: tuple[tuple[Cell, ...], ...]
    ends: tuple[Pose, ...]


def _geometry(
    domain: Domain[Any, Any], candidate: tuple[Any, ...]
) -> tuple[tuple[tuple[Cell, ...], ...], tuple[Pose, ...]]:
    """Swept-cell offsets and end pose of ``candidate`` for each start heading at the origin."""
    cells_by_heading = []
    ends = []
    for heading in Heading:
        state = Pose(0, 0, heading)
        cells: dict[Cell, None] = {}
        for b in candidate:
            cells.update(dict.fromkeys(domain.footprint(state, b)))
            state = domain.apply(state, b)
        cells_by_heading.append(tuple(cells))
        ends.append(state)
    return tuple(cells_by_heading), tuple(ends)


def _candidate_geometry(
    domain: Domain[Any, Any], table: ReplacementTable, candidate: tuple[Any, ...]
) -> tuple[tuple[tuple[Cell, ...], ...], tuple[Pose, ...]]:
    key = ("geometry", domain.name, candidate)
    geometry = table.derived.get(key)
    if geometry is None:
        geometry = _geometry(domain, candidate)
        table.derived[key] = geometry
    return geometry


def prepare_grid_geometry(domain: Domain[Any, Any], table: ReplacementTable) -> None:
    """Precompute (once per table object) the fault-independent geometry of every candidate, so
    that a first look-up under new faults only filters candidates by availability."""
    marker = ("geometry-ready", domain.name)
    if marker in table.derived:
        return
    for entry in table.entries:
        for candidate in entry.candidates:
            _candidate_geometry(domain, table, candidate)
    table.derived[marker] = True


def _compile_flat(
    domain: Domain[Any, Any], table: ReplacementTable, action: Any, known: frozenset[Any]
) -> tuple[_Compiled, ...]:
    compiled = []
    for index, candidate in enumerate(table.candidates(action, known)):
        if action in candidate or not all(domain.available(b, known) for b in candidate):
            continue
        cells, ends = _candidate_geometry(domain, table, candidate)
        compiled.append(_Compiled(index, candidate, cells, ends))
    return tuple(compiled)


def flat_replacement_on_grid(
    domain: Domain[Any, Any],
    table: ReplacementTable,
    action: Any,
    pose: Pose,
    known_faults: frozenset[Any],
    free_cells: frozenset[Cell],
) -> Replacement | None:
    """``find_replacement(..., mode="flat")`` for domains whose states are translation-invariant
    :class:`~selfrepair.geometry.Pose` values (both shipped domains), at a fraction of the cost.

    Per (action, known faults) the healthy candidates are compiled once (memoised on the table)
    into swept-cell offsets per heading; a look-up is then one dictionary access plus a set
    membership test per swept cell. ``free_cells`` is :func:`free_cell_set` of the maze. Returns
    the same replacement as the general flat search (a property test checks this).
    """
    key = ("flat-grid", domain.name, action, known_faults)
    compiled = table.derived.get(key)
    if compiled is None:
        compiled = _compile_flat(domain, table, action, known_faults)
        table.derived[key] = compiled
    x, y, heading = pose.x, pose.y, pose.heading
    for item in compiled:
        for dx, dy in item.cells[heading]:
            if (x + dx, y + dy) not in free_cells:
                break
        else:
            end = item.ends[heading]
            return Replacement(
                action,
                item.candidate,
                item.candidate,
                item.index,
                0,
                item.index + 1,
                Pose(x + end.x, y + end.y, end.heading),
            )
    return None


_FREE_SETS: dict[int, tuple[Maze, frozenset[Cell]]] = {}


def free_cell_set(maze: Maze) -> frozenset[Cell]:
    """The free cells of ``maze`` as a set, computed once per maze object (a few are kept)."""
    hit = _FREE_SETS.get(id(maze))
    if hit is not None and hit[0] is maze:
        return hit[1]
    cells = frozenset(maze.free_cells())
    if len(_FREE_SETS) >= 8:
        _FREE_SETS.pop(next(iter(_FREE_SETS)))
    _FREE_SETS[id(maze)] = (maze, cells)
    return cells
