"""D* Lite (Koenig and Likhachev 2002) on a robot's pose lattice: the incremental replanner.

The robotics baseline for replacement: instead of planning from scratch after every newly known
fault, D* Lite keeps its search between repairs and repairs only the part of it that the change
touches. Here a newly known fault is an edge-cost change: every edge of a motion class whose
fastest available action changed (or vanished) changes cost, everywhere on the map. (Losing an
action changes edges everywhere, the worst case for incremental search; the ``baselines``
experiment measures what that costs.)

The search runs backwards from the goal over the lattice of poses, with the robot's exact step
costs (duration plus clearance term, scaled to integers by ``MissionContext.cost_scale``) and the
admissible, consistent heuristic ``rate * manhattan`` (``rate`` from
:func:`selfrepair.robots.domain.progress_rate` over all actions, so it stays admissible under any
faults). A goal given as a cell (any heading) is a virtual node reached from each goal pose at cost
0. The plan is read off from the start by following ``argmin(c + g)``, which is optimal once the
start is consistent; a property test checks its cost against A* from scratch after every change.

Nodes are integers, ``4 * cell + heading`` with ``cell`` an index into the mission's
:class:`~selfrepair.geometry.FreeGrid` buffer, and each motion class is a fixed integer offset per
heading (as in the compiled planner), so that the pure-Python search spends its time searching.
Only the context is used (the domain, the free grid, the step cost): this module knows no maze
and no particular robot.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import (
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    RepairSource,
    RepairStatus,
    StrategyName,
    register_strategy,
)
from selfrepair.robots.domain import Domain, primitive_by_motion, progress_rate

__all__ = ["DSTAR_LITE", "DStarLite", "start_dstar_lite"]

DSTAR_LITE = StrategyName.DSTAR_LITE
"""The strategy's name in the registry."""

INF = math.inf
GOAL = -1
"""The virtual goal node."""


@dataclass(frozen=True, slots=True)
class _Lattice:
    """The moves of each motion class as integer offsets on a free-grid buffer.

    ``step[k][h]``: node offset of class ``k`` from heading ``h``; ``cells[k][h]``: its footprint
    as cell offsets; ``back[h]``: for a node facing ``h``, every ``(k, start heading, offset)``
    that arrives there. ``exact`` is false when a footprint reaches beyond the grid's margin (the
    footprint is then tested with the context's free test instead).
    """

    classes: tuple[str, ...]
    members: tuple[Any, ...]
    step: tuple[tuple[int, ...], ...]
    cells: tuple[tuple[tuple[int, ...], ...], ...]
    back: tuple[tuple[tuple[int, int, int], ...], ...]
    exact: bool


def _lattice(domain: Domain[Any, Any], stride: int, margin: int) -> _Lattice:
    members: dict[str, Any] = {}
    for action in domain.actions:
        if any(domain.apply(Pose(0, 0, h), action) != Pose(0, 0, h) for h in Heading):
            members.setdefault(domain.motion_class(action), action)
    classes = tuple(members)
    step, cells, reach = [], [], 0
    back: list[list[tuple[int, int, int]]] = [[] for _ in Heading]
    for k, motion in enumerate(classes):
        per_step, per_cells = [], []
        for heading in Heading:
            start = Pose(0, 0, heading)
            end = domain.apply(start, members[motion])
            offset = 4 * (end.y * stride + end.x) + (end.heading - heading)
            per_step.append(offset)
            footprint = domain.footprint(start, members[motion])
            reach = max(reach, *(max(abs(x), abs(y)) for x, y in footprint))
            per_cells.append(tuple(y * stride + x for x, y in footprint))
            back[end.heading].append((k, int(heading), offset))
        step.append(tuple(per_step))
        cells.append(tuple(per_cells))
    return _Lattice(
        classes,
        tuple(members[m] for m in classes),
        tuple(step),
        tuple(cells),
        tuple(tuple(b) for b in back),
        reach <= margin,
    )


