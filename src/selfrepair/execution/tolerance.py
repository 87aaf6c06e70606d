"""Plan tolerance for a mission: :func:`selfrepair.repair.tolerance.plan_tolerance` on the
mission's own context (its map, table, recursion mode and rewriting), for its initial plan or a
given one."""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction

from selfrepair.errors import ProblemError
from selfrepair.execution.context import mission_context
from selfrepair.execution.result import MissionSpec
from selfrepair.repair.strategies import StrategyName
from selfrepair.repair.tolerance import FaultModel, PlanTolerance, plan_tolerance
from selfrepair.search.astar import PlanResult, PlanStatus

__all__ = ["actions_tolerance", "mission_tolerance"]


def mission_tolerance(
    spec: MissionSpec, model: FaultModel, initial: PlanResult | None = None
) -> tuple[PlanResult, PlanTolerance | None]:
    """The plan (``initial``, else the mission's initial plan, made with no fault known) and its
    tolerance under ``model`` for the ``replacement`` strategy with ``spec.options`` (``None``
    when there is no plan). Raises :class:`ProblemError` when the mission's strategy is not
    ``replacement`` or its table is for another robot."""
    if spec.strategy != StrategyName.REPLACEMENT:
        raise ProblemError(
            f"plan tolerance is defined for the replacement strategy, not {spec.strategy!r}"
        )
    table = spec.options.resolved_table()
    if table.domain is not spec.domain:
        raise ProblemError(
            f"table {spec.options.table_label!r} is for the {table.domain.name!r} domain; "
            f"this mission's robot is {spec.domain.name!r}"
        )
    context = mission_context(spec, table)
    if initial is None:
        initial = context.plan(spec.start, spec.goal, spec.goal_heading, frozenset(), None)
    if initial.status is not PlanStatus.SOLVED:
        return initial, None
    return initial, plan_tolerance(context, initial.poses, initial.actions, model)


def actions_tolerance(
    spec: MissionSpec, model: FaultModel, actions: Sequence[object]
) -> PlanTolerance:
    """The tolerance under ``model`` of the plan ``actions`` from ``spec.start`` (say, the
    initial plan a trace records), for the mission's ``replacement`` strategy; raises as
    :func:`mission_tolerance` does."""
    poses = [spec.start]
    for action in actions:
        poses.append(spec.domain.apply(poses[-1], action))
    found = PlanResult(PlanStatus.SOLVED, tuple(actions), tuple(poses), None, Fraction(0), 0, 0)
    _, tolerance = mission_tolerance(spec, model, found)
    assert tolerance is not None  # a solved plan always has one
    return tolerance
