"""The robot's own motion, looked up instead of recomputed: a speed-up for the simulator's hot loop.

The domain contract (:func:`selfrepair.robots.domain.check_domain`, run when a domain is
registered) says that ``apply`` and ``footprint`` commute with translation: an action does the
same thing in every cell. So the effect of every action from every heading, computed once by the
domain's own :meth:`~selfrepair.robots.domain.Domain.step` at the origin, gives its effect anywhere
by a shift. :func:`tabulated` returns the domain with ``apply``, ``footprint`` and ``duration``
answered that way, and ``available`` answered from the set of actions the domain's own
``available`` allows under each fault set met (kept in a bounded cache). Nothing about the motion
or the faults is re-derived, and ``tests/test_envs.py`` checks that the answers are identical to
the domain's on every action, heading, some shifted cells and every fault set in scope.

The environment gives the tabulated copy to its :class:`~selfrepair.execution.simulator.Simulator`
only; everything that compares domains by identity (tables, mission specs) keeps the original.
"""

from __future__ import annotations

import dataclasses
from fractions import Fraction
from typing import Any

from selfrepair.caching import BoundedCache
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import Domain

__all__ = ["tabulated"]

_Move = tuple[int, int, Heading, tuple[Cell, ...]]

_TABULATED: BoundedCache[Domain[Any, Any], Domain[Any, Any]] = BoundedCache(
    "tabulated domains", 8
)
_AVAILABLE: BoundedCache[tuple[Domain[Any, Any], frozenset[Any]], frozenset[Any]] = BoundedCache(
    "available actions per fault set", 1024
)


def tabulated(domain: Domain[Any, Any]) -> Domain[Any, Any]:
    """``domain`` with its motion looked up per (heading, action) (see the module docstring);
    made once per domain (a few are kept)."""
    return _TABULATED.get(domain, lambda: _tabulate(domain))


def _tabulate(domain: Domain[Any, Any]) -> Domain[Any, Any]:
    moves: dict[tuple[Heading, Any], _Move] = {}
    for heading in Heading:
        origin = Pose(0, 0, heading)
        for action in domain.actions:
            end, cells, _ = domain.step(origin, action)
            moves[(heading, action)] = (end.x, end.y, end.heading, tuple(cells))
    durations: dict[Any, Fraction] = {a: domain.duration(a) for a in domain.actions}

    def apply(pose: Pose, action: Any) -> Pose:
        dx, dy, heading, _ = moves[(pose.heading, action)]
        return Pose(pose.x + dx, pose.y + dy, heading)

    def footprint(pose: Pose, action: Any) -> tuple[Cell, ...]:
        x, y = pose.x, pose.y
        return tuple([(x + cx, y + cy) for cx, cy in moves[(pose.heading, action)][3]])

    def allowed(faults: frozenset[Any]) -> frozenset[Any]:
        return frozenset(a for a in domain.actions if domain.available(a, faults))

    def available(action: Any, faults: frozenset[Any]) -> bool:
        return action in _AVAILABLE.get((domain, faults), lambda: allowed(faults))

    return dataclasses.replace(
        domain,
        apply=apply,
        footprint=footprint,
        duration=durations.__getitem__,
        available=available,
    )
