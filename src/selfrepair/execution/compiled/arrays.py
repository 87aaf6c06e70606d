"""A domain, a fault schedule and a table's compiled look-ups as the integer arrays the compiled
mission loop reads (:mod:`selfrepair.execution.compiled.kernel`, whose docstring gives the
layouts).

Everything here is derived from the values the Python loop uses, never defined a second time:
the moves come from the simulator's :class:`~selfrepair.execution.moves.MoveTable` (itself
derived from ``Domain.apply``/``footprint``/``duration``), availability and the faults that block
an action from ``Domain.available``/``Domain.blocking`` per subset of the schedule's faults, and
every look-up answer from the Python loop's compiled look-ups
(:class:`~selfrepair.repair.lookups.GridLookups`, which run the reference search for a pattern met
for the first time). :class:`CompiledLookups` copies those answers into a hash table of integer
keys as the kernel asks for them.

Caches: the move and availability arrays are the simulator's bookkeeping
(:attr:`~selfrepair.caching.CacheKind.SIMULATION`, kept by cold runs, like the move tables they
copy); the compiled look-ups hold repair answers (:attr:`~selfrepair.caching.CacheKind.REPAIR`,
emptied by a cold run, like the look-ups they copy).
"""

from __future__ import annotations

from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.moves import MoveTable
from selfrepair.geometry import FreeGrid
from selfrepair.repair.lookups import MISSING, GridLookups, action_index, occupancy_rows
from selfrepair.repair.replacement import DEFERRING, Replacement
from selfrepair.repair.strategies import MissionContext, Repair
from selfrepair.repair.strategies.replacement import (
    deferring_lookups,
    hit_repair,
    strategy_lookups,
)
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "MAX_CODE_RADIUS",
    "MAX_SCHEDULE_FAULTS",
    "CompiledLookups",
    "compiled_lookups",
    "empty_hash",
    "fault_arrays",
    "move_arrays",
]

Int64s = npt.NDArray[np.int64]

MAX_SCHEDULE_FAULTS = 10
"""The most distinct faults a schedule may name for the compiled loop (it tabulates every subset:
``2^n`` rows of availability)."""

MAX_CODE_RADIUS = 3
"""The largest occupancy window radius whose codes fit 63 bits (``(2r + 1)^2 = 49``); a look-up
of a wider neighbourhood is keyed by cell instead (same answers, one per cell)."""


def empty_hash(capacity: int) -> Int64s:
    """An empty hash table of the kernels (:func:`kernel.hash_put`) with room for ``capacity``
    slots: one row ``(k1, k2, value, 0)`` per slot (first keys all :data:`kernel.EMPTY`), the
    rows 32 bytes on 64-byte boundaries, so that a probe reads one cache line."""
    table = _aligned((capacity, k.H_COLS))
    table[:, k.H_K1] = k.EMPTY
    return table


def _aligned(shape: tuple[int, int]) -> Int64s:
    """A zeroed int64 array of ``shape`` whose data starts on a 64-byte boundary."""
    size = shape[0] * shape[1]
    raw = np.zeros(size + 8, dtype=np.int64)
    skip = (-raw.ctypes.data % 64) // 8
    return raw[skip : skip + size].reshape(shape)


def move_arrays(table: MoveTable) -> Int64s:
    """``mv[a, h] = (dx, dy, heading, units, n_cells, cells...)`` of ``table`` (per action index
    of its domain and heading; cells as offsets into the table's buffer stride)."""
    return _MOVES.get(table, lambda: _moves(table))


def _moves(table: MoveTable) -> Int64s:
    per = list(table.moves.values())
    width = max((len(m.cells) for moves in per for m in moves), default=0)
    out = np.zeros((len(per), 4, 5 + width), dtype=np.int64)
    for moves in per:
        for h, m in enumerate(moves):
            row = out[m.action_index, h]
            row[:5] = (m.dx, m.dy, int(m.heading), m.units, len(m.cells))
            row[5 : 5 + len(m.cells)] = m.cells
    out.setflags(write=False)
    return out


_MOVES: BoundedCache[MoveTable, Int64s] = BoundedCache(
    "compiled move arrays", 64, kind=CacheKind.SIMULATION
)


def fault_arrays(
    domain: SomeDomain, faults: tuple[object, ...]
) -> tuple[npt.NDArray[np.uint8], Int64s]:
    """For every subset ``m`` (a bit mask over ``faults``): ``avail[m, a]``, whether action ``a``
    is available under it, and ``block[m, a]``, the mask of the faults of ``m`` that block it
    (``Domain.blocking``)."""
    return _FAULTS.get((domain, faults), lambda: _faults(domain, faults))


def _faults(
    domain: SomeDomain, faults: tuple[object, ...]
) -> tuple[npt.NDArray[np.uint8], Int64s]:
    n = len(faults)
    actions = domain.actions
    avail = np.zeros((1 << n, len(actions)), dtype=np.uint8)
    block = np.zeros((1 << n, len(actions)), dtype=np.int64)
    bit = {f: 1 << i for i, f in enumerate(faults)}
    for mask in range(1 << n):
        subset = frozenset(f for i, f in enumerate(faults) if mask >> i & 1)
        for a, action in enumerate(actions):
            if domain.available(action, subset):
                avail[mask, a] = 1
            else:
                block[mask, a] = sum(bit[f] for f in domain.blocking(action, subset))
    avail.setflags(write=False)
    block.setflags(write=False)
    return avail, block


