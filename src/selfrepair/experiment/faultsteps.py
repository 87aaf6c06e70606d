"""Faults that appear at a random step: the step is drawn from the route's own optimal plan.

A plan cannot dodge a fault that is present from the first step by being tolerant of it (the
fault is known before the plan is made), so experiments on plan tolerance make faults appear
during the mission. :func:`random_fault_step` draws the step once per situation (maze, route,
fault set), seeded, so that every strategy and planning objective meets the fault at the same
step and comparisons stay paired.
"""

from __future__ import annotations

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.maze import Maze
from selfrepair.world.routes import Route

__all__ = ["optimum_steps", "random_fault_step"]


def optimum_steps(maze: Maze, route: Route, domain: SomeDomain) -> int:
    """The steps of the fault-free optimal plan of ``route`` (clearance weight 0; 0 when no plan
    exists), computed once per maze, route and robot."""

    def steps() -> int:
        found = plan(PlanningProblem(maze, route.start, route.goal, domain=domain))
        return len(found.actions)

    return _STEPS.get((maze, route, domain), steps)


_STEPS: BoundedCache[tuple[Maze, Route, SomeDomain], int] = BoundedCache(
    "optimal plan steps per route", 256, kind=CacheKind.REFERENCE, per_map=True
)


def random_fault_step(maze: Maze, route: Route, domain: SomeDomain, seed: int) -> int:
    """A step drawn uniformly from ``0 .. n - 1`` for the ``n`` steps of the route's optimal
    plan (0 for an empty plan), by ``numpy.random.default_rng(seed)``."""
    steps = optimum_steps(maze, route, domain)
    return int(np.random.default_rng(seed).integers(0, max(1, steps)))
