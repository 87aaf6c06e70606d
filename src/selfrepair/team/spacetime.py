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
from typing import Any

from selfrepair.caching import BoundedCache
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import Domain
from selfrepair.team.reservations import FOREVER, Reservations, TimedStep
from selfrepair.world.maze import Maze

__all__ = [
    "Lattice",
    "SpaceTimeResult",
    "cost_to_go",
    "lattice_of",
    "plan_spacetime",
    "schedule_path",
    "units",
]

SpaceTimeResult = tuple[tuple[TimedStep, ...] | None, int]
"""A space-time plan (``None``: none found) and the number of nodes expanded."""


def units(domain: Domain[Any, Any], action: Any, scale: int) -> int:
    """The duration of ``action`` in units of ``1 / scale`` ticks."""
    value = Fraction(domain.duration(action)) * scale
    if value.denominator != 1:
        raise ValueError(f"duration of {action} is not a whole number of units at scale {scale}")
    return int(value)


def schedule_path(
    reservations: Reservations,
    robot: str,
    domain: Domain[Any, Any],
    scale: int,
    maze: Maze,
    start: Pose,
    t0: int,
    actions: Sequence[Any],
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
    docstring)."""
    h = cost_to_go(lattice, extra, goal)
    if start not in h:
        return None, 0
    limit = t0 + horizon
    heap: list[tuple[int, int, int, Pose, int]] = [(h[start], h[start], 0, start, t0)]
    parent: dict[tuple[Pose, int], tuple[tuple[Pose, int], TimedStep | None]] = {}
    closed: set[tuple[Pose, int]] = set()
    counter = expansions = 0
    while heap:
        _, _, _, pose, t = heapq.heappop(heap)
        node = (pose, t)
        if node in closed:
            continue
        closed.add(node)
        expansions += 1
        if pose.cell == goal and reservations.free((goal,), t, FOREVER, robot):
            return _walk_back(node, parent), expansions
        if expansions >= max_expansions:
            return None, expansions
        successors: list[tuple[Pose, int, TimedStep | None]] = []
        if t + wait <= limit and reservations.free((pose.cell,), t, t + wait, robot):
            successors.append((pose, t + wait, None))
        for action, after, cells, length in lattice.forward.get(pose, ()):
            if after not in h or t + length > limit or not extra.isdisjoint(cells):
                continue
            if reservations.free(cells, t, t + length, robot):
                successors.append(
                    (after, t + length, TimedStep(t, t + length, action, pose, after, cells))
                )
        for after, t_next, step in successors:
            key = (after, t_next)
            if key in closed or key in parent:
                continue
            parent[key] = (node, step)
            counter += 1
            rest = h[after]
            heapq.heappush(heap, (t_next - t0 + rest, rest, counter, after, t_next))
    return None, expansions


def _walk_back(
    node: tuple[Pose, int],
    parent: dict[tuple[Pose, int], tuple[tuple[Pose, int], TimedStep | None]],
) -> tuple[TimedStep, ...]:
    steps: list[TimedStep] = []
    while node in parent:
        node, step = parent[node]
        if step is not None:
            steps.append(step)
    steps.reverse()
    return tuple(steps)


# --- the lattice and the heuristic ----------------------------------------------------------------

_Edge = tuple[Any, Pose, tuple[Cell, ...], int]


@dataclass(frozen=True, slots=True, eq=False)
class Lattice:
    """A robot's moves on a maze's free cells, both ways: ``forward[pose]`` lists
    ``(action, end pose, footprint, units)``, ``reverse[pose]`` the same edges by end pose.
    Built once per maze, domain, action set and scale (:func:`lattice_of`); cells that become
    walls later (blocked cells, stuck robots) are left out per query with ``extra``."""

    maze: Maze
    forward: dict[Pose, list[_Edge]]
    reverse: dict[Pose, list[_Edge]]


def lattice_of(
    maze: Maze, domain: Domain[Any, Any], actions: tuple[Any, ...], scale: int
) -> Lattice:
    """The (kept) :class:`Lattice` of ``actions`` on ``maze``."""
    key = (maze, domain, actions, scale)
    return _LATTICES.get(key, lambda: _build_lattice(maze, domain, actions, scale))


_LATTICES: BoundedCache[tuple[Maze, Domain[Any, Any], tuple[Any, ...], int], Lattice] = (
    BoundedCache("team lattices", 32)
)
_COST_TO_GO: BoundedCache[tuple[Lattice, frozenset[Cell], Cell], dict[Pose, int]] = BoundedCache(
    "team cost-to-go maps", 512
)


def _build_lattice(
    maze: Maze, domain: Domain[Any, Any], actions: tuple[Any, ...], scale: int
) -> Lattice:
    grid = maze.free_grid(2)
    moves = [(a, units(domain, a, scale)) for a in actions]
    forward: dict[Pose, list[_Edge]] = {}
    reverse: dict[Pose, list[_Edge]] = {}
    for x, y in maze.free_cells():
        for heading in Heading:
            pose = Pose(x, y, heading)
            for action, length in moves:
                cells = domain.footprint(pose, action)
                if grid.all_free(cells):
                    after = domain.apply(pose, action)
                    forward.setdefault(pose, []).append((action, after, cells, length))
                    reverse.setdefault(after, []).append((action, pose, cells, length))
    return Lattice(maze, forward, reverse)


def cost_to_go(lattice: Lattice, extra: frozenset[Cell], goal: Cell) -> dict[Pose, int]:
    """The least duration (units) from every pose to cell ``goal`` on ``lattice`` without the
    cells of ``extra`` and without other robots; poses that cannot reach it are absent (kept)."""
    return _COST_TO_GO.get((lattice, extra, goal), lambda: _dijkstra(lattice, extra, goal))


def _dijkstra(lattice: Lattice, extra: frozenset[Cell], goal: Cell) -> dict[Pose, int]:
    dist: dict[Pose, int] = {}
    heap: list[tuple[int, int, Pose]] = []
    if lattice.maze.is_free(*goal) and goal not in extra:
        for heading in Heading:
            pose = Pose(goal[0], goal[1], heading)
            dist[pose] = 0
            heap.append((0, heading, pose))
    heapq.heapify(heap)
    while heap:
        d, _, pose = heapq.heappop(heap)
        if d > dist.get(pose, FOREVER):
            continue
        for _, before, cells, length in lattice.reverse.get(pose, ()):
            nd = d + length
            if nd < dist.get(before, FOREVER) and extra.isdisjoint(cells):
                dist[before] = nd
                heapq.heappush(heap, (nd, before.heading, before))
    return dist
