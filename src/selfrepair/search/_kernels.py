"""Numba kernels for the planners: the same A* as :func:`selfrepair.search.astar.astar`, compiled.

Optional: without numba, :data:`NUMBA` is false and the ``"auto"`` backend uses pure Python.
Everything that defines the problem (motion geometry, durations, heuristic bounds) is computed in
Python from the robot's :class:`~selfrepair.robots.domain.Domain` and passed in as integer tables;
the kernels only search.

Layout: the grid is padded by one wall cell on every side and flattened, so a cell is one integer
``p = (y + 1) * (width + 2) + (x + 1)`` and every motion is a fixed integer offset; a lattice
state is ``4 * p + heading``.

The open list is an indexed 4-ary heap with decrease-key: a node whose ``g`` improves takes a new
counter and moves up in place. The grid's records are ``(f, h, counter, node)``, one row of a 2-D
array each; the lattice, whose costs are integers, packs ``f`` and ``h`` into one key
``(f << s) | h`` (``s`` bits hold the largest ``h``) and the counter and node into a second word
``(counter << 31) | node``: records of two words (16 bytes, the four children of a slot in one
cache line), ordered by the key and then by the counter. Pops are bottom-up (the hole goes down
to a leaf, then the last record up), and the slots from the heap's size on hold sentinel records
that never win, so a pop always compares four children. Whatever the arrangement inside the heap,
it pops exactly the entries that the lazy-deletion heap of :func:`selfrepair.search.astar.astar`
pops, in the same order (the keys are unique), so both backends return the same plan.

Per-state scratch is reused from one search to the next: ``g``, the heap slot, and a *word*
holding a generation stamp and the move that reached the state (lattice: one record
``[g, word, slot]`` per state, 32-bit when the problem's bound on ``f`` fits, so 12 bytes a
touched state; stamp above bit 10, heading of the parent and move index below; grid: three
arrays, the word a stamp above a move in 3 bits). Stamps are ``2k + 1`` (open) and ``2k + 2``
(closed) in search ``k``, anything lower is unvisited, so a new search clears nothing: only the
states a search touches cost memory or time, which matters for a small search on a large map.
Parents are not stored: the move and the parent's heading give the parent state.

The search kernels are compiled with ``_nrt=False`` (numba's reference counting off): they only
read and write arrays handed in, never allocate, and with counting on numba surrounds every call
and tuple of arrays in the hot loops with atomic reference-count updates, which took most of the
grid kernel's time.

A step term (:class:`~selfrepair.search.term.StepTerm`, the tolerant planner's) is read per
expanded cell: the cell's row of counts (per heading and move), found for a term by pattern by
gathering the cell's pattern from the term's grid and probing its table's index
(:func:`_pattern_row`), and kept per cell between searches on that term (:class:`_TermState`);
a pattern the table lacks is added by the kernel itself when the table knows the answer of every
part of it (:func:`_assemble`), and otherwise makes the kernel return, with the pattern's code,
so the source can add its row.

Kernels are resumable: all search state lives in arrays, and a call stops after a given number of
expansions (so that the Python wrapper can look at the clock between calls) or when the heap or
queue array is full (the wrapper then grows it and calls again).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, NamedTuple, TypeVar

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.jit import NUMBA, njit
from selfrepair.robots.domain import Domain
from selfrepair.search.astar import PlanStatus
from selfrepair.search.openmoves import open_moves
from selfrepair.search.problem import CellBound, PlanningProblem, make_pose, pose_table
from selfrepair.search.term import PART_STEP, PATTERN_MIX, PatternTable, StepTerm
from selfrepair.world.maze import Maze

_Fn = TypeVar("_Fn", bound=Callable[..., Any])


def _search_kernel(fn: _Fn) -> _Fn:
    """Compile ``fn`` like the other kernels, without reference counting (see the module
    docstring) and assuming no NaN (no value of the searches is one): a float comparison is then
    one branch, not two."""
    options: dict[str, Any] = {"cache": True, "_nrt": False, "fastmath": {"nnan"}}
    return njit(**options)(fn)  # type: ignore[no-any-return]


__all__ = ["CHUNK", "NUMBA", "bfs_padded", "grid_search", "plan_lattice", "term_counts"]

CHUNK = 1 << 15
"""Expansions per kernel call when a time limit is set (between two looks at the clock)."""

_PAUSED, _SOLVED, _UNSOLVABLE, _GROW, _MISS = 0, 1, 2, 3, 4
_GOING = -1
"""What :func:`_halt` says of a search that goes on (never returned by a kernel)."""
_SIZE, _COUNTER, _EXPANSIONS, _FOUND, _CODE = 0, 1, 2, 3, 4
_WITH, _HARD, _PER, _PW, _FSTRIDE, _FBASE = 0, 1, 2, 3, 4, 5
"""The lattice kernel's step-term parameters: whether there is a term, whether it is hard, the
scaled cost per count (soft), the kernel's padded width, and the stride and base offset of the
term's grid (see :func:`_pattern_row`)."""
_F, _H, _C, _NODE = 0, 1, 2, 3  # heap record columns
_MOVE_BITS = 10
"""Lattice words: the parent's heading (2 bits) and the move index (8 bits) below the stamp."""
_MOVE_MASK = (1 << _MOVE_BITS) - 1
_LATTICE_MARK_MAX = (1 << (31 - _MOVE_BITS)) - 1
_GRID_MARK_MAX = int(np.iinfo(np.uint16).max) >> 3
_FIRST_HEAP = 1 << 12
"""Heap records allocated at first; the heap doubles when a search needs more."""

# motion table columns (per heading and move): end-cell offset, end heading, scaled duration,
# neighbourhood bits of the footprint, number of footprint cells, then the footprint offsets
_DCELL, _NHEAD, _DUR, _NEED, _NSW, _SW = 0, 1, 2, 3, 4, 5


# --- indexed 4-ary heap of records -------------------------------------------------------------
# Row i holds (f, h, counter, node) and pos[node] == i; the children of row i are rows 4i+1 ..
# 4i+4: half the levels of a binary heap, so fewer cache misses.


@njit(cache=True, inline="always")
def _less(f1: Any, h1: Any, c1: Any, f2: Any, h2: Any, c2: Any) -> bool:
    if f1 != f2:
        return bool(f1 < f2)
    if h1 != h2:
        return bool(h1 < h2)
    return bool(c1 < c2)


@njit(cache=True, inline="always")
def _put(heap: Any, pos: Any, i: int, f: Any, h: Any, c: Any, node: Any) -> None:
    """Put the record ``(f, h, c, node)`` in slot ``i`` and record the slot."""
    heap[i, 0] = f
    heap[i, 1] = h
    heap[i, 2] = c
    heap[i, 3] = node
    pos[int(node)] = i


