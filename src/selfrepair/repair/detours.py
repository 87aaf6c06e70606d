"""Local detours at run time: when the plan's next actions sweep a cell the robot believes
blocked, replace them by a detour from the detour table (:mod:`selfrepair.tables.detours`) that
ends where they end, avoids every believed-blocked cell and is valid by the replacement core's
test (:func:`selfrepair.repair.core.walk`: every step healthy under the known faults, executable
in turn on the maze, and here sweeping no believed-blocked cell but the one the step starts
from, as the simulator judges a motion).

**The window.** From the robot's pose, the queued actions are followed (on the poses the plan
predicts) for ``j = 1, 2, ...`` actions, at most :data:`MAX_WINDOW`. A window of ``j`` actions is
a candidate when the cell it ends on is believed free and the next queued action (if any) sweeps
no believed-blocked cell; the first candidate window (shortest first) with a valid detour is
replaced: the repair consumes its ``j`` actions and runs the detour instead. A candidate window
whose end is beyond the table's radius ends the search. When no window has one, the strategy
replans (around the believed-blocked cells).

**Faults.** A detour's steps are motion classes; under the known faults each is bound to the
fastest available action of its class. A candidate that needs a class with no available action
is not valid (a detour does not recurse into the fault table; faulty actions are the fault
table's, with its recursion modes and guard, as before).

**Compiled look-ups**, as a table hit's (:mod:`selfrepair.repair.lookups`): whether a candidate
is valid depends only on the occupancy of the cells it sweeps, so per (window, start heading,
end pose) the answer is stored per masked occupancy code. The codes are the grid's
(:func:`~selfrepair.repair.neighbourhood.occupancy_rows`, at the table's window radius) with the
believed-blocked cells' bits cleared: :class:`BeliefCodes` keeps them in one flat list (copied
from the grid's when the finder is made, before the mission's clock runs), updating the
``(2r + 1)^2`` codes around a cell when the belief about it changes (in the repair that first
sees the change, so inside its latency). A warm detour is then a few integer operations per
window and two dictionary look-ups for the window that answers. The stored answers are shared by the
missions of a process (per detour table and fault set, in the ``detour answers per fault set``
cache), as a table's compiled look-ups are.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Any, Generic, TypeVar, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.core import walk
from selfrepair.repair.lookups import MISSING, Missing
from selfrepair.repair.neighbourhood import action_index, occupancy_bit, occupancy_rows
from selfrepair.repair.replacement import FreeTest, RobotWorld
from selfrepair.robots.domain import A, F, SomeDomain, primitive_by_motion
from selfrepair.tables.detours import DetourTable, SomeDetours, detour_table

__all__ = ["BeliefCodes", "DetourAnswer", "DetourFinder", "believed_free", "find_detour"]

T = TypeVar("T")

DetourAnswer = Callable[[int, tuple[object, ...], int], T]
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
    cleared (mutable: :meth:`sync` follows the belief), in one flat list: the code of cell
    ``(x, y)`` is ``codes[y * grid.width + x]`` (one index per step of a walk along a plan). The
    list is a copy of the grid's static codes (the integers are shared), made when the finder
    is, before any timed repair."""

    __slots__ = ("blocked", "codes", "grid", "radius")

    def __init__(self, grid: FreeGrid, radius: int) -> None:
        self.grid = grid
        self.radius = radius
        self.codes: list[int] = [code for row in occupancy_rows(grid, radius) for code in row]
        self.blocked: frozenset[Cell] = frozenset()

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
        grid, r, codes, width = self.grid, self.radius, self.codes, self.grid.width
        cx, cy = cell
        if not grid.is_free(cx, cy):
            return  # a wall stays a wall; a cell off the grid has no code
        for y in range(max(0, cy - r), min(grid.height, cy + r + 1)):
            base = (cy - y + r) * (2 * r + 1) + cx + r  # occupancy_bit((cx - x, cy - y), r) + x
            row = y * width
            for x in range(max(0, cx - r), min(width, cx + r + 1)):
                bit = 1 << (base - x)
                codes[row + x] = codes[row + x] | bit if free else codes[row + x] & ~bit


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


_Step = tuple[int, int, int, dict[int, Any]]
"""One queued action from one heading, as :meth:`DetourFinder.find` walks it: ``(dp, sweep,
delta, after)``: its change of index into the flat codes (:class:`BeliefCodes`), the occupancy
bits of the cells it sweeps but its start cell (relative to the start cell, at the table's window
radius), the change of the slot id (one more action, the new end offset and heading) and the
steps of every action from its end heading (by ``id(action)``)."""

