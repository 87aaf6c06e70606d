"""The changing world of an experiment's mission: obstacles drawn near the route's plan.

An experiment with a ``[world]`` section (:class:`~selfrepair.experiment.schema.WorldConfig`)
gives every situation a world rate and a sensing mode; :func:`mission_world` turns them into the
mission's :class:`~selfrepair.world.events.WorldSchedule` with
:func:`~selfrepair.world.events.random_world`, near the cells of the route's fault-free optimal
plan (clearance weight 0, computed once per maze, route and robot), over ``horizon`` times that
plan's duration, start and goal cells excluded. The generator's seed is the mission's seed, which
derives from the situation and not from the strategy, so every strategy meets the same obstacles
(paired comparisons).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.events import WorldSchedule, random_world
from selfrepair.world.maze import Maze

__all__ = ["mission_world", "route_plan"]


def route_plan(
    maze: Maze, start: Pose, goal: Cell, domain: SomeDomain
) -> tuple[tuple[Cell, ...], float]:
    """The cells of the fault-free optimal plan from ``start`` to ``goal`` (the start cell
    first) and its duration in ticks (no cells but the start when no plan exists); computed
    once per maze, route and robot."""

    def made() -> tuple[tuple[Cell, ...], float]:
        found = plan(PlanningProblem(maze, start, goal, domain=domain))
        cells = tuple(dict.fromkeys([start.cell, *(p.cell for p in found.poses)]))
        return cells, float(found.cost or 0)

    return _PLANS.get((maze, start, goal, domain), made)


_PLANS: BoundedCache[tuple[Maze, Pose, Cell, SomeDomain], tuple[tuple[Cell, ...], float]] = (
    BoundedCache("route plans for world events", 256, kind=CacheKind.REFERENCE, per_map=True)
)


def mission_world(
    world: Mapping[str, Any],
    maze: Maze,
    start: Pose,
    goal: Cell,
    domain: SomeDomain,
    seed: int,
) -> WorldSchedule:
    """The world events of one mission from its canonical ``world`` settings (``rate``,
    ``duration``, ``distance``, ``horizon``, ``sensing``, ``range``) and seed."""
    cells, ticks = route_plan(maze, start, goal, domain)
    return random_world(
        cells,
        maze.free_cells(),
        seed=[seed, 28],
        rate=float(world["rate"]),
        duration=world["duration"],
        distance=int(world["distance"]),
        horizon=max(1, int(world["horizon"] * ticks)),
        exclude=(start.cell, goal),
        sensing=world["sensing"],
        sensing_range=int(world["range"]),
    )