@njit(cache=True, inline="always")
def _move(heap: Any, pos: Any, i: int, j: int) -> None:
    """Move the record of slot ``j`` to slot ``i`` (:func:`_put`)."""
    _put(heap, pos, i, heap[j, 0], heap[j, 1], heap[j, 2], heap[j, 3])


@_search_kernel
def _sift_up(heap: Any, pos: Any, i: int, f: Any, h: Any, c: Any, node: Any) -> None:
    """Place the record ``(f, h, c, node)`` at slot ``i`` or above (a push when ``i`` is the
    heap's size, a decrease-key when it is the node's slot)."""
    while i > 0:
        up = (i - 1) >> 2
        if not _less(f, h, c, heap[up, 0], heap[up, 1], heap[up, 2]):
            break
        _move(heap, pos, i, up)
        i = up
    _put(heap, pos, i, f, h, c, node)


@_search_kernel
def _pop(heap: Any, pos: Any, size: int) -> int:
    """Remove the top record; ``size`` is the heap size before the pop. Returns the new size.
    Bottom-up, like :func:`_pop2`."""
    size -= 1
    if size > 0:
        f, h, c, node = heap[size, 0], heap[size, 1], heap[size, 2], heap[size, 3]
        heap[size, 0] = np.inf  # sentinel: slots size .. size + 3 never win (see _push)
        i = 0
        while True:
            first = 4 * i + 1
            if first >= size:
                break
            child = first
            for other in range(first + 1, first + 4):
                if _less(
                    heap[other, 0], heap[other, 1], heap[other, 2],
                    heap[child, 0], heap[child, 1], heap[child, 2],
                ):  # fmt: skip
                    child = other
            _move(heap, pos, i, child)
            i = child
        _sift_up(heap, pos, i, f, h, c, node)
    return size


# --- indexed 4-ary heap of two-word records (the lattice) ----------------------------------------
# Row ``_BASE + i`` holds slot i: ``(key, tie)`` with ``tie = (counter << _TIE_BITS) | node``, so
# the order of ties is that of counters (they are unique) and the node needs no column of its own:
# 16 bytes a record. The array's rows ``_BASE + 4i + 1`` .. ``_BASE + 4i + 4`` (the children of slot
# i) are rows ``4(i + 1)`` .. ``4(i + 1) + 3``: one 64-byte cache line when the array starts on one
# (:func:`_heap` sees to that).

_BASE = 3
_G, _WORD, _SLOT = 0, 1, 2
"""Columns of the lattice's per-state records: cost so far, word (stamp and move), heap slot."""
_NO_KEY = (1 << 63) - 1
"""The key of the sentinel records in the slots from the heap's size on: a pop compares four
children without bounds checks, and these never win (real keys are below ``2**62``)."""
_TIE_BITS = 31
_TIE_MASK = (1 << _TIE_BITS) - 1


@njit(cache=True, inline="always")
def _put2(heap: Any, rec: Any, i: int, key: int, tie: int) -> None:
    """Put the record ``(key, tie)`` in slot ``i`` and record the slot in its state's record."""
    heap[_BASE + i, 0] = key
    heap[_BASE + i, 1] = tie
    rec[tie & _TIE_MASK, _SLOT] = i


@_search_kernel
def _sift_up2(heap: Any, rec: Any, i: int, key: int, tie: int) -> None:
    """Place the record ``(key, tie)`` at slot ``i`` or above (a push when ``i`` is the heap's
    size, a decrease-key when it is the node's slot)."""
    while i > 0:
        up = (i - 1) >> 2
        uk = heap[_BASE + up, 0]
        ut = heap[_BASE + up, 1]
        if key > uk or (key == uk and tie > ut):
            break
        _put2(heap, rec, i, uk, ut)
        i = up
    _put2(heap, rec, i, key, tie)


@_search_kernel
def _pop2(heap: Any, rec: Any, size: int) -> int:
    """Remove the top record; ``size`` is the heap size before the pop. Returns the new size.

    Bottom-up: the hole at the top moves down along the smallest children to a leaf (one
    comparison fewer per level than a sift-down), then the last record moves up from there. The
    heap is then arranged differently than after a sift-down, but holds the same records, and
    the keys are unique, so the order of the pops is the same."""
    size -= 1
    if size > 0:
        key = heap[_BASE + size, 0]
        tie = heap[_BASE + size, 1]
        heap[_BASE + size, 0] = _NO_KEY  # sentinel (see _lattice's pushes)
        i = 0
        while True:
            first = 4 * i + 1
            if first >= size:
                break
            child = first
            ck = heap[_BASE + first, 0]
            ct = heap[_BASE + first, 1]
            for other in range(first + 1, first + 4):
                ok = heap[_BASE + other, 0]
                ot = heap[_BASE + other, 1]
                if (ok < ck) | ((ok == ck) & (ot < ct)):
                    child, ck, ct = other, ok, ot
            _put2(heap, rec, i, ck, ct)
            i = child
        _sift_up2(heap, rec, i, key, tie)
    return size


# --- the stop test of the resumable searches -------------------------------------------------


@njit(cache=True, inline="always")
def _halt(size: int, room: int, expansions: int, limit: int) -> int:
    """Why a resumable search (:func:`_lattice`, :func:`_grid`) stops before its next expansion:
    its open list is empty (``_UNSOLVABLE``), this call's budget is spent (``_PAUSED``) or the
    heap has no room for the next expansion's pushes (``_GROW``); ``_GOING`` when it goes on."""
    if size <= 0:
        return _UNSOLVABLE
    if expansions >= limit:
        return _PAUSED
    if size > room:
        return _GROW
    return _GOING


# --- breadth-first distances -------------------------------------------------------------------


@njit(cache=True, inline="always")
def _visit(dist: Any, queue: Any, q: int, d: int, head: int, count: int, mask: int) -> int:
    """Give unvisited cell ``q`` distance ``d`` and queue it; returns the new queue length."""
    if dist[q] == -1:
        dist[q] = d
        queue[(head + count) & mask] = q
        count += 1
    return count


@_search_kernel
def _bfs(pw: int, dist: Any, queue: Any, st: Any) -> int:
    """Breadth-first search on ``dist`` (-1 marks an unvisited free cell, -2 a wall) from the
    cells in the ring ``queue`` (``st``: head and count; the capacity is a power of two). Returns
    1 when the queue must grow before going on, else 0."""
    mask = queue.shape[0] - 1
    head, count = st[0], st[1]
    while count > 0:
        if count + 4 > mask + 1:
            st[0], st[1] = head, count
            return 1
        p = queue[head]
        head = (head + 1) & mask
        count -= 1
        d = dist[p] + 1
        count = _visit(dist, queue, p - pw, d, head, count, mask)
        count = _visit(dist, queue, p + 1, d, head, count, mask)
        count = _visit(dist, queue, p + pw, d, head, count, mask)
        count = _visit(dist, queue, p - 1, d, head, count, mask)
    st[0], st[1] = head, count
    return 0