@dataclass(slots=True)
class DStarLite:
    """The search state of one mission (mutable: it is kept between repairs).

    ``chosen[k]`` is the action that does motion class ``k`` under the known faults ``known``
    (``None``: none left); ``start`` is the node the search last planned from. ``expanded``
    counts vertex expansions since the last repair.
    """

    context: MissionContext
    lattice: _Lattice
    rate: float
    goal_cell: int
    known: frozenset[Any] = frozenset()
    chosen: list[Any] = field(default_factory=list)
    start: int | None = None
    km: float = 0.0
    g: dict[int, float] = field(default_factory=dict)
    rhs: dict[int, float] = field(default_factory=dict)
    heap: list[tuple[float, float, int, int]] = field(default_factory=list)
    keys: dict[int, tuple[float, float]] = field(default_factory=dict)
    counter: int = 0
    expanded: int = 0
    costs: dict[tuple[int, int], float] = field(default_factory=dict)

    # --- nodes and poses -----------------------------------------------------------------------

    def node(self, pose: Pose) -> int:
        return 4 * self.context.grid.index(pose.x, pose.y) + int(pose.heading)

    def pose(self, node: int) -> Pose:
        grid = self.context.grid
        y, x = divmod(node >> 2, grid.stride)
        return Pose(x - grid.margin, y - grid.margin, Heading(node & 3))

    def at_goal(self, node: int) -> bool:
        heading = self.context.goal_heading
        return node >> 2 == self.goal_cell and (heading is None or node & 3 == heading)

    # --- the graph -----------------------------------------------------------------------------

    def cost(self, node: int, k: int) -> float:
        """The scaled integer cost of motion class ``k`` from ``node`` (inf when no action of the
        class is left under the known faults, or the footprint is not free)."""
        key = (node, k)
        hit = self.costs.get(key)
        if hit is not None:
            return hit
        action = self.chosen[k]
        ctx = self.context
        if action is None or not self._free(node, k, action):
            hit = INF
        else:
            hit = float(ctx.cost(self.pose(node), action) * ctx.cost_scale)
        self.costs[key] = hit
        return hit

    def _free(self, node: int, k: int, action: Any) -> bool:
        lattice = self.lattice
        if not lattice.exact:
            ctx = self.context
            return ctx.free(ctx.domain.footprint(self.pose(node), action))
        data = self.context.grid.data
        cell = node >> 2
        return all(data[cell + o] for o in lattice.cells[k][node & 3])

    def successors(self, node: int) -> Iterator[tuple[int, float]]:
        step = self.lattice.step
        heading = node & 3
        for k in range(len(step)):
            c = self.cost(node, k)
            if c < INF:
                yield node + step[k][heading], c
        if self.at_goal(node):
            yield GOAL, 0.0

    def predecessors(self, node: int) -> Iterator[tuple[int, float]]:
        if node == GOAL:
            base = 4 * self.goal_cell
            heading = self.context.goal_heading
            for h in (heading,) if heading is not None else tuple(Heading):
                yield base + int(h), 0.0
            return
        for k, _, offset in self.lattice.back[node & 3]:
            before = node - offset
            c = self.cost(before, k)
            if c < INF:
                yield before, c

    # --- D* Lite ------------------------------------------------------------------------------

    def h(self, node: int) -> float:
        if node == GOAL or self.start is None:
            return 0.0
        stride = self.context.grid.stride
        y1, x1 = divmod(node >> 2, stride)
        y2, x2 = divmod(self.start >> 2, stride)
        return self.rate * (abs(x1 - x2) + abs(y1 - y2))

    def key(self, node: int) -> tuple[float, float]:
        best = min(self.g.get(node, INF), self.rhs.get(node, INF))
        return (best + self.h(node) + self.km, best)

    def push(self, node: int) -> None:
        key = self.key(node)
        self.keys[node] = key
        self.counter += 1
        heapq.heappush(self.heap, (key[0], key[1], self.counter, node))

    def update(self, node: int) -> None:
        """Recompute ``rhs(node)`` from its successors, then queue it if inconsistent."""
        if node != GOAL:
            g = self.g
            self.rhs[node] = min((c + g.get(s, INF) for s, c in self.successors(node)), default=INF)
        self.requeue(node)

    def requeue(self, node: int) -> None:
        """Queue ``node`` when it is inconsistent, drop it from the queue when it is not."""
        self.keys.pop(node, None)
        if self.g.get(node, INF) != self.rhs.get(node, INF):
            self.push(node)

    def top(self) -> tuple[tuple[float, float], int] | None:
        """The smallest live heap entry (stale entries are dropped)."""
        while self.heap:
            k1, k2, _, node = self.heap[0]
            if self.keys.get(node) == (k1, k2):
                return (k1, k2), node
            heapq.heappop(self.heap)
        return None

    def compute(self, budget: int | None) -> bool:
        """Run until the start is consistent; False when the budget ran out first."""
        assert self.start is not None
        start = self.start
        while True:
            entry = self.top()
            if entry is None or (
                entry[0] >= self.key(start) and self.rhs.get(start, INF) == self.g.get(start, INF)
            ):
                return True
            if budget is not None and self.expanded >= budget:
                return False
            old_key, node = entry
            heapq.heappop(self.heap)
            del self.keys[node]
            self.expanded += 1
            g, rhs = self.g.get(node, INF), self.rhs.get(node, INF)
            if old_key < self.key(node):
                self.push(node)
            elif g > rhs:  # over-consistent: settle it; its predecessors may now go through it
                self.g[node] = rhs
                for pred, c in self.predecessors(node):
                    if c + rhs < self.rhs.get(pred, INF):
                        self.rhs[pred] = c + rhs
                        self.requeue(pred)
            else:  # under-consistent: forget it; recompute whoever went through it
                self.g[node] = INF
                self.update(node)
                for pred, c in self.predecessors(node):
                    if self.rhs.get(pred, INF) == c + g:
                        self.update(pred)

    def path(self) -> tuple[Any, ...] | None:
        """The actions from the start to the goal following ``argmin(c + g)``."""
        assert self.start is not None
        if self.g.get(self.start, INF) == INF:
            return None
        node = self.start
        actions: list[Any] = []
        step = self.lattice.step
        limit = len(self.g) + 4
        while not self.at_goal(node):
            best: tuple[float, int] | None = None
            heading = node & 3
            for k in range(len(step)):
                c = self.cost(node, k)
                if c < INF:
                    total = c + self.g.get(node + step[k][heading], INF)
                    if best is None or total < best[0]:
                        best = (total, k)
            if best is None or best[0] == INF or len(actions) > limit:
                return None
            actions.append(self.chosen[best[1]])
            node += step[best[1]][heading]
        return tuple(actions)

    # --- the strategy -------------------------------------------------------------------------

    def _choose(self, known: frozenset[Any]) -> set[int]:
        """Take the fastest available action of each class under ``known``; the classes whose
        action changed (their edges changed cost everywhere)."""
        fastest = primitive_by_motion(self.context.domain, known)
        chosen = [fastest.get(m) for m in self.lattice.classes]
        changed = {k for k, a in enumerate(chosen) if not self.chosen or a != self.chosen[k]}
        self.known, self.chosen = known, chosen
        return changed

    def _faults_changed(self, known: frozenset[Any]) -> None:
        """Re-evaluate every vertex the search has touched, and the predecessors of every vertex
        with a finite cost (an impassable edge may have become usable when a transient fault
        cleared)."""
        changed = self._choose(known)
        if not changed:
            return
        self.costs = {key: c for key, c in self.costs.items() if key[1] not in changed}
        touched = {n for n in (*self.g, *self.rhs) if n != GOAL}
        for node in [n for n, g in self.g.items() if g < INF and n != GOAL]:
            touched.update(pred for pred, _ in self.predecessors(node))
        for node in touched:
            self.update(node)

    def begin(self, pose: Pose, known: frozenset[Any]) -> None:
        """Set up the first search, from ``pose`` with the faults ``known`` (:meth:`compute`
        runs it)."""
        self._choose(known)
        self.start = self.node(pose)
        self.rhs[GOAL] = 0.0
        self.push(GOAL)

    def repair(self, request: RepairRequest) -> Repair:
        """Plan (incrementally) from the robot's pose with the known faults."""
        self.expanded = 0
        node = self.node(request.pose)
        if self.start is None:
            self.begin(request.pose, request.known)
        else:
            self.km += self.h(node)
            self.start = node
            if request.known != self.known:
                self._faults_changed(request.known)
        done = self.compute(self.context.replan_budget)
        actions = self.path() if done else None
        if not done:
            status = RepairStatus.BUDGET_EXHAUSTED
        elif actions is None:
            status = RepairStatus.STUCK
        else:
            status = RepairStatus.REPAIRED
        return Repair(
            status,
            RepairSource.REPLAN,
            actions or (),
            len(request.queue),
            replans=1,
            expansions=self.expanded,
            attempts=(DSTAR_LITE,),
        )


def start_dstar_lite(context: MissionContext) -> Repairer:
    """The strategy factory: a fresh search for one mission.

    When the context names the mission's start, the first search runs here, with no fault known
    (as the executor's initial plan is made), as D* Lite's initial plan would be: each repair is
    then an incremental update of that search, which is what D* Lite is for. Without a start, the
    first repair searches from scratch."""
    domain = context.domain
    grid = context.grid
    lattice = _lattice(domain, grid.stride, grid.margin)
    rate = float(progress_rate(domain, domain.actions) * context.cost_scale)
    goal_cell = grid.index(*context.goal)
    search = DStarLite(context, lattice, rate, goal_cell)
    if context.start is not None:
        search.begin(context.start, frozenset())
        search.compute(context.replan_budget)  # if the budget runs out, repairs go on from here
    return search


register_strategy(DSTAR_LITE, start_dstar_lite)
