"""The ``lookahead`` strategy, the original work's proposed extension ("replanning windows"):
replace a window of the plan, the faulty action and up to ``window`` actions after it, by the
cheapest sub-plan that reaches the pose at the end of the window, found by A* with the known
faults and at most ``lookahead_expansions`` expansions; fall back to ``replacement``, then
``replan``."""

from __future__ import annotations

from collections.abc import Sequence

from selfrepair.repair.strategies.names import RepairSource, StrategyName
from selfrepair.repair.strategies.protocol import (
    FunctionRepairer,
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    chained,
)
from selfrepair.repair.strategies.registry import register_strategy
from selfrepair.repair.strategies.replacement import replacement
from selfrepair.robots.domain import SomeDomain, run_open
from selfrepair.status import PlanStatus, RepairStatus

__all__ = ["lookahead", "start_lookahead"]


def lookahead(context: MissionContext, request: RepairRequest) -> Repair:
    """Replace a window of the queue by the cheapest sub-plan to the window's end pose.

    The window runs from the front of the queue to ``window`` actions after the first faulty
    action. That faulty action is the first one queued when the executor met it there; with
    ``before > 0`` the executor asks as soon as it is among the next ``before`` actions after the
    front, under the faults known (:attr:`FunctionRepairer.horizon`), so the window also takes in
    the up to ``before`` actions that would have been executed before it. The robot cannot undo
    actions it has executed, so a window can reach back only when the fault is known ahead.

    When no sub-plan is found within ``lookahead_expansions``: :func:`replacement` (which falls
    back to :func:`replan`) for the faulty action at the pose where the robot will meet it, after
    the healthy actions before it.
    """
    domain = context.domain
    queue = request.queue
    faulty = _first_faulty(domain, queue, request.known, context.options.before)
    window = queue[: faulty + context.options.window + 1]
    end = run_open(domain, request.pose, window)
    budget = context.options.lookahead_expansions
    result = context.plan(request.pose, end.cell, end.heading, request.known, budget)
    if result.status is PlanStatus.SOLVED:
        return Repair(
            RepairStatus.REPAIRED,
            RepairSource.LOOKAHEAD,
            result.actions,
            len(window),
            expansions=result.expansions,
            attempts=(StrategyName.LOOKAHEAD,),
        )
    if not faulty:
        fallback = replacement(context, request)
    else:
        prefix = tuple(queue[:faulty])
        at = run_open(domain, request.pose, prefix)
        later = request._replace(pose=at, queue=tuple(queue[faulty:]))
        fallback = replacement(context, later)
        fallback = fallback._replace(
            actions=prefix + fallback.actions, consumed=fallback.consumed + faulty
        )
    return chained(fallback, (StrategyName.LOOKAHEAD,), expansions=result.expansions)


def _first_faulty(
    domain: SomeDomain, queue: Sequence[object], known: frozenset[object], before: int
) -> int:
    """The index of the first queued action unavailable under ``known``, among the first
    ``before + 1`` (0 when none is: the front is then repaired as it is)."""
    for i in range(min(before + 1, len(queue))):
        if not domain.available(queue[i], known):
            return i
    return 0


def start_lookahead(context: MissionContext) -> Repairer:
    """The ``lookahead`` strategy's factory: stateless, looking ``options.before`` actions ahead
    of the front for known faults."""
    return FunctionRepairer(context, lookahead, context.options.before)


register_strategy(StrategyName.LOOKAHEAD, start_lookahead, uses_table=True)