def _cached(cache: BoundedCache[Any, Any], key: Hashable, make: Callable[[], Any]) -> Any:
    return cache.get(key, make)


@dataclass(slots=True)
class _Scratch:
    """Per-thread search arrays of one kind, reused across searches (mutable by nature)."""

    size: int
    arrays: dict[str, Any]
    mark_max: int
    generation: int = 0

    def next_marks(self) -> tuple[int, int]:
        """The (open, closed) stamps of a new search; clears the marks when they run out."""
        opened = 2 * self.generation + 1
        if opened + 1 > self.mark_max:
            self.arrays["mark"].fill(0)
            self.generation, opened = 0, 1
        self.generation += 1
        return opened, opened + 1


_local = threading.local()


def _per_thread(name: str) -> dict[str, Any]:
    """This thread's dict ``name`` of reused arrays (made empty on first use)."""
    cache: dict[str, Any] | None = getattr(_local, name, None)
    if cache is None:
        cache = {}
        setattr(_local, name, cache)
    return cache


def _scratch(tag: str, n: int, spec: tuple[tuple[str, Any], ...], mark_max: int) -> _Scratch:
    """Scratch arrays of ``n`` states kept per thread and reused across searches.

    Fresh arrays would cost a page fault per touched page on every query, which for the
    million-state lattice of a 512x512 map is as slow as the search itself. Arrays are reused for
    any size from a quarter of theirs up; ``mark`` starts zeroed (lazily, by the OS), the others
    are never read before a search writes them. The heap is allocated small and grown on demand.
    """
    cache = _per_thread("scratch")
    entry = cache.get(tag)
    if entry is None or not n <= entry.size <= 4 * n:
        arrays = {
            name: np.zeros(n, dtype=dtype) if name == "mark" else np.empty(n, dtype=dtype)
            for name, dtype in spec
        }
        entry = cache[tag] = _Scratch(n, arrays, mark_max)
    return entry


def _records(tag: str, n: int, dtype: Any, mark_max: int) -> _Scratch:
    """Per-thread records of ``n`` lattice states (``[g, word, heap slot]`` rows, see
    :data:`_G`), zeroed lazily by the OS and reused across searches like :func:`_scratch`'s
    arrays; ``arrays["mark"]`` is the view of the words."""
    cache = _per_thread("scratch")
    entry = cache.get(tag)
    if entry is None or not n <= entry.size <= 4 * n:
        rec = np.zeros((n, 3), dtype=dtype)
        entry = cache[tag] = _Scratch(n, {"rec": rec, "mark": rec[:, _WORD]}, mark_max)
    return entry


def _heap(tag: str, dtype: Any, need: int, columns: int = 4) -> npt.NDArray[Any]:
    """The per-thread heap array of ``tag``, at least ``need`` records of ``columns`` words long,
    starting on a 64-byte boundary."""
    cache = _per_thread("heaps")
    heap = cache.get(tag)
    if heap is None or heap.shape[0] < need:
        size = max(_FIRST_HEAP, need, 0 if heap is None else 2 * heap.shape[0])
        raw = np.empty(size * columns + 8, dtype=dtype)
        skip = (-raw.ctypes.data % 64) // raw.itemsize
        fresh = raw[skip : skip + size * columns].reshape(size, columns)
        if heap is not None:
            fresh[: heap.shape[0]] = heap
        heap = cache[tag] = fresh
    return heap


def _padded(maze: Maze, inner: Any, border: int, dtype: Any, width: int = 1) -> npt.NDArray[Any]:
    """An array of the maze's shape grown by ``width`` cells on every side: ``inner`` (a value
    per maze cell) inside, ``border`` on the border (the padded layout of the kernels)."""
    out = np.full((maze.height + 2 * width, maze.width + 2 * width), border, dtype=dtype)
    out[width:-width, width:-width] = inner
    return out


def _frozen_flat(array: npt.NDArray[Any]) -> npt.NDArray[Any]:
    """``array`` flattened (row after row) and made read-only, as the plan caches keep it."""
    out = array.ravel()
    out.setflags(write=False)
    return out


def _padded_free(maze: Maze) -> npt.NDArray[np.uint8]:
    def make() -> npt.NDArray[np.uint8]:
        return _frozen_flat(_padded(maze, ~maze.walls, 0, np.uint8))

    return _cached(_FREE, maze, make)  # type: ignore[no-any-return]


_FREE: BoundedCache[Maze, npt.NDArray[np.uint8]] = BoundedCache(
    "padded free cells", 8, kind=CacheKind.PLAN, per_map=True
)


def _neighbourhoods(maze: Maze) -> npt.NDArray[np.uint16]:
    """Per padded cell: bit ``3 * (dy + 1) + (dx + 1)`` is set when the cell ``(dx, dy)`` away is
    free."""

    def make() -> npt.NDArray[np.uint16]:
        free = _padded(maze, ~maze.walls, 0, np.uint16, width=2)
        h, w = maze.height + 2, maze.width + 2
        mask = np.zeros((h, w), dtype=np.uint16)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                bit = np.uint16(1 << (3 * (dy + 1) + dx + 1))
                mask |= free[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w] * bit
        return _frozen_flat(mask)

    return _cached(_NEIGHBOURS, maze, make)  # type: ignore[no-any-return]


_NEIGHBOURS: BoundedCache[Maze, npt.NDArray[np.uint16]] = BoundedCache(
    "lattice neighbourhood masks", 8, kind=CacheKind.PLAN, per_map=True
)


def bfs_padded(maze: Maze, goal: Cell) -> npt.NDArray[np.int32]:
    """4-connected BFS distances to ``goal``, shape ``(height + 2, width + 2)``.

    Negative means unreachable: -1 for a free cell cut off from the goal, -2 for a wall or the
    border. The queue is a ring that grows with the frontier, not with the maze.
    """
    pw = maze.width + 2
    dist = np.where(_padded_free(maze) != 0, -1, -2).astype(np.int32)
    goal_p = (goal[1] + 1) * pw + goal[0] + 1
    dist[goal_p] = 0
    queue = np.empty(_FIRST_QUEUE, dtype=np.int32)
    queue[0] = goal_p
    st = np.array([0, 1], dtype=np.int64)
    while _bfs(pw, dist, queue, st):
        head, count = int(st[0]), int(st[1])
        live = queue[(head + np.arange(count)) & (queue.shape[0] - 1)]
        queue = np.empty(2 * queue.shape[0], dtype=np.int32)
        queue[:count] = live
        st[0] = 0
    return dist.reshape(maze.height + 2, pw)


_FIRST_QUEUE = 1 << 12
"""Breadth-first queue entries allocated at first (a power of two; doubled on demand)."""