_LIMIT = MAX_WINDOW * _WINDOW_STEP
"""The smallest slot id of a window of :data:`MAX_WINDOW` actions (the walk's last)."""


class DetourFinder(Generic[T]):
    """A mission's detours (mutable: the codes follow the belief, answers are stored).

    :meth:`find` answers a robot whose first queued action sweeps a believed-blocked cell: the
    stored ``answer`` of the detour (made by ``answer(position, actions, consumed)`` the first
    time), or ``None`` when no window has one. Answers must be true (a strategy's non-empty
    repair tuple), as the warm path tells them from "not stored yet" by one truth test.

    The walk along the queue reads one precomputed :data:`_Step` per action, found by the
    action's identity in the dictionary of the heading the previous step ended on (an equal copy
    of a domain action is found by equality, off the warm path): the chain of steps from each
    start heading is made once per finder, so a window costs a few integer operations, and one
    dictionary look-up of its slot when it may end where it does. A slot's id holds everything
    the slot is made from (window length, start heading, end offset and heading), so the walk
    tracks only the slot id and the index of the end cell's code.
    """

    __slots__ = (
        "_bindings",
        "_bound",
        "_bound_known",
        "_by_known",
        "_center",
        "_codes",
        "_domain",
        "_flat",
        "_height",
        "_index",
        "_moves",
        "_slots",
        "_starts",
        "_steps",
        "_width",
        "answer",
        "grid",
        "table",
    )

    def __init__(self, domain: SomeDomain, grid: FreeGrid, answer: DetourAnswer[T]) -> None:
        self.table = detour_table(domain)
        self.answer = answer
        self.grid = grid
        self._domain = domain
        radius = self.table.window
        self._codes = BeliefCodes(grid, radius)
        self._flat = self._codes.codes  # the same list object for the finder's life
        self._width = grid.width
        self._index = action_index(domain)
        self._height = grid.height
        self._center = 1 << occupancy_bit((0, 0), radius)
        self._moves = tuple(  # by slot 4 * index + heading: (dx, dy, end heading, sweep bits)
            (dx, dy, h1, sum(1 << occupancy_bit(c, radius) for c in cells[1:]))
            for (dx, dy, h1), cells in zip(
                self._index.slot_moves,
                (cells for per in self._index.footprints for cells in per),
                strict=True,
            )
        )
        self._steps: tuple[dict[int, _Step], ...] = tuple({} for _ in Heading)
        for action in domain.actions:
            for heading in map(int, Heading):
                self._steps[heading][id(action)] = self._step(heading, action)
        self._starts = tuple(
            h * _HEADING_STEP + h * _SIDE2 + _OFF * _SIDE + _OFF for h in map(int, Heading)
        )
        self._bound_known: frozenset[object] | None = None
        self._bound: tuple[Any | None, ...] = ()
        self._slots: dict[int, _Slot[T] | None] = {}
        self._by_known: dict[frozenset[object], dict[int, _Slot[T] | None]] = {}
        self._bindings: dict[frozenset[object], tuple[Any | None, ...]] = {}
        self._rebind(frozenset())  # the fault-free binding, before any timed repair
        for key in self.table.entries:  # every candidate's bits, before any timed repair
            candidate_masks(self.table, key)

    def _step(self, heading: int, action: object) -> _Step:
        """The :data:`_Step` of ``action`` from ``heading`` (found by equality, so an equal copy
        of a domain action has one; :class:`ProblemError` for an action not of the domain)."""
        dx, dy, h1, sweep = self._moves[4 * self._index.of(action) + heading]
        delta = _WINDOW_STEP + (h1 - heading) * _SIDE2 + dx * _SIDE + dy
        return (dy * self._width + dx, sweep, delta, self._steps[h1])

    def bound(self, known: frozenset[object]) -> tuple[Any | None, ...]:
        """Each class of the table bound to its fastest available action under ``known``
        (computed once per fault set)."""
        found = self._bindings.get(known)
        if found is None:
            found = self._bindings[known] = _bound(self.table, known)
        return found

    def _rebind(self, known: frozenset[object]) -> None:
        """Switch to the answers of ``known`` (kept per fault set: they depend on it; shared by
        every finder of the same table and answer, since an answer depends only on the slot,
        the masked code and the faults)."""
        slots = self._by_known.get(known)
        if slots is None:
            key = (self.table, self.answer, known)
            slots = self._by_known[known] = _SHARED.get(key, dict)
        self._slots, self._bound_known, self._bound = slots, known, self.bound(known)

    def find(
        self,
        pose: Pose,
        queue: Iterable[object],
        known: frozenset[object],
        blocked: frozenset[Cell],
    ) -> T | None:
        """The detour at ``pose`` for the ``queue`` of actions under the known faults ``known``
        with ``blocked`` believed blocked (the window rule of the module docstring).

        The warm path, kept to a few dozen bytecodes per window: the queue iterated (a queue
        view pays indexing in Python), each action's :data:`_Step` read by identity, the end
        cell's code read by one index, and for a window that may end there one dictionary
        look-up of its slot and one of the masked start code. Slot ids are ``j * _WINDOW_STEP +
        h0 * _HEADING_STEP + h * _SIDE ** 2 + (x - x0 + _OFF) * _SIDE + y - y0 + _OFF`` for a
        window of ``j`` actions from ``(x0, y0, h0)`` to ``(x, y, h)``, kept by each step's
        ``delta``."""
        if blocked is not self._codes.blocked:
            self._codes.sync(blocked)
        if known is not self._bound_known:
            self._rebind(known)
        codes, slots, center = self._flat, self._slots, self._center
        p = pose.y * self._width + pose.x
        start = codes[p]
        slot_id = self._starts[pose.heading]
        actions = iter(queue)
        for action in actions:
            try:
                dp, sweep, delta, steps = self._steps[pose.heading][id(action)]
            except KeyError:  # an equal copy of a domain action
                dp, sweep, delta, steps = self._step(pose.heading, action)
            break
        else:
            return None  # nothing queued
        for action in actions:  # the window of the actions before this one
            p += dp
            slot_id += delta
            code = codes[p]  # a queued plan's predicted poses stay on the grid
            try:
                dp, sweep, delta, steps = steps[id(action)]
            except KeyError:
                dp, sweep, delta, steps = self._step(slot_id // _SIDE2 % 4, action)
            if code & center and code & sweep == sweep:  # it ends free; this one sweeps free
                try:
                    slot = slots[slot_id]
                except KeyError:
                    slot = self._slot(slot_id)
                if slot is None:
                    return None  # the window's end left the table's radius
                masked = start & slot.mask
                try:
                    found = slot.answers[masked]
                except KeyError:
                    found = slot.fill(masked)
                if found:
                    return found
            if slot_id >= _LIMIT:
                return None  # the longest window
        p += dp  # the whole queue is the window
        slot_id += delta
        return self._last(slot_id, start) if codes[p] & center else None

    def next_blocked(
        self, pose: Pose, actions: Sequence[object], begin: int, start: int
    ) -> tuple[int, Pose] | None:
        """Where a rewriting pass meets the next blocked window: from ``pose``, the pose the
        plan predicts before ``actions[begin]``, the first ``k >= start`` whose action sweeps a
        believed-blocked cell (but the one it starts from) from the pose the plan predicts
        there, with that pose; ``None`` when none does or a predicted pose leaves the grid (a
        plan that leaves it is not this walk's to mend). Reads the codes as the last
        :meth:`find` left them (the belief it was given)."""
        codes, width, height, moves = self._flat, self._width, self._height, self._moves
        quads = self._index.quads
        x, y, h = pose.x, pose.y, int(pose.heading)
        for k in range(begin, len(actions)):
            action = actions[k]
            quad = quads.get(id(action))
            if quad is None:
                quad = 4 * self._index.of(action)  # an equal copy of a domain action
            dx, dy, h1, sweep = moves[quad + h]
            if k >= start and codes[y * width + x] & sweep != sweep:
                return k, Pose(x, y, Heading(h))
            x, y, h = x + dx, y + dy, h1
            if not (0 <= x < width and 0 <= y < height):
                return None
        return None

    def _last(self, slot_id: int, start: int) -> T | None:
        """The answer of the window that takes in the whole queue (off the warm loop)."""
        slot = self._slots[slot_id] if slot_id in self._slots else self._slot(slot_id)
        if slot is None:
            return None
        masked = start & slot.mask
        found: T | Missing | None = slot.answers.get(masked, MISSING)
        return slot.fill(masked) if found is MISSING else found

    def _slot(self, slot_id: int) -> _Slot[T] | None:
        """The slot of ``slot_id`` (see :meth:`find`), made on first use; ``None`` when its end
        is beyond the table's radius."""
        radius = self.table.radius
        rx = slot_id // _SIDE % _SIDE - _OFF
        ry = slot_id % _SIDE - _OFF
        slot = None  # stored too, so that a warm walk that stops there raises nothing
        if -radius <= rx <= radius and -radius <= ry <= radius:
            key = (slot_id // _HEADING_STEP % 4, rx, ry, slot_id // _SIDE2 % 4)
            slot = _Slot(self.table, key, slot_id // _WINDOW_STEP, self._bound, self.answer)
        self._slots[slot_id] = slot
        return slot
