"""A small generic A* core: binary heap, deterministic tie-breaking, node and time budgets.

The pure-Python planners (:mod:`selfrepair.search.lattice` on the robot lattice,
:mod:`selfrepair.search.grid` on plain grids) both run on :func:`astar`; the numba kernels in
:mod:`selfrepair.search._kernels` implement the same loop with the same keys, so both backends
pop nodes in the same order.

Heap entries are ``(f, h, counter, node)``: lowest ``f = g + h`` first, among equal ``f`` the node
nearer the goal (lowest ``h``), and among those the one pushed first (``counter``; networkx's
``astar_path`` breaks ties on the counter alone). The counter is unique, so nodes themselves are
never compared. A node is pushed again when its ``g`` improves (lazy deletion: stale entries are
skipped when popped).

The heuristic must be consistent (``h(n) <= cost(n, m) + h(m)`` and ``h(goal) = 0``). Then a node is
never improved after it is expanded, so closed nodes are never reopened and the first goal popped is
optimal. A heuristic value of ``None`` marks a node from which the goal cannot be reached; such
nodes are never pushed.
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable, Hashable, Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Generic, TypeVar

from selfrepair.geometry import Pose
from selfrepair.status import PlanStatus

__all__ = [
    "BACKENDS",
    "MAX_TIME_LIMIT",
    "PlanResult",
    "PlanStatus",
    "SearchOutcome",
    "astar",
    "deadline_from",
]

N = TypeVar("N", bound=Hashable)
L = TypeVar("L")

BACKENDS = ("auto", "python", "numba")
"""``"python"``: the reference; ``"numba"``: the compiled kernels; ``"auto"``: numba if present."""

MAX_TIME_LIMIT = 1e9
"""The largest time limit in seconds (about 32 years); NaN and infinity are refused."""

_TIME_CHECK_EVERY = 256
"""Expansions between two looks at the clock (the clock costs more than an expansion)."""


@dataclass(frozen=True, slots=True)
class SearchOutcome(Generic[N, L]):
    """The result of :func:`astar`.

    ``path`` lists the nodes from start to goal and ``labels`` the edge labels between them
    (``len(labels) == len(path) - 1``); both are empty unless solved. ``cost`` is the path cost in
    the caller's cost type, ``None`` unless solved. ``expansions`` counts closed nodes, the goal
    included.
    """

    status: PlanStatus
    path: tuple[N, ...]
    labels: tuple[L, ...]
    cost: int | float | None
    expansions: int


def deadline_from(time_limit: float | None, start_ns: int) -> int | None:
    """The ``time.perf_counter_ns`` value at which a search started at ``start_ns`` must stop."""
    return None if time_limit is None else start_ns + int(time_limit * 1e9)


def astar(
    start: N,
    *,
    successors: Callable[[N], Iterable[tuple[N, int | float, L]]],
    heuristic: Callable[[N], int | float | None],
    is_goal: Callable[[N], bool],
    max_expansions: int | None = None,
    deadline_ns: int | None = None,
) -> SearchOutcome[N, L]:
    """A* from ``start`` to the first node satisfying ``is_goal``.

    ``successors(n)`` yields ``(m, edge_cost, label)`` with non-negative costs. Costs may be ints
    (exact) or floats; the caller chooses. ``max_expansions`` bounds the number of closed nodes and
    ``deadline_ns`` (a ``time.perf_counter_ns`` value) the wall time; hitting either gives
    :attr:`PlanStatus.BUDGET_EXHAUSTED`, an exhausted open list :attr:`PlanStatus.UNSOLVABLE`.
    """
    h0 = heuristic(start)
    if h0 is None:
        return SearchOutcome(PlanStatus.UNSOLVABLE, (), (), None, 0)
    g: dict[N, int | float] = {start: 0}
    parent: dict[N, tuple[N, L]] = {}
    closed: set[N] = set()
    counter = 0
    heap: list[tuple[int | float, int | float, int, N]] = [(h0, h0, counter, start)]
    expansions = 0
    while heap:
        _, _, _, node = heapq.heappop(heap)
        if node in closed:
            continue
        if max_expansions is not None and expansions >= max_expansions:
            return SearchOutcome(PlanStatus.BUDGET_EXHAUSTED, (), (), None, expansions)
        if (
            deadline_ns is not None
            and expansions % _TIME_CHECK_EVERY == 0
            and time.perf_counter_ns() >= deadline_ns
        ):
            return SearchOutcome(PlanStatus.BUDGET_EXHAUSTED, (), (), None, expansions)
        closed.add(node)
        expansions += 1
        if is_goal(node):
            path, labels = _walk_back(node, parent)
            return SearchOutcome(PlanStatus.SOLVED, path, labels, g[node], expansions)
        g_node = g[node]
        for succ, cost, label in successors(node):
            if succ in closed:
                continue
            g_new = g_node + cost
            old = g.get(succ)
            if old is not None and g_new >= old:
                continue
            h = heuristic(succ)
            if h is None:
                continue
            g[succ] = g_new
            parent[succ] = (node, label)
            counter += 1
            heapq.heappush(heap, (g_new + h, h, counter, succ))
    return SearchOutcome(PlanStatus.UNSOLVABLE, (), (), None, expansions)


def _walk_back(goal: N, parent: dict[N, tuple[N, L]]) -> tuple[tuple[N, ...], tuple[L, ...]]:
    nodes = [goal]
    labels: list[L] = []
    while nodes[-1] in parent:
        prev, label = parent[nodes[-1]]
        nodes.append(prev)
        labels.append(label)
    nodes.reverse()
    labels.reverse()
    return tuple(nodes), tuple(labels)


@dataclass(frozen=True, slots=True)
class PlanResult:
    """The outcome of :func:`plan`.

    ``actions`` are the domain's actions (the fastest available one of each motion class), ``poses``
    the ``len(actions) + 1`` poses from start to goal; both are empty unless solved. ``cost`` is
    duration plus clearance term (``None`` unless solved), ``duration`` the total ticks (0 unless
    solved). ``expansions`` counts closed nodes; ``wall_time_ns`` is the wall time of the call
    without ``kernel_load_ns``, the time this call spent importing and loading (or compiling) the
    compiled kernels, which only the first call of a process pays.
    """

    status: PlanStatus
    actions: tuple[Any, ...]
    poses: tuple[Pose, ...]
    cost: Fraction | None
    duration: Fraction
    expansions: int
    wall_time_ns: int
    kernel_load_ns: int = 0
