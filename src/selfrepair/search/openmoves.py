"""A domain's actions on an open plane, by action index and heading: what each does from the
origin, derived once per domain from ``Domain.apply`` and ``Domain.footprint``.

Several readers need this table in the same mission: the planner's kernel check
(:func:`selfrepair.search.backend.kernel_refusal`), its motion table and set-up
(:mod:`selfrepair.search.lattice`, :mod:`selfrepair.search._kernels`) and the replacement
look-ups' action index (:func:`selfrepair.repair.neighbourhood.action_index`). Each used to ask
the domain for the same 4 x ``len(actions)`` moves itself; now one derivation serves them all.
It depends on the domain alone (not on the maze, the faults or the goal), and every mission
derives it before its clocks start (:func:`selfrepair.execution.executor.run_mission` asks for it
in its preparation, as it loads the compiled planner there), so it is
:attr:`~selfrepair.caching.CacheKind.PREFILLED` data: a cold run keeps it, as it keeps the
simulator's move tables derived from the same ``apply`` and ``footprint``. Before, a cold run
emptied it and every cold run derived it again, outside every clock.
"""

from __future__ import annotations

from dataclasses import dataclass

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import SomeDomain

__all__ = ["OpenMoves", "open_moves"]

Move = tuple[int, int, int]
"""An end pose relative to the start cell: ``(dx, dy, heading)``."""


@dataclass(frozen=True, slots=True, eq=False)
class OpenMoves:
    """``ends[i][h]`` is ``(dx, dy, heading)``, the end of action ``i`` of ``domain.actions``
    started at the origin facing ``h``; ``footprints[i][h]`` its footprint there (the start cell
    first); ``ids`` maps ``id(action)`` of the domain's own action objects to their index."""

    domain: SomeDomain
    ends: tuple[tuple[Move, ...], ...]
    footprints: tuple[tuple[tuple[Cell, ...], ...], ...]
    ids: dict[int, int]

    def index(self, action: object) -> int:
        """The index of ``action`` (one of the domain's own objects, else found by equality)."""
        found = self.ids.get(id(action))
        return self.domain.actions.index(action) if found is None else found

    def stays(self, i: int) -> bool:
        """Whether action ``i`` keeps every pose (the planner leaves such actions out)."""
        return all(end == (0, 0, h) for h, end in enumerate(self.ends[i]))


_STARTS = tuple(Pose(0, 0, heading) for heading in Heading)


def _open_moves(domain: SomeDomain) -> OpenMoves:
    apply, footprint = domain.apply, domain.footprint
    ends = []
    footprints = []
    for action in domain.actions:
        per = [apply(start, action) for start in _STARTS]
        ends.append(tuple((end.x, end.y, int(end.heading)) for end in per))
        footprints.append(tuple(footprint(start, action) for start in _STARTS))
    ids = {id(a): i for i, a in enumerate(domain.actions)}
    return OpenMoves(domain, tuple(ends), tuple(footprints), ids)


_OPEN: BoundedCache[SomeDomain, OpenMoves] = BoundedCache(
    "open-plane moves", 16, kind=CacheKind.PREFILLED
)


def open_moves(domain: SomeDomain) -> OpenMoves:
    """The :class:`OpenMoves` of ``domain`` (derived once per domain; a cold run keeps it)."""
    return _OPEN.get(domain, lambda: _open_moves(domain))
