"""The ``dstar-lite`` strategy: D* Lite (Koenig and Likhachev 2002), the incremental replanner.

The robotics baseline for replacement: instead of planning from scratch after every newly known
fault, D* Lite keeps its search between repairs and repairs only the part of it that the change
touches. Here a newly known fault is an edge-cost change: every edge of a motion class whose
fastest available action changed (or vanished) changes cost, everywhere on the map. (Losing an
action changes edges everywhere, the worst case for incremental search; the ``baselines``
experiment and ``benchmarks/dstar_lite.py`` measure what that costs.)

The search is :class:`selfrepair.search.dstar.DStarLite` (its docstring defines the graph, the
heuristic and the tie-breaking), on the mission's map with the mission's clearance term and
planner backend (``"python"``: the pure-Python reference; ``"numba"``: the compiled kernels, the
same plans; ``"auto"``: numba when it is installed). In a changing world it sees cells: the
cells the robot believes blocked (``MissionContext.belief``) reach the kept search as cell
updates (:meth:`~selfrepair.search.dstar.DStarLite.update_cells`), so D* Lite answers blocked
moves as well as faults, as it is meant to be used.
Only the context is used (the domain, the free grid, the planner settings): this module knows no
maze and no particular robot.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from selfrepair.geometry import Cell, Pose
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
from selfrepair.search.astar import PlanStatus
from selfrepair.search.dstar import DStarLite

__all__ = ["DSTAR_LITE", "DStarLiteRepairer", "start_dstar_lite"]

DSTAR_LITE = StrategyName.DSTAR_LITE
"""The strategy's name in the registry."""


def _search(context: MissionContext, pose: Pose, known: frozenset[object]) -> DStarLite:
    grid = context.grid
    m = grid.margin
    padded = np.frombuffer(grid.data, dtype=np.uint8).reshape(grid.height + 2 * m, grid.stride)
    walls = padded[m : m + grid.height, m : m + grid.width] == 0
    return DStarLite.create(
        context.domain, walls, pose, context.goal, known, goal_heading=context.goal_heading,
        clearance_weight=context.clearance_weight, clearance_radius=context.clearance_radius,
        backend=context.backend,
    )  # fmt: skip


@dataclass(slots=True)
class DStarLiteRepairer:
    """The search of one mission (mutable: it is kept between repairs; ``None`` until the first
    search). ``blocked`` are the cells the search has been told are blocked (the robot's belief,
    ``MissionContext.belief``, at the last repair, without the cell the robot stood on).

    It declares ``sees_cells``: in a changing world the stepper asks it, not a plain replan, to
    repair an action that sweeps a cell believed blocked, and it answers with D* Lite kept
    between changes (the newly believed cells are an :meth:`~DStarLite.update_cells`)."""

    context: MissionContext
    search: DStarLite | None = None
    blocked: frozenset[Cell] = frozenset()
    sees_cells: ClassVar[bool] = True

    def _see(self, search: DStarLite, pose: Pose) -> None:
        believed = self.context.belief.blocked
        if pose.cell in believed:  # the robot stands there: it can drive off (as the stepper)
            believed = believed - {pose.cell}
        if believed != self.blocked:
            search.update_cells(blocked=believed - self.blocked, freed=self.blocked - believed)
            self.blocked = believed

    def repair(self, request: RepairRequest) -> Repair:
        """Plan (incrementally) from the robot's pose with the known faults and blocked cells."""
        search = self.search
        if search is None:
            search = self.search = _search(self.context, request.pose, request.known)
        else:
            search.move_start(request.pose)
            search.update_faults(request.known)
        self._see(search, request.pose)
        found = search.plan(self.context.replan_budget)
        if found.status is PlanStatus.BUDGET_EXHAUSTED:
            status = RepairStatus.BUDGET_EXHAUSTED
        elif found.status is PlanStatus.UNSOLVABLE:
            status = RepairStatus.STUCK
        else:
            status = RepairStatus.REPAIRED
        return Repair(
            status,
            RepairSource.REPLAN,
            found.actions,
            len(request.queue),
            replans=1,
            expansions=found.expansions,
            attempts=(DSTAR_LITE,),
        )


def start_dstar_lite(context: MissionContext) -> Repairer:
    """The strategy factory: a fresh search for one mission.

    When the context names the mission's start, the first search runs here, with no fault known
    (as the executor's initial plan is made), as D* Lite's initial plan would be: each repair is
    then an incremental update of that search, which is what D* Lite is for. Without a start, the
    first repair searches from scratch."""
    repairer = DStarLiteRepairer(context)
    if context.start is not None:
        repairer.search = _search(context, context.start, frozenset())
        repairer._see(repairer.search, context.start)
        repairer.search.plan(context.replan_budget)  # a budget cut: repairs go on from here
    return repairer


register_strategy(DSTAR_LITE, start_dstar_lite)