# --- robot lattice -------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _pattern_code(cell: int, pw: int, term: Any, free: Any, offs: Any) -> Any:
    """The pattern code of kernel cell ``cell``, read from ``free`` (the term's grid,
    ``term[_FSTRIDE]`` bytes a row, cell ``(x, y)`` at ``(y + 1) * stride + x + 1 + term[_FBASE]``
    in padded coordinates) at ``offs``."""
    y = cell // pw
    q = y * term[_FSTRIDE] + (cell - y * pw) + term[_FBASE]
    code = np.int64(0)
    for j in range(offs.shape[0]):
        code |= np.int64(free[q + offs[j]]) << j
    return code


@njit(cache=True, inline="always")
def _pattern_row(cell: int, pw: int, term: Any, free: Any, offs: Any, keys: Any, rows: Any) -> int:
    """The pattern row of kernel cell ``cell`` (-1: a pattern the table has not met): its code
    (:func:`_pattern_code`) probed in the open-addressing index ``keys``/``rows`` from
    :func:`selfrepair.search.term.pattern_slot`'s slot."""
    code = _pattern_code(cell, pw, term, free, offs)
    mask = keys.shape[0] - 1
    slot = ((code ^ (code >> 7) ^ (code >> 19)) * PATTERN_MIX) & mask
    while True:
        key = keys[slot]
        if key == code:
            return int(rows[slot])
        if key < 0:
            return -1
        slot = (slot + 1) & mask


@njit(cache=True, inline="always")
def _assemble(
    code: Any, project: Any, parts: Any, acounts: Any, counts: Any, answers: Any, codes: Any,
    keys: Any, rows: Any, meta: Any,
) -> int:  # fmt: skip
    """Add the row of pattern ``code`` to a :class:`~selfrepair.search.term.PatternTable` (its
    arrays, ``counts``, ``answers`` and ``parts`` flat: every array of the lattice kernel is
    one-dimensional, so that the mission kernel's one stand-in fits them all) from the answers
    of its parts, and return the row;
    -1 when a part has no answer yet or the table has no room (``meta``; the caller then adds
    the row). Probes as :func:`~selfrepair.search.term.part_slot` and
    :meth:`~selfrepair.search.term.PatternTable.add` do."""
    size = meta[0]
    if size >= meta[1]:
        return -1
    n = project.shape[0]
    base = size * n
    pmask = parts.shape[0] // 3 - 1
    for i in range(n):
        part = code & project[i]
        first = ((part ^ (part >> 7) ^ (part >> 19)) * PATTERN_MIX) & pmask
        slot = (first + i * PART_STEP) & pmask
        while True:
            key = parts[3 * slot]
            if key == part and parts[3 * slot + 1] == i:
                break
            if key < 0:
                return -1
            slot = (slot + 1) & pmask
        answer = parts[3 * slot + 2]
        answers[base + i] = answer
        counts[base + i] = acounts[answer]
    codes[size] = code
    mask = keys.shape[0] - 1
    slot = ((code ^ (code >> 7) ^ (code >> 19)) * PATTERN_MIX) & mask
    while keys[slot] >= 0:
        slot = (slot + 1) & mask
    keys[slot] = code
    rows[slot] = size
    meta[0] = size + 1
    return int(size)


@_search_kernel
def _lattice(
    nbr: Any, pen: Any, hdist: Any, mt: Any, par: Any, rec: Any, heap: Any, scal: Any,
    term: Any, counts: Any, crow: Any, free: Any, offs: Any, keys: Any, rows: Any,
    project: Any, parts: Any, acounts: Any, answers: Any, codes: Any, meta: Any,
) -> int:  # fmt: skip
    rnum, rden, wmul = par[0], par[1], par[2]
    goal_cell, goal_head, limit, opened, shift = par[3], par[4], par[5], par[6], par[7]
    with_term, hard, per_count = term[_WITH], term[_HARD], term[_PER]
    pw = term[_PW]
    closed = opened + 1
    size, counter, expansions = scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS]
    nmoves = mt.shape[1]
    room = heap.shape[0] - _BASE - nmoves - 4
    status = _halt(size, room, expansions, limit)
    while status == _GOING:
        s = heap[_BASE, 1] & _TIE_MASK
        cell = s >> 2
        head = s & 3
        at_goal = cell == goal_cell and (goal_head < 0 or head == goal_head)
        row = 0
        if with_term and not at_goal:  # the step term's row of this cell, read on expansion
            row = crow[cell]
            if row < 0:
                row = _pattern_row(cell, pw, term, free, offs, keys, rows)
                if row < 0:  # a pattern never met: its row from its parts' answers, if known
                    code = _pattern_code(cell, pw, term, free, offs)
                    row = _assemble(
                        code, project, parts, acounts, counts, answers, codes, keys, rows, meta
                    )  # fmt: skip
                    if row < 0:  # else the caller fills it, then calls again
                        scal[_FOUND] = cell
                        scal[_CODE] = code
                        status = _MISS
                        break
                crow[cell] = row
            row = (row * 4 + head) * nmoves
        size = _pop2(heap, rec, size)
        rec[s, _WORD] = (closed << _MOVE_BITS) | (rec[s, _WORD] & _MOVE_MASK)
        expansions += 1
        if at_goal:
            scal[_FOUND] = s
            status = _SOLVED
            break
        gs = rec[s, _G]
        around = nbr[cell]
        for k in range(nmoves):
            need = mt[head, k, _NEED]
            if around & need != need:
                continue
            nc = cell + mt[head, k, _DCELL]
            ns = 4 * nc + mt[head, k, _NHEAD]
            m = rec[ns, _WORD] >> _MOVE_BITS
            if m == closed:
                continue
            gn = gs + mt[head, k, _DUR]
            if with_term:  # the step term: a count forbids the step (hard) or costs per_count
                c = counts[row + k]
                if c:
                    if hard:
                        continue
                    gn += c * per_count
            if wmul:
                penalty = 0
                for j in range(mt[head, k, _NSW]):
                    penalty += pen[cell + mt[head, k, _SW + j]]
                gn += wmul * penalty
            if m == opened and gn >= rec[ns, _G]:
                continue
            d = hdist[nc]
            if d < 0:
                continue
            hv = d * rnum if rden == 1 else d * rnum // rden
            counter += 1
            rec[ns, _G] = gn
            rec[ns, _WORD] = (opened << _MOVE_BITS) | (head << 8) | k
            key = ((gn + hv) << shift) | hv
            if m == opened:
                _sift_up2(heap, rec, rec[ns, _SLOT], key, (counter << _TIE_BITS) | ns)
            else:
                _sift_up2(heap, rec, size, key, (counter << _TIE_BITS) | ns)
                size += 1
                heap[_BASE + size + 3, 0] = _NO_KEY
        status = _halt(size, room, expansions, limit)
    scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS] = size, counter, expansions
    return status


