"""The pure-Python reference of D* Lite over integer arrays, and the lattice both backends use.

:class:`selfrepair.search.dstar.DStarLite` documents the graph, the heuristic and the
tie-breaking; this module holds its lattice (:class:`Geometry`, built once per search from the
robot) and the reference search (:class:`PythonCore`), which the compiled kernels of
:mod:`selfrepair.search._dstar_kernels` copy step for step. Both read the graph from a
:class:`Graph` (the search object itself).
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import A, Domain, F

__all__ = ["INF", "Core", "Geometry", "Graph", "PythonCore", "geometry", "reach"]

INF = 1 << 60
"""Infinity of ``g``, ``rhs`` and edge costs (an integer; finite sums stay far below
``2**63``, as the kernels need)."""


@dataclass(frozen=True, slots=True)
class Geometry:
    """The lattice of one robot on one padded grid (see the module docstring)."""

    classes: tuple[str, ...]
    pw: int
    margin: int
    nodes: int
    step: tuple[tuple[int, ...], ...]
    sweep: tuple[tuple[tuple[int, ...], ...], ...]
    back: tuple[tuple[tuple[int, int], ...], ...]
    """Per end heading: ``(class, node offset)`` of every move that arrives facing it."""


def reach(domain: Domain[A, F]) -> int:
    reach = 0
    for action in domain.actions:
        for heading in Heading:
            start = Pose(0, 0, heading)
            end = domain.apply(start, action)
            cells = (end.cell, *domain.footprint(start, action))
            reach = max(reach, *(max(abs(x), abs(y)) for x, y in cells))
    return reach


def geometry(domain: Domain[A, F], pw: int, margin: int, rows: int) -> Geometry:
    members: dict[str, A] = {}  # motion class -> its first moving action
    for action in domain.actions:
        if any(domain.apply(Pose(0, 0, h), action) != Pose(0, 0, h) for h in Heading):
            members.setdefault(domain.motion_class(action), action)
    classes = tuple(members)
    step, sweep = [], []
    back: list[list[tuple[int, int]]] = [[] for _ in Heading]
    for k, motion in enumerate(classes):
        per_step, per_sweep = [], []
        for heading in Heading:
            start = Pose(0, 0, heading)
            end = domain.apply(start, members[motion])
            offset = 4 * (end.y * pw + end.x) + (end.heading - heading)
            per_step.append(offset)
            footprint = domain.footprint(start, members[motion])
            per_sweep.append(tuple(y * pw + x for x, y in footprint))
            back[end.heading].append((k, offset))
        step.append(tuple(per_step))
        sweep.append(tuple(per_sweep))
    return Geometry(
        classes, pw, margin, 4 * pw * rows, tuple(step), tuple(sweep), tuple(map(tuple, back))
    )


class Graph(Protocol):
    """What a search core reads: the lattice, the arrays of the graph (free cells, clearance
    penalties, the scaled duration of each class's chosen action, -1 when none) and the
    constants (clearance weight times the cost scale, goal cell and heading (-1: any), the
    heuristic rate ``rnum / rden``). The owner changes the arrays in place."""

    geometry: Geometry
    free: npt.NDArray[np.uint8]
    pen: npt.NDArray[np.int64]
    dur: npt.NDArray[np.int64]
    wmul: int
    goal_cell: int
    goal_head: int
    rnum: int
    rden: int


class Core(Protocol):
    """A search core (mutable: the search state): the reference :class:`PythonCore` or the
    compiled :class:`selfrepair.search._dstar_kernels.CompiledCore`. ``start`` is the start
    node, ``km`` D* Lite's key modifier, ``expansions`` the count since it was last reset."""

    start: int
    km: int
    expansions: int

    def set_dur(self, dur: npt.NDArray[np.int64]) -> None:
        """The chosen actions' durations changed (the owner's ``dur``)."""

    def set_cells(self, cells: Sequence[int]) -> None:
        """The owner's ``free`` and ``pen`` changed at ``cells``."""

    def update_nodes(self, nodes: Sequence[int]) -> None:
        """Recompute ``rhs`` of ``nodes`` (their out-edges changed) and requeue them."""

    def faults_sweep(self) -> int:
        """Update every touched node and the predecessors of every node with a finite ``g``,
        each once; returns the number of updates."""

    def compute(self, budget: int) -> bool:
        """Run until the start is consistent (true) or ``expansions`` reaches ``budget``."""

    def walk(self) -> tuple[list[int], int] | None:
        """The classes of the plan from the start and its scaled cost (``None``: no plan)."""


class PythonCore:
    """The reference D* Lite over Python lists (mutable: the search state)."""

    def __init__(self, dstar: Graph) -> None:
        self.d = dstar
        geo = dstar.geometry
        self.goal = geo.nodes
        self.g = [INF] * (geo.nodes + 1)
        self.rhs = [INF] * (geo.nodes + 1)
        self.heap: list[tuple[int, int, int]] = []
        self.keys: dict[int, tuple[int, int]] = {}
        self.km = 0
        self.start = 0
        self.expansions = 0
        self.free = bytearray(dstar.free.tobytes())
        self.pen = dstar.pen.tolist()
        self.dur: list[int] = []
        self.rhs[self.goal] = 0
        self.set_dur(dstar.dur)

    def set_dur(self, dur: npt.NDArray[np.int64]) -> None:
        self.dur = dur.tolist()

    def set_cells(self, cells: Sequence[int]) -> None:
        for c in cells:
            self.free[c] = int(self.d.free[c])
            if self.d.wmul:
                self.pen[c] = int(self.d.pen[c])

    # --- the graph -----------------------------------------------------------------------------

    def cost(self, u: int, k: int) -> int:
        d = self.dur[k]
        if d < 0:
            return INF
        cells = self.d.geometry.sweep[k][u & 3]
        cell = u >> 2
        free = self.free
        for o in cells:
            if not free[cell + o]:
                return INF
        wmul = self.d.wmul
        if wmul:
            pen = self.pen
            d += wmul * sum(pen[cell + o] for o in cells)
        return d

    def at_goal(self, u: int) -> bool:
        d = self.d
        gh = d.goal_head
        return (u >> 2) == d.goal_cell and (gh < 0 or u & 3 == gh) and self.free[d.goal_cell] != 0

    def predecessors(self, u: int) -> list[tuple[int, int]]:
        d = self.d
        if u == self.goal:
            if not self.free[d.goal_cell]:
                return []
            heads = range(4) if d.goal_head < 0 else (d.goal_head,)
            return [(4 * d.goal_cell + h, 0) for h in heads]
        out = []
        for k, offset in d.geometry.back[u & 3]:
            p = u - offset
            if 0 <= p < self.goal:
                c = self.cost(p, k)
                if c < INF:
                    out.append((p, c))
        return out

    def h(self, u: int) -> int:
        if u == self.goal:
            return 0
        pw = self.d.geometry.pw
        a, b = u >> 2, self.start >> 2
        dist = abs(a % pw - b % pw) + abs(a // pw - b // pw)
        return dist * self.d.rnum // self.d.rden

    def key(self, u: int) -> tuple[int, int]:
        m = min(self.g[u], self.rhs[u])
        if m >= INF:
            return (INF, INF)
        return (m + self.h(u) + self.km, m)

    # --- D* Lite ------------------------------------------------------------------------------

    def requeue(self, u: int) -> None:
        self.keys.pop(u, None)
        if self.g[u] != self.rhs[u]:
            key = self.key(u)
            self.keys[u] = key
            heapq.heappush(self.heap, (key[0], key[1], u))

    def update(self, u: int) -> None:
        if u != self.goal:
            g, step = self.g, self.d.geometry.step
            h = u & 3
            best = INF
            for k in range(len(step)):
                c = self.cost(u, k)
                if c < INF:
                    gv = g[u + step[k][h]]
                    if gv < INF and c + gv < best:
                        best = c + gv
            if self.at_goal(u) and g[self.goal] < best:
                best = g[self.goal]
            self.rhs[u] = best
        self.requeue(u)

    def update_nodes(self, nodes: Sequence[int]) -> None:
        for u in nodes:
            self.update(u)

    def faults_sweep(self) -> int:
        g, rhs = self.g, self.rhs
        nodes = {u for u in range(self.goal) if g[u] < INF or rhs[u] < INF}
        for u in range(self.goal):
            if g[u] < INF:
                nodes.update(p for p, _ in self.predecessors(u))
        for u in sorted(nodes):  # an update reads only g, which none changes: any order will do
            self.update(u)
        return len(nodes)

    def top(self) -> tuple[int, int, int] | None:
        heap, keys = self.heap, self.keys
        while heap:
            k1, k2, u = heap[0]
            if keys.get(u) == (k1, k2):
                return heap[0]
            heapq.heappop(heap)
        return None

    def compute(self, budget: int) -> bool:
        g, rhs = self.g, self.rhs
        while True:
            entry = self.top()
            start = self.start
            if entry is None or (entry[:2] >= self.key(start) and g[start] == rhs[start]):
                return True
            if self.expansions >= budget:
                return False
            heapq.heappop(self.heap)
            u = entry[2]
            del self.keys[u]
            self.expansions += 1
            gu, ru = g[u], rhs[u]
            if entry[:2] < self.key(u):
                self.requeue(u)
            elif gu > ru:
                g[u] = ru
                for p, c in self.predecessors(u):
                    if c + ru < rhs[p]:
                        rhs[p] = c + ru
                        self.requeue(p)
            else:
                g[u] = INF
                self.update(u)
                for p, c in self.predecessors(u):
                    if rhs[p] == c + gu:
                        self.update(p)

    def walk(self) -> tuple[list[int], int] | None:
        g, step = self.g, self.d.geometry.step
        u = self.start
        if g[u] >= INF:
            return None
        classes: list[int] = []
        total = 0
        while not self.at_goal(u):
            h = u & 3
            best, bk, bc = INF, -1, 0
            for k in range(len(step)):
                c = self.cost(u, k)
                if c < INF:
                    gv = g[u + step[k][h]]
                    if gv < INF and c + gv < best:
                        best, bk, bc = c + gv, k, c
            if bk < 0 or len(classes) > self.goal:
                return None
            classes.append(bk)
            total += bc
            u += step[bk][h]
        return classes, total