_FAULTS: BoundedCache[
    tuple[SomeDomain, tuple[object, ...]], tuple[npt.NDArray[np.uint8], Int64s]
] = BoundedCache(
    "compiled availability per fault subset", 256, kind=CacheKind.SIMULATION
)


class CompiledLookups:
    """The compiled look-ups of one (table, recursion mode, depth bound, pattern budget) on one
    grid, for every known fault set met so far, as the kernel's arrays (mutable: it grows as the
    kernel asks). Answer ids index :attr:`answers`, the very :class:`Repair` values the Python
    loop's look-ups return.
    """

    def __init__(self, context: MissionContext, n_actions: int) -> None:
        self.context = context
        self.grid: FreeGrid = context.grid
        self.n_slots = 4 * n_actions
        self.deferring = context.options.recursion in DEFERRING
        """Whether answers may defer faulty complex actions (``primitive``): look-ups are then
        per (known faults, guard set), and an answer lists its deferred positions."""
        self.sets: dict[tuple[frozenset[object], frozenset[object]], int] = {}
        self.known_of: list[frozenset[object]] = []
        self.guards: list[frozenset[object]] = [frozenset()]
        """The guard sets met so far, by id (0: none)."""
        self._guard_ids: dict[frozenset[object], int] = {frozenset(): 0}
        self.gh = empty_hash(1 << 6)
        self._g_stored = 0
        self.ans_dpos = np.zeros(64, dtype=np.int64)
        self._n_def = 0
        self._kept: list[object] = []
        self._set_of: dict[tuple[object, ...], npt.NDArray[np.int64]] = {}
        self.on_grid: list[GridLookups[Any]] = []
        self.lk = np.full((4, self.n_slots, 2), k.UNLOADED, dtype=np.int64)
        """Per look-up id and slot: ``(mask, radius index)`` (mask :data:`kernel.UNLOADED`
        until the kernel asks for the slot)."""
        self.radii: list[int] = []
        self.codes = np.zeros((0, self.grid.height, self.grid.width), dtype=np.int64)
        self.ht = empty_hash(1 << 10)
        self.stored = 0
        self.answers: list[Repair] = []
        self._ids: dict[int, int] = {}
        self.ans = np.zeros((64, k.A_COLS), dtype=np.int64)
        """Per answer id: ``(off, len, doff, dlen)``, where its actions and (deferring mode)
        its deferred positions lie in :attr:`ans_act` and :attr:`ans_dpos`."""
        self.ans_act = np.zeros(256, dtype=np.int32)
        self._n_act = 0
        self.longest = 0
        """The most actions of any answer stored (what bounds a whole-plan rewrite's splice)."""

    def set_of(self, faults: tuple[object, ...]) -> npt.NDArray[np.int64]:
        """Per bit mask over ``faults`` (a schedule's), the id of its look-ups (-1: not met
        yet); one array per tuple of faults, kept, so a later mission over the same faults
        starts with every set it needs known."""
        found = self._set_of.get(faults)
        if found is None:
            found = self._set_of[faults] = np.full(1 << len(faults), -1, dtype=np.int64)
        return found

    def set_id(self, known: frozenset[object], guard: frozenset[object] = frozenset()) -> int:
        """The id of the look-ups under ``known`` with the guard set ``guard`` (only a deferring
        mode has guards; made on first use)."""
        sid = self.sets.get((known, guard))
        if sid is None:
            sid = self.sets[known, guard] = len(self.on_grid)
            on_grid: GridLookups[Any] = (
                deferring_lookups(self.context, known, guard, self.grid)
                if self.deferring
                else strategy_lookups(self.context, known, self.grid)
            )
            self.on_grid.append(on_grid)
            self.known_of.append(known)
            if sid >= self.lk.shape[0]:
                self.lk = _grown(self.lk, k.UNLOADED)
        return sid

    def serve_guard(self, k1: int, k2: int) -> None:
        """Answer the kernel's ``NEED_GUARD`` for key ``(k1, k2)`` and store it: for an even
        ``k1 = 2 g``, the id of guard set ``g`` with action ``k2`` added; for an odd
        ``k1 = 2 g + 1``, the look-up id of the known faults of look-up ``k2`` with guard ``g``."""
        guard = self.guards[k1 >> 1]
        if k1 & 1:
            value = self.set_id(self.known_of[k2], guard)
        else:
            grown = guard | {self.context.domain.actions[k2]}
            value = self._guard_ids.get(grown, -1)
            if value < 0:
                value = self._guard_ids[grown] = len(self.guards)
                self.guards.append(grown)
        if 2 * (self._g_stored + 1) > self.gh.shape[0]:
            self.gh = _rehashed(self.gh)
        k.hash_put(self.gh, k1, k2, value)
        self._g_stored += 1

    def load_slot(self, sid: int, slot: int) -> None:
        """Load the masks of the action of ``slot`` (all four headings) and copy the answers its
        look-ups hold already."""
        on_grid = self.on_grid[sid]
        first = slot & ~3
        lookup = on_grid.lookups.action(first >> 2)
        if on_grid.slots[first] is None:
            on_grid.slot(first)
        radius = lookup.radius
        by_cell = radius > MAX_CODE_RADIUS
        ridx = 0 if by_cell else self._radius_index(radius)
        for h in range(4):
            mask = int(lookup.masks[h])
            self.lk[sid, first + h] = (k.BY_CELL if by_cell else mask, ridx)
            if not by_cell:
                for key, value in list(lookup.answers[h].items()):
                    self._put(sid, first + h, key, value)

    def fill(self, sid: int, slot: int, x: int, y: int, key: int) -> None:
        """Answer the pattern of ``slot`` at cell ``(x, y)`` (masked code ``key``, or the cell for
        a slot read by cell) with the Python loop's look-ups, and store it."""
        on_grid = self.on_grid[sid]
        mask, answers, rows = on_grid.slots[slot] or on_grid.slot(slot)
        code = rows[y][x] & mask
        value = answers.get(code, MISSING)
        if value is MISSING:
            value = on_grid.fill(slot, x, y, code)
        self._put(sid, slot, key, value)

    def _put(self, sid: int, slot: int, key: int, value: Repair | Replacement | None) -> None:
        if 2 * (self.stored + 1) > self.ht.shape[0]:
            self.ht = _rehashed(self.ht)
        aid = k.NO_ANSWER if value is None else self._answer(value)
        k.hash_put(self.ht, sid * self.n_slots + slot, key, aid)
        self.stored += 1

    def _answer(self, value: Repair | Replacement) -> int:
        """The id of answer ``value``: a :class:`Repair`, or in a deferring mode a
        :class:`Replacement` (its repair and its deferred positions are stored)."""
        aid = self._ids.get(id(value))
        if aid is not None:
            return aid
        aid = self._ids[id(value)] = len(self.answers)
        self._kept.append(value)  # keeps ``value`` alive, so its id stays its own
        if aid >= self.ans.shape[0]:
            self.ans = _grown(self.ans, 0)
        if isinstance(value, Replacement):
            self.answers.append(hit_repair(value))
            deferred = value.deferred
            while self._n_def + len(deferred) > self.ans_dpos.shape[0]:
                self.ans_dpos = _grown(self.ans_dpos, 0)
            self.ans[aid, k.A_DOFF], self.ans[aid, k.A_DLEN] = self._n_def, len(deferred)
            self.ans_dpos[self._n_def : self._n_def + len(deferred)] = deferred
            self._n_def += len(deferred)
        else:
            self.answers.append(value)
        of = action_index(self.context.domain).of  # by identity, else by equality
        acts = [of(a) for a in value.actions]
        while self._n_act + len(acts) > self.ans_act.shape[0]:
            self.ans_act = _grown(self.ans_act, 0)
        self.ans[aid, k.A_OFF], self.ans[aid, k.A_LEN] = self._n_act, len(acts)
        self.ans_act[self._n_act : self._n_act + len(acts)] = acts
        self._n_act += len(acts)
        self.longest = max(self.longest, len(acts))
        return aid

    def _radius_index(self, radius: int) -> int:
        if radius not in self.radii:
            rows = np.array(occupancy_rows(self.grid, radius), dtype=np.int64)
            self.codes = np.concatenate([self.codes, rows[None]], axis=0)
            self.radii.append(radius)
        return self.radii.index(radius)