@njit(cache=True)
def _walk_lattice(rec: Any, mt: Any, start: int, goal: int) -> Any:
    """The states from ``start`` to ``goal`` (``out[0]``), the move index into each (``out[1]``,
    -1 for the start) and the scaled duration of the path (``out[2, 0]``)."""
    n = 1
    s = goal
    while s != start:
        pm = rec[s, _WORD] & _MOVE_MASK
        head = pm >> 8
        s = 4 * ((s >> 2) - mt[head, pm & 255, _DCELL]) + head
        n += 1
    out = np.zeros((3, n), dtype=np.int64)
    s = goal
    total = 0
    for i in range(n - 1, -1, -1):
        out[0, i] = s
        if i:
            pm = rec[s, _WORD] & _MOVE_MASK
            head = pm >> 8
            k = pm & 255
            out[1, i] = k
            total += mt[head, k, _DUR]
            s = 4 * ((s >> 2) - mt[head, k, _DCELL]) + head
    out[1, 0] = -1
    out[2, 0] = total
    return out


class _Motion(NamedTuple):
    """A motion table (read-only), its largest duration, and the moves as an object array (to
    turn the kernel's move indices into actions in one step)."""

    table: npt.NDArray[np.int64]
    dur_max: int
    moves: npt.NDArray[np.object_]


def _motion(domain: Domain[Any, Any], moves: tuple[Any, ...], pw: int, scale: int) -> _Motion:
    """Integer motion table ``[heading, move, column]`` of the planning actions ``moves``, from
    the domain's moves on an open plane (:func:`~selfrepair.search.openmoves.open_moves`, shared
    with the other readers of a run) and ``domain.duration`` (columns as in the module's
    ``_DCELL`` .. ``_SW``). Raises :class:`OverflowError` for an action that reaches beyond the
    3x3 neighbourhood or a duration that is not a multiple of ``1/scale``. Rows are made as
    Python lists and copied into the array once."""
    n = len(moves)
    if n > 255:
        raise OverflowError("more than 255 planning actions")
    table_of = open_moves(domain)
    index = [table_of.index(a) for a in moves]
    width = max([len(cells) for i in index for cells in table_of.footprints[i]] or [1])
    durations = []
    for action in moves:
        duration = domain.duration(action)
        scaled = Fraction(duration) * scale
        if scaled.denominator != 1:
            raise OverflowError(f"duration {duration} is not a multiple of 1/{scale}")
        durations.append(scaled.numerator)
    rows: list[list[list[int]]] = []
    for heading in range(4):
        per: list[list[int]] = []
        for i, units in zip(index, durations, strict=True):
            dx, dy, end_heading = table_of.ends[i][heading]
            if max(abs(dx), abs(dy)) > 1:
                raise OverflowError("an action moves beyond the 3x3 neighbourhood")
            swept = table_of.footprints[i][heading]
            row = [0] * (_SW + width)
            row[_DCELL], row[_NHEAD], row[_DUR] = dy * pw + dx, end_heading, units
            row[_NSW] = len(swept)
            need = 0
            for j, (x, y) in enumerate(swept):
                if max(abs(x), abs(y)) > 1:
                    raise OverflowError("an action sweeps beyond the 3x3 neighbourhood")
                row[_SW + j] = y * pw + x
                need |= 1 << (3 * (y + 1) + x + 1)
            row[_NEED] = need
            per.append(row)
        rows.append(per)
    table = np.array(rows, dtype=np.int64).reshape(4, n, _SW + width)
    table.setflags(write=False)
    objects = np.empty(n, dtype=object)
    objects[:] = moves
    return _Motion(table, int(table[:, :, _DUR].max(initial=0)), objects)


_MOTIONS: BoundedCache[Hashable, _Motion] = BoundedCache(
    "lattice motion tables", 256, kind=CacheKind.PLAN
)


def _padded_penalty(maze: Maze, radius: int) -> tuple[npt.NDArray[np.int64], int]:
    """The clearance penalties in the padded layout (``radius`` on the border) and their
    maximum."""

    def make() -> tuple[npt.NDArray[np.int64], int]:
        from selfrepair.world.maze import clearance_penalties

        out = _frozen_flat(_padded(maze, clearance_penalties(maze, radius), radius, np.int64))
        return out, int(out.max(initial=0))

    return _cached(_PENALTY, (maze, radius), make)  # type: ignore[no-any-return]


_PENALTY: BoundedCache[tuple[Maze, int], tuple[npt.NDArray[np.int64], int]] = BoundedCache(
    "padded clearance penalties", 8, kind=CacheKind.PLAN, per_map=True
)

_NO_PENALTY = np.zeros(1, dtype=np.int64)
_NO_PENALTY.setflags(write=False)


class _TermState:
    """What the lattice kernel reads of one step term, kept between its searches (mutable: the
    cell rows fill as cells are expanded): the counts per row (flat), each padded kernel cell's
    row (-1: not read yet), and for a term by pattern its grid's bytes, the pattern's cells as
    offsets in them and the pattern table the rows refer to."""

    __slots__ = (
        "acounts",
        "answers",
        "base",
        "codes",
        "counts",
        "crow",
        "free",
        "keys",
        "meta",
        "offs",
        "parts",
        "project",
        "rows",
        "stride",
        "table",
    )

    def __init__(self, term: StepTerm, pw: int) -> None:
        height, width = term.size
        self.crow = np.full((height + 2) * pw, -1, dtype=np.int32)
        self.table: PatternTable | None = None
        source = term.source
        if source is None:  # dense counts: cell (x, y) is row y * width + x
            inner = self.crow.reshape(height + 2, pw)[1:-1, 1:-1]
            inner[:] = np.arange(height * width, dtype=np.int32).reshape(height, width)
            self.counts = term.dense_counts().astype(np.int32).reshape(-1)  # a writable copy
            self.free, self.offs, self.keys, self.rows = _NO_BYTES, _NO_INTS, _NO_INTS, _NO_ROWS
            self._no_parts()
            self.stride = self.base = 0
            return
        grid = source.grid
        table = source.table()
        reach = table.reach
        margin = grid.margin
        free = np.frombuffer(grid.data, dtype=np.uint8)
        if margin < reach:  # cells beyond the margin are walls
            free = np.pad(free.reshape(grid.height + 2 * margin, grid.stride), reach - margin)
            margin = reach
            free = free.ravel()
            free.setflags(write=False)
        self.free = free
        self.stride = grid.width + 2 * margin
        self.base = (margin - 1) * self.stride + margin - 1
        self.offs = table.dy * self.stride + table.dx
        self.counts, self.keys, self.rows = _NO_COUNTS, _NO_INTS, _NO_ROWS
        self._no_parts()
        self.refresh(table)

    def _no_parts(self) -> None:
        self.project, self.parts, self.acounts = _NO_INTS, _NO_PARTS, _NO_ROWS
        self.answers, self.codes, self.meta = _NO_ROWS, _NO_INTS, _NO_META

    def arrays(self) -> tuple[npt.NDArray[Any], ...]:
        """The kernel's term arrays: counts, cell rows, grid bytes, offsets, index keys, rows,
        then the table's parts (projections, index, answer counts) and its rows' answers, codes
        and meta (see :class:`~selfrepair.search.term.PatternTable`)."""
        return (
            self.counts, self.crow, self.free, self.offs, self.keys, self.rows,
            self.project, self.parts, self.acounts, self.answers, self.codes, self.meta,
        )  # fmt: skip

    def refresh(self, table: PatternTable) -> None:
        """Read ``table``'s current arrays; a new table (the source started afresh) makes every
        cell row read so far stale."""
        if table is not self.table and self.table is not None:
            self.crow.fill(-1)
        self.table = table
        self.counts = table.counts.reshape(-1)
        self.keys, self.rows = table.keys, table.rows
        self.project, self.acounts = table.project, table.acounts
        self.parts = table.parts.reshape(-1)
        self.answers, self.codes, self.meta = table.answers.reshape(-1), table.codes, table.meta


