"""Local detours at run time: when the plan's next actions sweep a cell the robot believes
blocked, replace them by a detour from the detour table (:mod:`selfrepair.tables.detours`) that
ends where they end, avoids every believed-blocked cell and is valid by the replacement core's
test (:func:`selfrepair.repair.core.walk`: every step healthy under the known faults, executable
in turn on the maze, and here sweeping no believed-blocked cell but the one the step starts
from, as the simulator judges a motion).

**The window.** From the robot's pose, the queued actions are followed (on the poses the plan
predicts) for ``j = 1, 2, ...`` actions while the end pose stays within the table's radius. A
window of ``j`` actions is a candidate when the cell it ends on is believed free and the next
queued action (if any) sweeps no believed-blocked cell; the first window (shortest first) with a
valid detour is replaced: the repair consumes its ``j`` actions and runs the detour instead.
When no window has one, the strategy replans (around the believed-blocked cells).

**Faults.** A detour's steps are motion classes; under the known faults each is bound to the
fastest available action of its class. A candidate that needs a class with no available action
is not valid (a detour does not recurse into the fault table; faulty actions are the fault
table's, with its recursion modes and guard, as before).

**Compiled look-ups**, as a table hit's (:mod:`selfrepair.repair.lookups`): whether a candidate
is valid depends only on the occupancy of the cells it sweeps, so per (window, start heading,
end pose) the answer is stored per masked occupancy code. The codes are the grid's
(:func:`~selfrepair.repair.neighbourhood.occupancy_rows`, at the table's window radius) with the
believed-blocked cells' bits cleared: :class:`BeliefCodes` keeps them, copying a row on its first
change and updating the ``(2r + 1)^2`` codes around a cell when the belief about it changes (in
the repair that first sees the change, so inside its latency). A warm detour is then a few
integer operations per window and one dictionary look-up. The stored answers are shared by the
missions of a process (per detour table and fault set, in the ``detour answers per fault set``
cache), as a table's compiled look-ups are.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Generic, TypeVar, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.core import walk
from selfrepair.repair.lookups import MISSING, Missing
from selfrepair.repair.neighbourhood import action_index, occupancy_bit, occupancy_rows
from selfrepair.repair.replacement import FreeTest, RobotWorld
from selfrepair.robots.domain import A, Domain, F, primitive_by_motion
from selfrepair.tables.detours import DetourTable, SomeDetours, detour_table

__all__ = ["BeliefCodes", "DetourAnswer", "DetourFinder", "believed_free", "find_detour"]

T = TypeVar("T")

DetourAnswer = Callable[[int, tuple[Any, ...], int], T]
"""Turns a valid detour (candidate position, actions, queued actions it replaces) into what a
:class:`DetourFinder` stores and answers (a strategy's repair)."""

MAX_WINDOW = 8
"""Queued actions a window takes in at most."""

_OFF = 16
_SIDE = 2 * _OFF + 1
_SIDE2 = _SIDE * _SIDE
_HEADING_STEP = 4 * _SIDE2
_WINDOW_STEP = 4 * _HEADING_STEP
"""A slot's integer id: a window's end offset, shifted by ``_OFF`` into ``[0, _SIDE)`` per axis
(an end farther than ``_OFF`` cannot be reached by :data:`MAX_WINDOW` actions of reach 2), its
end heading, start heading and length."""


class BeliefCodes:
    """The occupancy codes of ``grid`` at ``radius`` with the believed-blocked cells' bits
    cleared (mutable: :meth:`sync` follows the belief). Rows are shared with the grid's static
    codes until a change touches them."""

    __slots__ = ("_copied", "blocked", "grid", "radius", "rows")

    def __init__(self, grid: FreeGrid, radius: int) -> None:
        self.grid = grid
        self.radius = radius
        self.rows: list[list[int]] = list(occupancy_rows(grid, radius))
        self.blocked: frozenset[Cell] = frozenset()
        self._copied: set[int] = set()

    def sync(self, blocked: frozenset[Cell]) -> None:
        """Make the codes those of the grid with exactly ``blocked`` blocked."""
        if blocked is self.blocked or blocked == self.blocked:
            self.blocked = blocked
            return
        for cell in sorted(blocked - self.blocked):
            self._set(cell, free=False)
        for cell in sorted(self.blocked - blocked):
            self._set(cell, free=True)
        self.blocked = blocked

    def _set(self, cell: Cell, *, free: bool) -> None:
        grid, r = self.grid, self.radius
        cx, cy = cell
        if not grid.is_free(cx, cy):
            return  # a wall stays a wall; a cell off the grid has no code
        for y in range(max(0, cy - r), min(grid.height, cy + r + 1)):
            if y not in self._copied:
                self.rows[y] = self.rows[y][:]
                self._copied.add(y)
            row = self.rows[y]
            base = (cy - y + r) * (2 * r + 1) + cx + r  # occupancy_bit((cx - x, cy - y), r) + x
            for x in range(max(0, cx - r), min(grid.width, cx + r + 1)):
                bit = 1 << (base - x)
                row[x] = row[x] | bit if free else row[x] & ~bit


def believed_free(grid: FreeGrid, blocked: frozenset[Cell]) -> FreeTest:
    """The free test of a footprint on ``grid`` with ``blocked`` believed blocked, but the
    footprint's first cell (the cell the step starts from, as the simulator judges it)."""

    def free(cells: tuple[Cell, ...]) -> bool:
        return grid.all_free(cells) and blocked.isdisjoint(cells[1:])

    return free


def _bound(table: DetourTable[A, F], known: frozenset[F]) -> tuple[A | None, ...]:
    """Each class of ``table`` bound to its fastest available action under ``known``."""
    fastest = primitive_by_motion(table.domain, known)
    return tuple(fastest.get(name) for name in table.classes)


def find_detour(
    table: DetourTable[A, F],
    key: tuple[int, int, int, int],
    pose: Pose,
    known: frozenset[F],
    free: FreeTest,
    *,
    bound: tuple[A | None, ...] | None = None,
) -> tuple[int, tuple[A, ...]] | None:
    """The reference: the first candidate of ``key`` (its position and actions) valid at
    ``pose`` by the core's test under ``known`` with the free test ``free``, or ``None``
    (``bound``: the classes' actions under ``known``, when the caller has them)."""
    if bound is None:
        bound = _bound(table, known)
    world = RobotWorld(table.domain, known, free)
    for position, candidate in enumerate(table.candidates(key)):
        actions = tuple(bound[k] for k in candidate)
        if None in actions:
            continue
        walked = walk(world, cast("tuple[A, ...]", actions), pose, frozenset())  # no None left
        if walked is not None:
            return position, cast("tuple[A, ...]", actions)
    return None


def candidate_masks(table: DetourTable[A, F], key: tuple[int, int, int, int]) -> tuple[int, ...]:
    """Per candidate of ``key``, the occupancy bits (at the table's window radius) its steps
    test: every cell each step sweeps but the start cell of the first (the robot's own), so that
    a candidate is valid on a pattern exactly when the pattern has all its bits (for a robot
    whose motions end inside their footprint, as every bundled one; the property test checks
    it against :func:`find_detour`)."""
    return _MASKS.get(
        (table, key), lambda: tuple(_mask(table, key, c) for c in table.candidates(key))
    )


def _mask(
    table: DetourTable[A, F], key: tuple[int, int, int, int], candidate: tuple[int, ...]
) -> int:
    domain, radius = table.domain, table.window
    pose, bits = Pose(0, 0, Heading(key[0])), 0
    for step, k in enumerate(candidate):
        cells = domain.footprint(pose, table.actions[k])
        for cell in cells[1:] if step == 0 else cells:
            bits |= 1 << occupancy_bit(cell, radius)
        pose = domain.apply(pose, table.actions[k])
    return bits


_MASKS: BoundedCache[tuple[object, tuple[int, int, int, int]], tuple[int, ...]] = BoundedCache(
    "detour candidate masks", 1 << 14, kind=CacheKind.PREFILLED
)
"""Candidate masks per (table, key): a few per key, for the few tables a process makes."""


class _Slot(Generic[T]):
    """One (window length, start heading, end pose) under one fault set: the candidates whose
    classes are all bound (position, mask, actions), the neighbourhood mask, and the answers by
    masked code (``None``: no valid candidate)."""

    __slots__ = ("answer", "answers", "candidates", "mask", "window")

    def __init__(
        self,
        table: SomeDetours,
        key: tuple[int, int, int, int],
        window: int,
        bound: tuple[Any | None, ...],
        answer: DetourAnswer[T],
    ) -> None:
        self.window = window
        self.answer = answer
        usable = []
        for position, (candidate, mask) in enumerate(
            zip(table.candidates(key), candidate_masks(table, key), strict=True)
        ):
            actions = tuple(bound[k] for k in candidate)
            if None not in actions:
                usable.append((position, mask, actions))
        self.candidates = tuple(usable)
        self.mask = 0
        for _, mask, _ in usable:
            self.mask |= mask
        self.answers: dict[int, T | None] = {}

    def fill(self, code: int) -> T | None:
        """The answer for the masked code ``code``: the first usable candidate whose bits are
        all free in it (stored)."""
        value = None
        for position, mask, actions in self.candidates:
            if code & mask == mask:
                value = self.answer(position, actions, self.window)
                break
        self.answers[code] = value
        return value


_SHARED: BoundedCache[tuple[object, object, frozenset[object]], dict[int, Any]] = BoundedCache(
    "detour answers per fault set", 512, kind=CacheKind.REPAIR
)
"""The slots and stored answers of each (detour table, answer maker, fault set)."""


class DetourFinder(Generic[T]):
    """A mission's detours (mutable: the codes follow the belief, answers are stored).

    :meth:`find` answers a robot whose first queued action sweeps a believed-blocked cell: the
    stored ``answer`` of the detour (made by ``answer(position, actions, consumed)`` the first
    time), or ``None`` when no window has one. Answers must be true (a strategy's non-empty
    repair tuple), as the warm path tells them from "not stored yet" by one truth test.
    """

    __slots__ = (
        "_bindings",
        "_bound",
        "_bound_known",
        "_by_known",
        "_center",
        "_codes",
        "_domain",
        "_index",
        "_infos",
        "_quads",
        "_slots",
        "answer",
        "grid",
        "table",
    )

    def __init__(self, domain: Domain[Any, Any], grid: FreeGrid, answer: DetourAnswer[T]) -> None:
        self.table = detour_table(domain)
        self.answer = answer
        self.grid = grid
        self._domain = domain
        radius = self.table.window
        self._codes = BeliefCodes(grid, radius)
        self._index = action_index(domain)
        self._quads = self._index.quads
        self._center = 1 << occupancy_bit((0, 0), radius)
        self._infos = tuple(
            (dx, dy, h1, sum(1 << occupancy_bit(c, radius) for c in cells[1:]))
            for (dx, dy, h1), cells in zip(
                self._index.slot_moves,
                (cells for per in self._index.footprints for cells in per),
                strict=True,
            )
        )
        self._bound_known: frozenset[Any] | None = None
        self._bound: tuple[Any | None, ...] = ()
        self._slots: dict[int, _Slot[T]] = {}
        self._by_known: dict[frozenset[Any], dict[int, _Slot[T]]] = {}
        self._bindings: dict[frozenset[Any], tuple[Any | None, ...]] = {}
        self._rebind(frozenset())  # the fault-free binding, before any timed repair
        for key in self.table.entries:  # every candidate's bits, before any timed repair
            candidate_masks(self.table, key)

    def _quad(self, action: Any) -> int:
        quad = self._quads.get(id(action))
        return 4 * self._index.of(action) if quad is None else quad

    def bound(self, known: frozenset[Any]) -> tuple[Any | None, ...]:
        """Each class of the table bound to its fastest available action under ``known``
        (computed once per fault set)."""
        found = self._bindings.get(known)
        if found is None:
            found = self._bindings[known] = _bound(self.table, known)
        return found

    def _rebind(self, known: frozenset[Any]) -> None:
        """Switch to the answers of ``known`` (kept per fault set: they depend on it; shared by
        every finder of the same table and answer, since an answer depends only on the slot,
        the masked code and the faults)."""
        slots = self._by_known.get(known)
        if slots is None:
            key = (self.table, self.answer, known)
            slots = self._by_known[known] = _SHARED.get(key, dict)
        self._slots, self._bound_known, self._bound = slots, known, self.bound(known)

    def find(
        self, pose: Pose, queue: Sequence[Any], known: frozenset[Any], blocked: frozenset[Cell]
    ) -> T | None:
        """The detour at ``pose`` for the ``queue`` of actions under the known faults ``known``
        with ``blocked`` believed blocked (see the class).

        The warm path, kept to a few dozen bytecodes per window: the next action's slot found by
        the action's identity, its move and footprint mask read by slot, the codes read by row
        and column, one masked dictionary look-up per window end (slots are numbered
        ``j * _WINDOW_STEP + h * _SIDE ** 2 + x * _SIDE + y`` plus a start term)."""
        codes = self._codes
        if blocked is not codes.blocked:
            codes.sync(blocked)
        if known is not self._bound_known:
            self._rebind(known)
        rows = codes.rows
        x0, y0, h0 = pose.x, pose.y, pose.heading
        x, y = x0, y0
        start_code = rows[y0][x0]
        center, infos, quads, slots = self._center, self._infos, self._quads, self._slots
        slot_id = h0 * _HEADING_STEP - x0 * _SIDE - y0 + _OFF * _SIDE + _OFF
        n = len(queue)
        action = queue[0]
        quad = quads.get(id(action))
        info = infos[(self._quad(action) if quad is None else quad) + h0]
        for j in range(1, (n if n < MAX_WINDOW else MAX_WINDOW) + 1):
            x += info[0]
            y += info[1]
            h = info[2]
            slot_id += _WINDOW_STEP
            code = rows[y][x]  # a queued plan's predicted poses stay on the grid
            if j < n:
                action = queue[j]
                quad = quads.get(id(action))
                info = infos[(self._quad(action) if quad is None else quad) + h]
                if code & info[3] != info[3]:
                    continue  # the next action sweeps a blocked cell: take it in too
            if not code & center:
                continue  # the window would end on a blocked cell
            slot = slots.get(slot_id + h * _SIDE2 + x * _SIDE + y)
            if slot is None:
                slot = self._slot(slot_id + h * _SIDE2 + x * _SIDE + y, j, h0, h, x0, y0, x, y)
                if slot is None:
                    return None  # the window's end left the table's radius
            masked = start_code & slot.mask
            found: T | Missing | None = slot.answers.get(masked, MISSING)
            if found:
                return found
            if found is MISSING and (found := slot.fill(masked)):
                return found
        return None

    def _slot(
        self, slot_id: int, j: int, h0: int, h: int, x0: int, y0: int, x: int, y: int
    ) -> _Slot[T] | None:
        """The slot of a window of ``j`` actions from ``(x0, y0, h0)`` to ``(x, y, h)``, made on
        first use; ``None`` when the end is beyond the table's radius."""
        radius, rx, ry = self.table.radius, x - x0, y - y0
        if not (-radius <= rx <= radius and -radius <= ry <= radius):
            return None
        slot = self._slots[slot_id] = _Slot(
            self.table, (h0, rx, ry, h), j, self._bound, self.answer
        )
        return slot