def _rehashed(table: Int64s) -> Int64s:
    """The hash table ``table`` in twice the room."""
    out = empty_hash(2 * table.shape[0])
    for k1, k2, value in table[table[:, k.H_K1] != k.EMPTY, : k.H_V + 1].tolist():
        k.hash_put(out, k1, k2, value)
    return out


_G = TypeVar("_G", bound=np.generic)


def _grown(array: npt.NDArray[_G], fill: int) -> npt.NDArray[_G]:
    """``array`` twice as long (first axis), the new rows ``fill``."""
    out = np.full((2 * array.shape[0], *array.shape[1:]), fill, dtype=array.dtype)
    out[: array.shape[0]] = array
    return out


def compiled_lookups(context: MissionContext, n_actions: int) -> CompiledLookups:
    """The :class:`CompiledLookups` of the mission's table, recursion mode, depth bound and
    pattern budget on its grid (kept per process, emptied by a cold run)."""
    options = context.options
    key = (
        context.table,
        options.recursion,
        options.max_depth,
        options.max_lookup_patterns,
        context.grid,
    )
    return _LOOKUPS.get(key, lambda: CompiledLookups(context, n_actions))


_LOOKUPS: BoundedCache[tuple[object, ...], CompiledLookups] = BoundedCache(
    "compiled look-ups as arrays", 64, kind=CacheKind.REPAIR, per_map=True
)