# Stand-ins the kernel never reads (no term, or a dense one), with the flags of the real arrays
# (only the grid's bytes are read-only), so that every call has one signature.
_NO_BYTES = np.zeros(1, dtype=np.uint8)
_NO_BYTES.setflags(write=False)
_NO_INTS = np.full(1, -1, dtype=np.int64)
_NO_ROWS = np.zeros(1, dtype=np.int32)
_NO_COUNTS = np.zeros(1, dtype=np.int32)
_NO_CELLS = np.zeros(1, dtype=np.int32)
_NO_TERM = np.zeros(6, dtype=np.int64)
_NO_PARTS = np.full(3, -1, dtype=np.int64)
_NO_META = np.zeros(2, dtype=np.int64)  # no room: the kernel never adds a row
_NO_TERM_ARRAYS = (
    _NO_COUNTS, _NO_CELLS, _NO_BYTES, _NO_INTS, _NO_INTS, _NO_ROWS,
    _NO_INTS, _NO_PARTS, _NO_ROWS, _NO_ROWS, _NO_INTS, _NO_META,
)  # fmt: skip


def _term_state(term: StepTerm, pw: int) -> _TermState:
    state: _TermState = _cached(_TERM_STATES, term, lambda: _TermState(term, pw))
    return state


_TERM_STATES: BoundedCache[StepTerm, _TermState] = BoundedCache(
    "step terms as the lattice kernel reads them", 16, kind=CacheKind.PLAN, per_map=True
)


@njit(cache=True)
def _pattern_rows(
    cells: Any, pw: int, term: Any, free: Any, offs: Any, keys: Any, rows: Any, out: Any,
    codes: Any,
) -> None:  # fmt: skip
    for i in range(cells.shape[0]):
        out[i] = _pattern_row(cells[i], pw, term, free, offs, keys, rows)
        codes[i] = _pattern_code(cells[i], pw, term, free, offs)


def term_counts(term: StepTerm) -> npt.NDArray[np.int32]:
    """The counts of ``term`` at every pose, ``[y, x, heading, k]``, read as the lattice kernel
    reads them: a term by pattern through the kernel's own pattern gather and index probe (the
    source filling the patterns its table lacks), a dense one as is. For checking the compiled
    path against :meth:`StepTerm.dense_counts`; 0 on walls (never expanded). The table must hold
    the patterns of every free cell at once."""
    height, width = term.size
    source = term.source
    if source is None:
        return term.dense_counts()
    pw = width + 2
    state = _TermState(term, pw)
    free = np.array([source.grid.is_free(x, y) for y in range(height) for x in range(width)])
    ys, xs = np.divmod(np.flatnonzero(free).astype(np.int64), width)
    cells = (ys + 1) * pw + xs + 1
    tpar = np.array([1, 0, 0, pw, state.stride, state.base], dtype=np.int64)
    out = np.empty(len(cells), dtype=np.int32)
    codes = np.empty(len(cells), dtype=np.int64)
    while True:
        _pattern_rows(
            cells, pw, tpar, state.free, state.offs, state.keys, state.rows, out, codes
        )  # fmt: skip
        missing = np.flatnonzero(out < 0)
        if not len(missing):
            break
        at = int(missing[0])
        source.fill(int(xs[at]), int(ys[at]), int(codes[at]))
        state.refresh(source.table())
    n_actions = len(term.actions)
    found = np.zeros((height, width, 4, n_actions), dtype=np.int32)
    found[ys, xs] = state.counts.reshape(-1, 4, n_actions)[out]
    return found


def _term_bound(term: StepTerm | None, per_count: int) -> int:
    """The largest scaled cost a step term adds to one step (0 for a hard term)."""
    if term is None or term.hard:
        return 0
    if term.source is not None:
        return term.source.max_count * per_count
    return int(term.dense_counts().max(initial=0)) * per_count


