"""The ``replan`` strategy, the original baseline: plan from scratch from the current pose with
the known faults. Every other robot strategy falls back to it."""

from __future__ import annotations

from selfrepair.repair.strategies.names import RepairSource, StrategyName
from selfrepair.repair.strategies.protocol import (
    MissionContext,
    Repair,
    RepairRequest,
    stateless,
)
from selfrepair.repair.strategies.registry import register_strategy
from selfrepair.status import REPAIR_OF_PLAN

__all__ = ["replan"]


def replan(context: MissionContext, request: RepairRequest) -> Repair:
    """Plan from scratch from the current pose with the known faults."""
    result = context.plan(
        request.pose, context.goal, context.goal_heading, request.known, context.replan_budget
    )
    return Repair(
        REPAIR_OF_PLAN[result.status],
        RepairSource.REPLAN,
        result.actions,
        len(request.queue),
        replans=1,
        expansions=result.expansions,
        attempts=(StrategyName.REPLAN,),
    )


register_strategy(StrategyName.REPLAN, stateless(replan))
