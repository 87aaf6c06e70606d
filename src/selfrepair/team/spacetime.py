"""Placing a robot's drive in space and time around the other robots' reservations.

Two ways, tried in this order by the engine:

:func:`schedule_path`
    Keep the robot's own plan (from the lattice planner, possibly repaired by its replacement
    table) and only choose when each action starts: as early as possible, waiting on the cell
    it stands on while a footprint is held by another robot. It fails when the robot would have
    to wait on a cell another robot needs, when it would wait longer than ``max_wait``, or when
    the last cell cannot be held afterwards.
:func:`plan_spacetime`
    Cooperative A* (Silver 2005) over ``(pose, time)``: the robot's available actions plus a
    wait of ``wait`` units, each step checked against the reservation table, the goal accepted
    only where the robot can then stay. The heuristic is the exact cost-to-go on the robot's
    pose lattice without other robots (:func:`cost_to_go`, a backward Dijkstra), so it is
    admissible and the search goes straight to the goal unless robots are in the way. The
    lattice of moves is built once per maze and action set (:func:`lattice_of`); cells that
    turned into walls since (blocked cells, stuck robots) are passed as ``extra``.

Both return :class:`~selfrepair.team.reservations.TimedStep` values; a wait is the gap between two
steps. Neither reserves anything: the engine does, after choosing.
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.team.reservations import FOREVER, Reservations, TimedStep
from selfrepair.world.maze import Maze

__all__ = [
    "Lattice",
    "SpaceTimeResult",
    "clear_cost_to_go",
    "cost_to_go",
    "lattice_of",
    "plan_spacetime",
    "schedule_path",
    "units",
]

SpaceTimeResult = tuple[tuple[TimedStep, ...] | None, int]
"""A space-time plan (``None``: none found) and the number of nodes expanded."""


def units(domain: SomeDomain, action: object, scale: int) -> int:
    """The duration of ``action`` in units of ``1 / scale`` ticks."""
    value = Fraction(domain.duration(action)) * scale
    if value.denominator != 1:
        raise ValueError(f"duration of {action} is not a whole number of units at scale {scale}")
    return int(value)


def schedule_path(
    reservations: Reservations,
    robot: str,
    domain: SomeDomain,
    scale: int,
    maze: Maze,
    start: Pose,
    t0: int,
    actions: Sequence[object],
    *,
    max_wait: int,
) -> tuple[TimedStep, ...] | None:
    """The earliest timing of ``actions`` from ``start`` at ``t0`` (see the module docstring)."""
    steps: list[TimedStep] = []
    pose, now = start, t0
    for action in actions:
        after, cells = domain.apply(pose, action), domain.footprint(pose, action)
        if not maze.all_free(cells):
            return None
        length = units(domain, action, scale)
        begin = reservations.clear_after(cells, now, now + length, robot)
        if begin - now > max_wait or begin >= FOREVER:
            return None
        if begin > now and not reservations.free((pose.cell,), now, begin, robot):
            return None
        steps.append(TimedStep(begin, begin + length, action, pose, after, cells))
        pose, now = after, begin + length
    if not reservations.free((pose.cell,), now, FOREVER, robot):
        return None
    return tuple(steps)


def plan_spacetime(
    reservations: Reservations,
    robot: str,
    lattice: Lattice,
    extra: frozenset[Cell],
    start: Pose,
    t0: int,
    goal: Cell,
    *,
    wait: int,
    horizon: int,
    max_expansions: int,
) -> SpaceTimeResult:
    """A fastest collision-free drive from ``start`` at ``t0`` to cell ``goal`` within
    ``horizon`` units, on ``lattice`` without the cells of ``extra`` (see the module
    docstring). Nodes are ``pose id * span + time offset`` integers, for speed."""
    h = cost_to_go(lattice, extra, goal)
    first = lattice.ids.get(start)
    if first is None or h[first] < 0:
        return None, 0
    held = reservations.snapshot(robot, t0)

    def free(cells: tuple[Cell, ...], begin: int, end: int) -> bool:
        for cell in cells:
            for s, e in held.get(cell, ()):
                if s < end and begin < e:
                    return False
        return True

    span = horizon + 1
    goal_ids = (
        {lattice.ids[Pose(goal[0], goal[1], heading)] for heading in Heading}
        if (Pose(goal[0], goal[1], Heading.N) in lattice.ids)
        else set()
    )
    heap: list[tuple[int, int, int]] = [(h[first], h[first], first * span)]
    parent: dict[int, tuple[int, int]] = {}
    closed: set[int] = set()
    expansions = 0
    forward = lattice.edges
    while heap:
        _, _, node = heapq.heappop(heap)
        if node in closed:
            continue
        closed.add(node)
        expansions += 1
        pose_id, dt = divmod(node, span)
        t = t0 + dt
        if pose_id in goal_ids and free((goal,), t, FOREVER):
            return _walk_back(lattice, node, parent, span, t0), expansions
        if expansions >= max_expansions:
            return None, expansions
        cell = lattice.poses[pose_id].cell
        if dt + wait <= horizon and free((cell,), t, t + wait):
            _push(heap, parent, closed, node, pose_id * span + dt + wait, -1, dt + wait, h[pose_id])
        for index, (_, after, cells, length) in enumerate(forward[pose_id]):
            rest = h[after]
            if rest < 0 or dt + length > horizon or not extra.isdisjoint(cells):
                continue
            if free(cells, t, t + length):
                _push(
                    heap, parent, closed, node, after * span + dt + length, index, dt + length, rest
                )
    return None, expansions


def _push(
    heap: list[tuple[int, int, int]],
    parent: dict[int, tuple[int, int]],
    closed: set[int],
    node: int,
    nxt: int,
    edge: int,
    g: int,
    rest: int,
) -> None:
    if nxt in closed or nxt in parent:
        return
    parent[nxt] = (node, edge)
    heapq.heappush(heap, (g + rest, rest, nxt))


def _walk_back(
    lattice: Lattice, node: int, parent: dict[int, tuple[int, int]], span: int, t0: int
) -> tuple[TimedStep, ...]:
    steps: list[TimedStep] = []
    while node in parent:
        before, edge = parent[node]
        if edge >= 0:
            pose_id, dt = divmod(before, span)
            action, after, cells, length = lattice.edges[pose_id][edge]
            t = t0 + dt
            steps.append(
                TimedStep(
                    t, t + length, action, lattice.poses[pose_id], lattice.poses[after], cells
                )
            )
        node = before
    steps.reverse()
    return tuple(steps)


# --- the lattice and the heuristic ----------------------------------------------------------------

_Edge = tuple[object, int, tuple[Cell, ...], int]


@dataclass(frozen=True, slots=True, eq=False)
class Lattice:
    """A robot's moves on a maze's free cells, on pose ids: ``poses[i]`` is pose ``i``,
    ``ids`` the way back, ``edges[i]`` lists ``(action, end pose id, footprint, units)``. The
    same edges as arrays (``sources``, ``targets``, ``lengths``, with ``by_cell[c]`` the
    indices of the edges whose footprint holds cell ``c``) feed the cost-to-go search.
    Built once per maze, domain, action set and scale (:func:`lattice_of`); cells that become
    walls later (blocked cells, stuck robots) are left out per query with ``extra``."""

    maze: Maze
    poses: tuple[Pose, ...]
    ids: dict[Pose, int]
    edges: tuple[tuple[_Edge, ...], ...]
    sources: npt.NDArray[np.int32]
    targets: npt.NDArray[np.int32]
    lengths: npt.NDArray[np.float64]
    by_cell: dict[Cell, npt.NDArray[np.intp]]

    def cost(self, distances: list[int], pose: Pose) -> int | None:
        """The cost-to-go of ``pose`` in ``distances`` (``None``: the goal cannot be reached)."""
        index = self.ids.get(pose)
        if index is None or distances[index] < 0:
            return None
        return distances[index]


def lattice_of(
    maze: Maze, domain: SomeDomain, actions: tuple[object, ...], scale: int
) -> Lattice:
    """The (kept) :class:`Lattice` of ``actions`` on ``maze``."""
    key = (maze, domain, actions, scale)
    return _LATTICES.get(key, lambda: _build_lattice(maze, domain, actions, scale))


_LATTICES: BoundedCache[tuple[Maze, SomeDomain, tuple[object, ...], int], Lattice] = (
    BoundedCache("team lattices", 32, kind=CacheKind.PLAN, per_map=True)
)
_COST_TO_GO: BoundedCache[tuple[Lattice, frozenset[Cell], Cell], list[int]] = BoundedCache(
    "team cost-to-go maps", 512, kind=CacheKind.PLAN, per_map=True
)


def _build_lattice(
    maze: Maze, domain: SomeDomain, actions: tuple[object, ...], scale: int
) -> Lattice:
    grid = maze.free_grid(2)
    moves = [(a, units(domain, a, scale)) for a in actions]
    poses = tuple(Pose(x, y, heading) for x, y in maze.free_cells() for heading in Heading)
    ids = {pose: i for i, pose in enumerate(poses)}
    edges: list[list[_Edge]] = [[] for _ in poses]
    sources: list[int] = []
    targets: list[int] = []
    lengths: list[int] = []
    by_cell: dict[Cell, list[int]] = {}
    for i, pose in enumerate(poses):
        for action, length in moves:
            cells = domain.footprint(pose, action)
            if grid.all_free(cells):
                j = ids[domain.apply(pose, action)]
                edges[i].append((action, j, cells, length))
                for cell in cells:
                    by_cell.setdefault(cell, []).append(len(sources))
                sources.append(i)
                targets.append(j)
                lengths.append(length)
    return Lattice(
        maze,
        poses,
        ids,
        tuple(tuple(e) for e in edges),
        np.asarray(sources, dtype=np.int32),
        np.asarray(targets, dtype=np.int32),
        np.asarray(lengths, dtype=np.float64),
        {c: np.asarray(v, dtype=np.intp) for c, v in by_cell.items()},
    )


def cost_to_go(lattice: Lattice, extra: frozenset[Cell], goal: Cell) -> list[int]:
    """The least duration (units) from every pose id to cell ``goal`` on ``lattice`` without
    the cells of ``extra`` and without other robots; -1 where it cannot be reached (kept).
    One Dijkstra search backwards from the goal's poses (``scipy.sparse.csgraph``)."""
    return _COST_TO_GO.get((lattice, extra, goal), lambda: _dijkstra(lattice, extra, goal))


def clear_cost_to_go() -> None:
    """Forget every kept cost-to-go map (each team mission starts with none, so that what a
    repair costs does not depend on which missions ran before in the process)."""
    _COST_TO_GO.clear()


def _dijkstra(lattice: Lattice, extra: frozenset[Cell], goal: Cell) -> list[int]:
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import dijkstra

    starts = [
        i
        for heading in Heading
        if goal not in extra and (i := lattice.ids.get(Pose(goal[0], goal[1], heading))) is not None
    ]
    size = len(lattice.poses)
    if not starts:
        return [-1] * size
    keep = np.ones(len(lattice.sources), dtype=bool)
    for cell in extra:
        hit = lattice.by_cell.get(cell)
        if hit is not None:
            keep[hit] = False
    # backwards: an edge i -> j of the lattice is j -> i here
    graph = csr_matrix(
        (lattice.lengths[keep], (lattice.targets[keep], lattice.sources[keep])), shape=(size, size)
    )
    found = dijkstra(graph, directed=True, indices=starts, min_only=True)
    return [int(d) if np.isfinite(d) else -1 for d in found]