def plan_lattice(
    problem: PlanningProblem,
    moves: tuple[Any, ...],
    bound: CellBound,
    scale: int,
    max_expansions: int | None,
    deadline_ns: int | None,
    *,
    key: Hashable | None = None,
    largest: int | None = None,
) -> tuple[PlanStatus, tuple[Any, ...], tuple[Pose, ...], int, int, int]:
    """Run the lattice search over ``moves``; the arguments mean what they mean in
    :mod:`selfrepair.search.lattice` (``problem.clearance_weight`` a
    :class:`~fractions.Fraction`); ``key`` identifies ``(problem.domain, moves)`` for the
    motion-table cache (``moves`` itself when omitted); ``largest`` is the largest distance in
    ``bound`` when the caller knows it (else it is found by a scan).

    Returns status, actions, poses, the scaled integer cost, the scaled integer duration and the
    number of expansions. Raises :class:`OverflowError` when the problem does not fit the integer
    kernel (the caller then uses the pure-Python search).
    """
    maze = problem.maze
    height, width = maze.walls.shape
    pw = width + 2
    n_states = 4 * (height + 2) * pw
    weight = problem.clearance_weight
    wmul = weight.numerator * (scale // weight.denominator)
    pen, pen_max = _padded_penalty(maze, problem.clearance_radius) if wmul else (_NO_PENALTY, 0)
    hdist = bound.padded.ravel().view()
    hdist.setflags(write=False)  # one kernel signature whatever the heuristic hands over
    rnum, rden = bound.rate.numerator * scale, bound.rate.denominator
    common = math.gcd(rnum, rden)
    rnum, rden = rnum // common, rden // common
    domain = problem.domain
    motion = _cached(
        _MOTIONS, (domain, moves if key is None else key, pw, scale),
        lambda: _motion(domain, moves, pw, scale),
    )  # fmt: skip
    mt = motion.table
    hmax = (int(hdist.max(initial=0)) if largest is None else largest) * rnum // rden
    shift = hmax.bit_length()  # heap key: (f << shift) | h, ordered as (f, h)
    term = problem.step_term
    per_count = 0 if term is None or term.penalty is None else int(term.penalty * scale)
    f_max = _check_int64(
        motion.dur_max + _term_bound(term, per_count), mt.shape[2] - _SW, pen_max, wmul, hmax,
        shift, n_states, len(moves),
    )  # fmt: skip
    start = problem.start
    start_cell = (start.y + 1) * pw + start.x + 1
    start_state = 4 * start_cell + start.heading
    if hdist[start_cell] < 0:
        return PlanStatus.UNSOLVABLE, (), (), 0, 0, 0
    goal_cell = (problem.goal[1] + 1) * pw + problem.goal[0] + 1
    goal_head = -1 if problem.goal_heading is None else int(problem.goal_heading)
    narrow = f_max < 1 << 31  # 32-bit costs when every cost fits: 12 bytes a state, not 24
    scratch = _records(
        "lattice32" if narrow else "lattice64", n_states, np.int32 if narrow else np.int64,
        _LATTICE_MARK_MAX,
    )  # fmt: skip
    rec = scratch.arrays["rec"]
    opened, _ = scratch.next_marks()
    h0 = int(hdist[start_cell]) * rnum // rden
    heap = _heap("lattice", np.int64, _FIRST_HEAP, 2)
    rec[start_state] = (0, opened << _MOVE_BITS, 0)
    heap[_BASE] = ((h0 << shift) | h0, start_state)
    heap[_BASE + 1 : _BASE + 4, 0] = _NO_KEY  # slots from the size on never win a comparison
    scal = np.array([1, 0, 0, -1, 0], dtype=np.int64)
    par = np.array([rnum, rden, wmul, goal_cell, goal_head, 0, opened, shift], dtype=np.int64)
    nbr = _neighbourhoods(maze)
    ts = None
    tpar = _NO_TERM
    if term is not None:
        ts = _term_state(term, pw)  # arrays left behind by a grown table: read-only to it
        tpar = np.array([1, int(term.hard), per_count, pw, ts.stride, ts.base], dtype=np.int64)
    missed = -1

    def run(limit: int) -> int:
        nonlocal heap, missed
        while True:
            par[5] = limit
            arrays = _NO_TERM_ARRAYS if ts is None else ts.arrays()
            code = int(_lattice(nbr, pen, hdist, mt, par, rec, heap, scal, tpar, *arrays))
            if code == _GROW:
                heap = _heap("lattice", np.int64, 2 * heap.shape[0], 2)
            elif code == _MISS:  # a pattern the term's table has not met: the source adds it
                assert ts is not None and term is not None and term.source is not None
                cell = int(scal[_FOUND])
                if cell == missed:
                    raise AssertionError(f"pattern of kernel cell {cell} is still missing")
                missed = cell
                term.source.fill(cell % pw - 1, cell // pw - 1, int(scal[_CODE]))
                ts.refresh(term.source.table())
            else:
                return code

    status = _drive(run, scal, max_expansions, deadline_ns)
    expansions = int(scal[_EXPANSIONS])
    if status is not PlanStatus.SOLVED:
        return status, (), (), 0, 0, expansions
    goal = int(scal[_FOUND])
    walk = _walk_lattice(rec, mt, start_state, goal)
    actions = tuple(motion.moves[walk[1, 1:]].tolist())
    cost = int(rec[goal, _G])
    return status, actions, _poses(maze, walk[0], pw), cost, int(walk[2, 0]), expansions


def _poses(maze: Maze, path: npt.NDArray[np.int64], pw: int) -> tuple[Pose, ...]:
    """The poses of a path of lattice states (shared from the maze's pose table if it has one)."""
    table = pose_table(maze)
    if table is not None:  # poses are truthy: ``or`` makes only the missing ones
        return tuple([table[s] or _new_pose(table, s, pw) for s in path.tolist()])
    cells = (path >> 2) - pw - 1
    xs, ys, headings = (cells % pw).tolist(), (cells // pw).tolist(), (path & 3).tolist()
    return tuple(map(make_pose, xs, ys, [_HEADINGS[h] for h in headings]))


def _new_pose(table: list[Pose | None], state: int, pw: int) -> Pose:
    cell = (state >> 2) - pw - 1
    pose = table[state] = make_pose(cell % pw, cell // pw, _HEADINGS[state & 3])
    return pose


_HEADINGS = tuple(Heading)


def _check_int64(
    dur_max: int,
    cells: int,
    pen_max: int,
    wmul: int,
    hmax: int,
    shift: int,
    n_states: int,
    n_moves: int,
) -> int:
    """Refuse problems whose heap keys ``(f << shift) | h`` could overflow int64 (``f`` is at most
    the largest step cost times the number of states plus the largest heuristic value), whose
    states overflow 31 bits or whose push counter (at most one push per move of each state)
    overflows the 32 bits above the node in a heap record's tie word. Returns that bound on
    ``f``."""
    step_max = dur_max + wmul * cells * pen_max
    f_max = step_max * n_states + hmax
    if shift >= 62 or f_max >= 1 << (62 - shift) or wmul >= 1 << 62 or n_states >= 1 << _TIE_BITS:
        raise OverflowError("the problem is too large for the integer kernel")
    if n_states * n_moves >= 1 << (63 - _TIE_BITS):
        raise OverflowError("the problem is too large for the integer kernel")
    return f_max


def _drive(
    run: Callable[[int], int],
    scal: npt.NDArray[np.int64],
    max_expansions: int | None,
    deadline_ns: int | None,
) -> PlanStatus:
    """Call a resumable kernel until it finishes, the node budget is spent or time is up."""
    budget = min(1 << 62, (1 << 62) if max_expansions is None else max_expansions)
    while True:
        limit = budget
        if deadline_ns is not None:
            if time.perf_counter_ns() >= deadline_ns:
                return PlanStatus.BUDGET_EXHAUSTED
            limit = min(budget, int(scal[_EXPANSIONS]) + CHUNK)
        code = run(limit)
        if code == _SOLVED:
            return PlanStatus.SOLVED
        if code == _UNSOLVABLE:
            return PlanStatus.UNSOLVABLE
        if int(scal[_EXPANSIONS]) >= budget:
            return PlanStatus.BUDGET_EXHAUSTED


# --- plain grid ----------------------------------------------------------------------------


@_search_kernel
def _grid(
    free: Any, pw: int, diagonal: bool, goal: int, limit: int, opened: int,
    g: Any, word: Any, heap: Any, scal: Any, pos: Any,
) -> int:  # fmt: skip
    size, counter, expansions = scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS]
    closed = opened + 1
    gx = goal % pw
    gy = goal // pw
    inv = 1.0 / pw
    nmoves = 8 if diagonal else 4
    room = heap.shape[0] - nmoves - 4
    sqrt2 = np.sqrt(2.0)
    keys = (diagonal, sqrt2, opened, closed)
    arrays = (free, g, word, heap, pos)
    status = _halt(size, room, expansions, limit)
    while status == _GOING:
        p = int(heap[0, _NODE])
        size = _pop(heap, pos, size)
        word[p] = (closed << 3) | (word[p] & 7)
        expansions += 1
        if p == goal:
            scal[_FOUND] = p
            status = _SOLVED
            break
        gp = g[p]
        y = int((p + 0.5) * inv)  # p // pw without a division (exact: p is far below 2**40)
        ex = p - y * pw - gx
        ey = y - gy
        north, east, south, west = free[p - pw], free[p + 1], free[p + pw], free[p - 1]
        # N, E, S, W, then NE, SE, SW, NW (a diagonal needs both orthogonal cells free)
        if north:
            size, counter = _relax(p - pw, 0, 1.0, ex, ey - 1, gp, keys, arrays, size, counter)
        if east:
            size, counter = _relax(p + 1, 1, 1.0, ex + 1, ey, gp, keys, arrays, size, counter)
        if south:
            size, counter = _relax(p + pw, 2, 1.0, ex, ey + 1, gp, keys, arrays, size, counter)
        if west:
            size, counter = _relax(p - 1, 3, 1.0, ex - 1, ey, gp, keys, arrays, size, counter)
        if diagonal:
            if north and east:
                size, counter = _relax(
                    p - pw + 1, 4, sqrt2, ex + 1, ey - 1, gp, keys, arrays, size, counter
                )
            if south and east:
                size, counter = _relax(
                    p + pw + 1, 5, sqrt2, ex + 1, ey + 1, gp, keys, arrays, size, counter
                )
            if south and west:
                size, counter = _relax(
                    p + pw - 1, 6, sqrt2, ex - 1, ey + 1, gp, keys, arrays, size, counter
                )
            if north and west:
                size, counter = _relax(
                    p - pw - 1, 7, sqrt2, ex - 1, ey - 1, gp, keys, arrays, size, counter
                )
        status = _halt(size, room, expansions, limit)
    scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS] = size, counter, expansions
    return status


@njit(cache=True, inline="always")
def _relax(
    q: Any, k: int, step: float, ex: Any, ey: Any, gp: float, keys: Any, arrays: Any,
    size: int, counter: int,
) -> tuple[int, int]:  # fmt: skip
    """Relax the edge to cell ``q`` (move ``k``, cost ``step``; ``(ex, ey)`` its offset from the
    goal); returns the new heap size and push counter. Inlined into :func:`_grid`."""
    diagonal, sqrt2, opened, closed = keys
    free, g, word, heap, pos = arrays
    if free[q] == 0:
        return size, counter
    m = word[q] >> 3
    if m == closed:
        return size, counter
    gn = gp + step
    if m == opened and gn >= g[q]:
        return size, counter
    dx = abs(ex)
    dy = abs(ey)
    hv = (dx + dy) + (sqrt2 - 2.0) * min(dx, dy) if diagonal else float(dx + dy)
    counter += 1
    g[q] = gn
    word[q] = (opened << 3) | k
    if m == opened:
        _sift_up(heap, pos, pos[q], gn + hv, hv, float(counter), float(q))
    else:
        _sift_up(heap, pos, size, gn + hv, hv, float(counter), float(q))
        size += 1
        heap[size + 3, 0] = np.inf
    return size, counter


@njit(cache=True)
def _walk_grid(word: Any, pw: int, start: int, goal: int) -> Any:
    """The cells from ``start`` to ``goal`` (``out[:-1]``) and the number of diagonal steps
    (``out[-1]``)."""
    steps = np.array([-pw, 1, pw, -1, 1 - pw, pw + 1, pw - 1, -pw - 1], dtype=np.int64)
    n = 1
    p = goal
    while p != start:
        p -= steps[word[p] & 7]
        n += 1
    out = np.empty(n + 1, dtype=np.int64)
    p = goal
    diagonals = 0
    for i in range(n - 1, -1, -1):
        out[i] = p
        if i:
            k = word[p] & 7
            diagonals += k >= 4
            p -= steps[k]
    out[n] = diagonals
    return out


_GRID_ARRAYS = (("g", np.float64), ("mark", np.uint16), ("pos", np.int32))
"""Per grid cell: cost so far, word (stamp above bit 3, the move that reached it below), heap
slot."""


def grid_search(
    maze: Maze,
    start: Cell,
    goal: Cell,
    connectivity: int,
    max_expansions: int | None,
    deadline_ns: int | None,
) -> tuple[PlanStatus, tuple[Cell, ...], int, int]:
    """Run the plain-grid search; returns status, path (start first), expansions and the number
    of diagonal steps of the path."""
    from selfrepair.search.problem import grid_heuristic

    pw = maze.width + 2
    n = (maze.height + 2) * pw
    if n >= 1 << 31:
        raise OverflowError("the grid is too large for the int32 kernel")
    free = _padded_free(maze)
    s = (start[1] + 1) * pw + start[0] + 1
    goal_p = (goal[1] + 1) * pw + goal[0] + 1
    scratch = _scratch("grid", n, _GRID_ARRAYS, _GRID_MARK_MAX)
    g, word, pos = scratch.arrays["g"], scratch.arrays["mark"], scratch.arrays["pos"]
    opened, _ = scratch.next_marks()
    heap = _heap("grid", np.float64, _FIRST_HEAP)
    h0 = grid_heuristic(start, goal, connectivity)
    g[s], word[s], pos[s] = 0.0, opened << 3, 0
    heap[0] = (h0, h0, 0.0, float(s))
    heap[1:4, 0] = np.inf  # slots from the size on hold infinite f (the pop looks at 4 children)
    scal = np.array([1, 0, 0, -1], dtype=np.int64)
    diagonal = connectivity == 8

    def run(limit: int) -> int:
        nonlocal heap
        while True:
            code = _grid(free, pw, diagonal, goal_p, limit, opened, g, word, heap, scal, pos)
            code = int(code)
            if code != _GROW:
                return code
            heap = _heap("grid", np.float64, 2 * heap.shape[0])

    status = _drive(run, scal, max_expansions, deadline_ns)
    expansions = int(scal[_EXPANSIONS])
    if status is not PlanStatus.SOLVED:
        return status, (), expansions, 0
    walk = _walk_grid(word, pw, s, goal_p)
    cells = walk[:-1] - pw - 1
    xs, ys = (cells % pw).tolist(), (cells // pw).tolist()
    return status, tuple(zip(xs, ys, strict=True)), expansions, int(walk[-1])
