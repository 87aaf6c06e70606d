"""Numba kernels of D* Lite: :class:`~selfrepair.search._dstar_reference.PythonCore`, compiled.

Optional: without numba, :data:`NUMBA` is false and :mod:`selfrepair.search.dstar` runs the
pure-Python reference. Everything that defines the graph (the lattice's integer offsets, the
footprints, the scaled durations of the chosen actions, the free cells and clearance penalties)
is computed in Python and handed in as integer arrays; the kernels only search, and keep all
their state in arrays owned by the caller, so a search is kept between calls.

Layout (as :mod:`selfrepair.search.dstar` documents): a node is ``4 * cell + heading`` with
``cell`` an index into a padded, flattened grid; the virtual goal is node ``N`` (one past the
last lattice node). ``g`` and ``rhs`` are ``int64[N + 1]`` with :data:`INF` for infinity.

Arrays of the graph: ``free`` (``uint8`` per padded cell), ``pen`` (clearance penalty per padded
cell, read only when ``wmul``), ``dur[k]`` (scaled duration of motion class ``k``'s chosen action,
-1 when no action of the class is available), ``step[k, h]`` (node offset), ``nsw[k, h]`` and
``sw[k, h, j]`` (footprint cells as offsets), ``backk[he, i]``, ``backo[he, i]`` and ``nback[he]``
(the ``(class, node offset)`` pairs that arrive at a node facing ``he``).

The open list is an indexed binary heap over ``(k1, k2, node)`` (``hk1``, ``hk2``, ``hn``;
``pos[node]`` its slot, -1 when the node is not queued): a node is queued at most once, with its
current key. That order is total (nodes are unique), so the kernels pop exactly the nodes that
the reference's lazy-deletion heap pops, in the same order, whatever the heap's arrangement.

``sc`` holds the scalars: :data:`SIZE`, :data:`KM`, :data:`START`, :data:`EXPANSIONS` (written
back) and the constants :data:`GOAL_CELL`, :data:`GOAL_HEAD` (-1: any heading), :data:`RNUM`,
:data:`RDEN` (the heuristic is ``manhattan * RNUM // RDEN``), :data:`WMUL` (clearance weight
times the cost scale), :data:`PW` (padded row length) and :data:`NODES` (``N``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from selfrepair.jit import NUMBA, njit
from selfrepair.search._dstar_reference import INF, Graph

__all__ = ["NUMBA", "CompiledCore", "compute", "faults_sweep", "update_nodes", "walk"]

SIZE, KM, START, EXPANSIONS = 0, 1, 2, 3
GOAL_CELL, GOAL_HEAD, RNUM, RDEN, WMUL, PW, NODES = 4, 5, 6, 7, 8, 9, 10
N_SCALARS = 11

I64 = npt.NDArray[np.int64]
"""The kernels' integer arrays: costs, steps, sweeps, the search state and the scalars ``sc``."""
U8 = npt.NDArray[np.uint8]
"""The free-cell bytes of the padded grid (and the fault sweep's marks)."""

_Fn = TypeVar("_Fn", bound=Callable[..., object])


def _kernel(fn: _Fn) -> _Fn:
    """Compile ``fn`` without numba's reference counting (the search kernels never allocate;
    see :mod:`selfrepair.search._kernels`)."""
    options: dict[str, Any] = {"cache": True, "_nrt": False}
    return njit(**options)(fn)  # type: ignore[no-any-return]


def _inline(fn: _Fn) -> _Fn:
    """Compile ``fn`` as :func:`_kernel`, inlined into its callers."""
    options: dict[str, Any] = {"cache": True, "_nrt": False, "inline": "always"}
    return njit(**options)(fn)  # type: ignore[no-any-return]


def _allocating(fn: _Fn) -> _Fn:
    """Compile ``fn`` with reference counting (it returns a new array)."""
    options: dict[str, Any] = {"cache": True}
    return njit(**options)(fn)  # type: ignore[no-any-return]


@_inline
def _cost(free: U8, pen: I64, dur: I64, nsw: I64, sw: I64, wmul: int, u: int, k: int) -> int:
    """Scaled cost of class ``k`` from node ``u`` (INF: no action, or a footprint cell blocked)."""
    d = dur[k]
    if d < 0:
        return INF
    cell = u >> 2
    h = u & 3
    n = nsw[k, h]
    for j in range(n):
        if free[cell + sw[k, h, j]] == 0:
            return INF
    if wmul:
        p = 0
        for j in range(n):
            p += pen[cell + sw[k, h, j]]
        d += wmul * p
    return int(d)


@_inline
def _at_goal(sc: I64, free: U8, u: int) -> bool:
    gh = sc[GOAL_HEAD]
    return bool(
        (u >> 2) == sc[GOAL_CELL] and (gh < 0 or (u & 3) == gh) and free[sc[GOAL_CELL]] != 0
    )


@_inline
def _h(sc: I64, u: int) -> int:
    if u == sc[NODES]:
        return 0
    pw = sc[PW]
    a = u >> 2
    b = sc[START] >> 2
    d = abs(a % pw - b % pw) + abs(a // pw - b // pw)
    return int(d * sc[RNUM] // sc[RDEN])


@_inline
def _less(a1: int, a2: int, an: int, b1: int, b2: int, bn: int) -> bool:
    if a1 != b1:
        return a1 < b1
    if a2 != b2:
        return a2 < b2
    return an < bn


@_inline
def _put(hk1: Any, hk2: Any, hn: Any, pos: Any, i: int, k1: int, k2: int, n: int) -> None:
    """Put node ``n`` with key ``(k1, k2)`` in heap slot ``i`` and record the slot."""
    hk1[i], hk2[i], hn[i] = k1, k2, n
    pos[n] = i


@_inline
def _move(hk1: Any, hk2: Any, hn: Any, pos: Any, i: int, j: int) -> None:
    """Move the entry of heap slot ``j`` to slot ``i`` (:func:`_put`)."""
    _put(hk1, hk2, hn, pos, i, hk1[j], hk2[j], hn[j])


@_kernel
def _sift_up(hk1: I64, hk2: I64, hn: I64, pos: I64, i: int) -> None:
    k1, k2, n = hk1[i], hk2[i], hn[i]
    while i > 0:
        up = (i - 1) >> 1
        if not _less(k1, k2, n, hk1[up], hk2[up], hn[up]):
            break
        _move(hk1, hk2, hn, pos, i, up)
        i = up
    _put(hk1, hk2, hn, pos, i, k1, k2, n)


@_kernel
def _sift_down(hk1: I64, hk2: I64, hn: I64, pos: I64, i: int, size: int) -> None:
    k1, k2, n = hk1[i], hk2[i], hn[i]
    while True:
        c = 2 * i + 1
        if c >= size:
            break
        if c + 1 < size and _less(hk1[c + 1], hk2[c + 1], hn[c + 1], hk1[c], hk2[c], hn[c]):
            c += 1
        if not _less(hk1[c], hk2[c], hn[c], k1, k2, n):
            break
        _move(hk1, hk2, hn, pos, i, c)
        i = c
    _put(hk1, hk2, hn, pos, i, k1, k2, n)


@_kernel
def _remove(hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64, u: int) -> None:
    i = pos[u]
    if i < 0:
        return
    pos[u] = -1
    size = sc[SIZE] - 1
    sc[SIZE] = size
    if i == size:
        return
    _move(hk1, hk2, hn, pos, i, size)
    if i > 0 and _less(
        hk1[i], hk2[i], hn[i], hk1[(i - 1) >> 1], hk2[(i - 1) >> 1], hn[(i - 1) >> 1]
    ):
        _sift_up(hk1, hk2, hn, pos, i)
    else:
        _sift_down(hk1, hk2, hn, pos, i, size)


@_inline
def _best_step(
    free: U8, pen: I64, dur: I64, step: I64, nsw: I64, sw: I64, g: I64, wmul: int, u: int
) -> tuple[int, int, int]:
    """The best step out of node ``u``: ``(c + g, k, c)`` for the class ``k`` of least cost ``c``
    plus ``g`` of its end (ties: the lowest class); ``(INF, -1, 0)`` when no step has both
    finite. ``rhs(u)`` is its first element (away from the goal), the plan follows its class."""
    h = u & 3
    best, bk, bc = INF, -1, 0
    for k in range(dur.shape[0]):
        c = _cost(free, pen, dur, nsw, sw, wmul, u, k)
        if c < INF:
            gv = g[u + step[k, h]]
            if gv < INF and c + gv < best:
                best, bk, bc = c + gv, k, c
    return best, bk, bc


@_kernel
def _requeue(g: I64, rhs: I64, hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64, u: int) -> None:
    """Queue ``u`` with its current key when it is inconsistent, else take it off the queue."""
    gu, ru = g[u], rhs[u]
    if gu == ru:
        _remove(hk1, hk2, hn, pos, sc, u)
        return
    m = min(gu, ru)
    k1 = m + _h(sc, u) + sc[KM]
    i = pos[u]
    if i < 0:
        i = sc[SIZE]
        sc[SIZE] = i + 1
        hk1[i], hk2[i], hn[i] = k1, m, u
        _sift_up(hk1, hk2, hn, pos, i)
    else:
        old1, old2 = hk1[i], hk2[i]
        hk1[i], hk2[i] = k1, m
        if _less(k1, m, u, old1, old2, u):
            _sift_up(hk1, hk2, hn, pos, i)
        else:
            _sift_down(hk1, hk2, hn, pos, i, sc[SIZE])


@_kernel
def _update(
    free: U8, pen: I64, dur: I64, step: I64, nsw: I64, sw: I64,
    g: I64, rhs: I64, hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64, u: int,
) -> None:  # fmt: skip
    """Recompute ``rhs(u)`` from its successors, then requeue it."""
    goal = sc[NODES]
    if u != goal:
        best, _, _ = _best_step(free, pen, dur, step, nsw, sw, g, sc[WMUL], u)
        if _at_goal(sc, free, u) and g[goal] < best:
            best = g[goal]
        rhs[u] = best
    _requeue(g, rhs, hk1, hk2, hn, pos, sc, u)


@_kernel
def update_nodes(
    free: U8, pen: I64, dur: I64, step: I64, nsw: I64, sw: I64,
    g: I64, rhs: I64, hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64, nodes: I64,
) -> None:  # fmt: skip
    """:func:`_update` every node of ``nodes`` (edges out of them changed cost)."""
    for i in range(nodes.shape[0]):
        _update(free, pen, dur, step, nsw, sw, g, rhs, hk1, hk2, hn, pos, sc, nodes[i])


@_kernel
def faults_sweep(
    free: U8, pen: I64, dur: I64, step: I64, nsw: I64, sw: I64,
    backk: I64, backo: I64, nback: I64,
    g: I64, rhs: I64, hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64, mark: U8,
) -> int:  # fmt: skip
    """After the chosen actions changed (``dur``): update every node the search has touched and
    every predecessor of a node with a finite ``g`` (an edge that was impassable may have become
    usable), each once (``mark``: scratch of ``N`` bytes). Returns the number of updates (an
    update reads only ``g``, which none changes, so their order does not matter)."""
    goal = sc[NODES]
    wmul = sc[WMUL]
    for u in range(goal):
        mark[u] = 1 if g[u] < INF or rhs[u] < INF else 0
    for u in range(goal):
        if g[u] < INF:
            he = u & 3
            for i in range(nback[he]):
                p = u - backo[he, i]
                k = backk[he, i]
                if (
                    0 <= p < goal
                    and mark[p] == 0
                    and _cost(free, pen, dur, nsw, sw, wmul, p, k) < INF
                ):
                    mark[p] = 1
    count = 0
    for u in range(goal):
        if mark[u]:
            _update(free, pen, dur, step, nsw, sw, g, rhs, hk1, hk2, hn, pos, sc, u)
            count += 1
    return count


@_kernel
def compute(
    free: U8, pen: I64, dur: I64, step: I64, nsw: I64, sw: I64,
    backk: I64, backo: I64, nback: I64,
    g: I64, rhs: I64, hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64, budget: int,
) -> int:  # fmt: skip
    """D* Lite's ComputeShortestPath: run until the start is consistent and no queued key is
    below its key (returns 1), or until ``sc[EXPANSIONS]`` reaches ``budget`` (returns 0)."""
    goal = sc[NODES]
    wmul = sc[WMUL]
    gcell = sc[GOAL_CELL]
    gh = sc[GOAL_HEAD]
    while True:
        start = sc[START]
        ms = min(g[start], rhs[start])
        s1 = INF if ms >= INF else ms + _h(sc, start) + sc[KM]
        s2 = INF if ms >= INF else ms
        if sc[SIZE] == 0 or (not _less(hk1[0], hk2[0], 0, s1, s2, 0) and g[start] == rhs[start]):
            return 1
        if sc[EXPANSIONS] >= budget:
            return 0
        u = hn[0]
        o1, o2 = hk1[0], hk2[0]
        _remove(hk1, hk2, hn, pos, sc, u)
        sc[EXPANSIONS] += 1
        gu, ru = g[u], rhs[u]
        m = min(gu, ru)
        n1 = m + _h(sc, u) + sc[KM]
        if _less(o1, o2, 0, n1, m, 0):
            _requeue(g, rhs, hk1, hk2, hn, pos, sc, u)
            continue
        settled = gu > ru  # over-consistent: settle it; its predecessors may now go through it
        if settled:
            g[u] = ru
        else:  # under-consistent: forget it; recompute whoever went through it
            g[u] = INF
            _update(free, pen, dur, step, nsw, sw, g, rhs, hk1, hk2, hn, pos, sc, u)
        through = ru if settled else gu
        graph = (free, pen, dur, step, nsw, sw)
        if u == goal:  # the goal's predecessors: the goal cell's poses, at no cost
            if free[gcell] != 0:
                for h in range(4):
                    if gh < 0 or h == gh:
                        _via(graph, g, rhs, hk1, hk2, hn, pos, sc, 4 * gcell + h, through, settled)
            continue
        he = u & 3
        for i in range(nback[he]):
            p = u - backo[he, i]
            if not 0 <= p < goal:
                continue
            c = _cost(free, pen, dur, nsw, sw, wmul, p, backk[he, i])
            if c < INF:
                _via(graph, g, rhs, hk1, hk2, hn, pos, sc, p, c + through, settled)


@_inline
def _via(
    graph: Any, g: I64, rhs: I64, hk1: I64, hk2: I64, hn: I64, pos: I64, sc: I64,
    p: int, cost: int, settled: bool,
) -> None:  # fmt: skip
    """Predecessor ``p`` of a node whose ``g`` changed, ``cost`` its cost through that node at
    the node's old (``settled``: new) ``g``: a settled node lowers ``rhs(p)`` to ``cost``; a
    forgotten one makes ``p`` recompute ``rhs`` when it went through the node."""
    if settled:
        if cost < rhs[p]:
            rhs[p] = cost
            _requeue(g, rhs, hk1, hk2, hn, pos, sc, p)
    elif rhs[p] == cost:
        free, pen, dur, step, nsw, sw = graph
        _update(free, pen, dur, step, nsw, sw, g, rhs, hk1, hk2, hn, pos, sc, p)


@_allocating
def walk(
    free: U8, pen: I64, dur: I64, step: I64, nsw: I64, sw: I64, g: I64, sc: I64
) -> I64:  # fmt: skip
    """The classes of the plan from the start, following ``argmin(c + g)`` (ties: the lowest
    class), then its scaled cost as the last element; an empty array when there is none."""
    goal = sc[NODES]
    wmul = sc[WMUL]
    u = sc[START]
    if g[u] >= INF:
        return np.empty(0, dtype=np.int64)
    out = np.empty(16, dtype=np.int64)
    n = 0
    total = 0
    while not _at_goal(sc, free, u):
        _, bk, bc = _best_step(free, pen, dur, step, nsw, sw, g, wmul, u)
        if bk < 0 or n > goal:
            return np.empty(0, dtype=np.int64)
        if n + 1 >= out.shape[0]:
            bigger = np.empty(2 * out.shape[0], dtype=np.int64)
            bigger[:n] = out[:n]
            out = bigger
        out[n] = bk
        n += 1
        total += bc
        u += step[bk, u & 3]
    out[n] = total
    return out[: n + 1].copy()


class _Scalar:
    """An ``int`` attribute of :class:`CompiledCore` kept in its scalar array ``sc`` at ``index``,
    where the kernels read and write it."""

    def __init__(self, index: int) -> None:
        self.index = index

    def __get__(self, core: CompiledCore, owner: type[CompiledCore] | None = None) -> int:
        return int(core.sc[self.index])

    def __set__(self, core: CompiledCore, value: int) -> None:
        core.sc[self.index] = value


class CompiledCore:
    """The search of :class:`selfrepair.search._dstar_reference.PythonCore` in the kernels above;
    its state is in arrays (mutable)."""

    def __init__(self, dstar: Graph) -> None:
        self.d = dstar
        geo = dstar.geometry
        n = geo.nodes + 1
        k = len(geo.classes)
        self.g = np.full(n, INF, dtype=np.int64)
        self.rhs = np.full(n, INF, dtype=np.int64)
        self.hk1 = np.zeros(n, dtype=np.int64)
        self.hk2 = np.zeros(n, dtype=np.int64)
        self.hn = np.zeros(n, dtype=np.int64)
        self.pos = np.full(n, -1, dtype=np.int64)
        self.mark: npt.NDArray[np.uint8] | None = None  # scratch of the fault sweep, made on use
        self.step = np.array(geo.step, dtype=np.int64).reshape(k, 4)
        width = max([len(c) for per in geo.sweep for c in per] or [1])
        self.nsw = np.zeros((k, 4), dtype=np.int64)
        self.sw = np.zeros((k, 4, width), dtype=np.int64)
        for i, per in enumerate(geo.sweep):
            for h, cells in enumerate(per):
                self.nsw[i, h] = len(cells)
                self.sw[i, h, : len(cells)] = cells
        nb = max(len(b) for b in geo.back) if geo.back else 0
        self.nback = np.array([len(b) for b in geo.back], dtype=np.int64)
        self.backk = np.zeros((4, max(nb, 1)), dtype=np.int64)
        self.backo = np.zeros((4, max(nb, 1)), dtype=np.int64)
        for h, entries in enumerate(geo.back):
            for i, (cls, offset) in enumerate(entries):
                self.backk[h, i], self.backo[h, i] = cls, offset
        sc = np.zeros(N_SCALARS, dtype=np.int64)
        sc[GOAL_CELL], sc[GOAL_HEAD] = dstar.goal_cell, dstar.goal_head
        sc[RNUM], sc[RDEN], sc[WMUL] = dstar.rnum, dstar.rden, dstar.wmul
        sc[PW], sc[NODES] = geo.pw, geo.nodes
        self.sc = sc
        self.rhs[geo.nodes] = 0

    start = _Scalar(START)
    km = _Scalar(KM)
    expansions = _Scalar(EXPANSIONS)

    def set_dur(self, dur: npt.NDArray[np.int64]) -> None:
        pass  # the kernels read the owner's array

    def set_cells(self, cells: Sequence[int]) -> None:
        pass  # the kernels read the owner's arrays

    def _graph(self) -> tuple[U8, I64, I64, I64, I64, I64]:
        d = self.d  # arrays changed in place, never replaced
        return (d.free, d.pen, d.dur, self.step, self.nsw, self.sw)

    def _back(self) -> tuple[I64, I64, I64]:
        return (self.backk, self.backo, self.nback)

    def _state(self) -> tuple[I64, I64, I64, I64, I64, I64, I64]:
        return (self.g, self.rhs, self.hk1, self.hk2, self.hn, self.pos, self.sc)

    def update_nodes(self, nodes: Sequence[int]) -> None:
        array = np.asarray(nodes, dtype=np.int64)
        update_nodes(*self._graph(), *self._state(), array)

    def faults_sweep(self) -> int:
        if self.mark is None:
            self.mark = np.zeros(self.d.geometry.nodes, dtype=np.uint8)
        return int(faults_sweep(*self._graph(), *self._back(), *self._state(), self.mark))

    def compute(self, budget: int) -> bool:
        return bool(compute(*self._graph(), *self._back(), *self._state(), budget))

    def walk(self) -> tuple[list[int], int] | None:
        d = self.d
        out = walk(d.free, d.pen, d.dur, self.step, self.nsw, self.sw, self.g, self.sc)
        if out.shape[0] == 0:
            return None
        return out[:-1].tolist(), int(out[-1])
