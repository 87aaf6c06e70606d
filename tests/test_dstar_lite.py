"""D* Lite keeps its search between repairs; after every change its plan costs what A* finds from
scratch (a property test over random mazes, moving starts and fault sets that come and go)."""

from __future__ import annotations

import dataclasses
from fractions import Fraction
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.execution.context import mission_context
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.dstar_lite import start_dstar_lite
from selfrepair.repair.strategies import RepairRequest, RepairStatus, get_strategy, strategy_names
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan, plan_cost
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze

FAULT_TEXTS = ["", "FL:F", "FL:F,RR:B", "FR:F,FR:B", "RL:B", "FL:S,FR:S", "FL:F,FR:F,RL:F,RR:F"]


@st.composite
def scenarios(draw: st.DrawFn) -> tuple[MissionSpec, list[tuple[int, str]]]:
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    h, w = draw(st.integers(3, 8)), draw(st.integers(3, 8))
    walls = rng.random((h, w)) < draw(st.sampled_from([0.0, 0.15, 0.3]))
    free = [(int(x), int(y)) for y, x in zip(*np.nonzero(~walls), strict=True)]
    if len(free) < 2:
        walls[:] = False
        free = [(0, 0), (w - 1, h - 1)]
    start = free[draw(st.integers(0, len(free) - 1))]
    goal = free[draw(st.integers(0, len(free) - 1))]
    heading = draw(st.sampled_from(list(Heading)))
    weight = draw(st.sampled_from([Fraction(0), Fraction(1, 2), Fraction(2)]))
    goal_heading = draw(st.sampled_from([None, None, Heading.S]))
    spec = MissionSpec(
        Maze(walls),
        Pose(*start, heading),
        goal,
        goal_heading=goal_heading,
        strategy="dstar-lite",
        clearance_weight=weight,
    )
    changes = draw(
        st.lists(
            st.tuples(st.integers(0, 3), st.sampled_from(FAULT_TEXTS)), min_size=1, max_size=4
        )
    )
    return spec, changes


def _astar(spec: MissionSpec, pose: Pose, known: frozenset[Any]) -> tuple[PlanStatus, Any]:
    problem = PlanningProblem(
        spec.maze,
        pose,
        spec.goal,
        spec.goal_heading,
        known,
        spec.clearance_weight,
        spec.clearance_radius,
    )
    result = plan(problem, backend="python")
    return result.status, (problem, result.cost)


@settings(max_examples=60, deadline=None)
@given(scenarios())
def test_after_every_change_dstar_lite_costs_what_astar_from_scratch_costs(
    scenario: tuple[MissionSpec, list[tuple[int, str]]],
) -> None:
    spec, changes = scenario
    repairer = start_dstar_lite(mission_context(spec, None))
    pose = spec.start
    for moves, faults in changes:
        known = FOUR_WHEEL.parse_faults(faults)
        repair = repairer.repair(RepairRequest(pose, (), known))
        status, (problem, cost) = _astar(spec, pose, known)
        if status is PlanStatus.SOLVED:
            assert repair.status is RepairStatus.REPAIRED
            assert plan_cost(problem, repair.actions) == cost
            for action in repair.actions[:moves]:  # the robot drives on before the next change
                pose = FOUR_WHEEL.apply(pose, action)
        else:
            assert repair.status is RepairStatus.STUCK and repair.actions == ()


def test_dstar_lite_is_a_registered_strategy_and_runs_missions() -> None:
    assert "dstar-lite" in strategy_names()
    assert get_strategy("dstar-lite") is start_dstar_lite
    maze = load_bundled("wide-short")
    for route in bundled_routes("wide-short"):
        rows = {}
        for strategy in ("replan", "dstar-lite"):
            spec = MissionSpec(
                maze,
                route.start,
                route.goal,
                schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FL:F,RL:F"), at=3),
                strategy=strategy,
            )
            result = run_mission(spec)
            rows[strategy] = (result.status, result.ticks)
        assert rows["dstar-lite"] == rows["replan"]  # both replan optimally


def test_dstar_lite_works_for_another_robot() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(THREE_ACTION.parse_faults("L"), at=2),
        strategy="dstar-lite",
        domain=THREE_ACTION,
    )
    assert run_mission(spec).reached


def test_unreachable_goal_is_stuck_not_a_hang() -> None:
    walls = np.zeros((3, 5), dtype=bool)
    walls[:, 2] = True
    spec = MissionSpec(Maze(walls), Pose(0, 1, Heading.E), (4, 1), strategy="dstar-lite")
    result = run_mission(spec)
    assert result.status == "no_initial_plan"
    repairer = start_dstar_lite(mission_context(spec, None))
    repair = repairer.repair(RepairRequest(spec.start, (), frozenset()))
    assert repair.status is RepairStatus.STUCK


@pytest.mark.parametrize("budget", [1, 5])
def test_a_budget_is_respected(budget: int) -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(
        maze, route.start, route.goal, strategy="dstar-lite", replan_max_expansions=budget
    )
    repairer = start_dstar_lite(mission_context(spec, None))
    repair = repairer.repair(RepairRequest(spec.start, (), frozenset()))
    assert repair.status is RepairStatus.BUDGET_EXHAUSTED and repair.expansions <= budget


def test_the_search_from_the_mission_start_is_kept_for_the_first_repair() -> None:
    """With the mission's start in the context, D* Lite's first search runs when the mission
    starts (no fault known, like the initial plan): a repair that changes nothing then expands
    nothing, where a repairer without the start searches from scratch; both give the same plan."""
    route = bundled_routes("wide-short")[0]
    spec = MissionSpec(load_bundled("wide-short"), route.start, route.goal, strategy="dstar-lite")
    context = mission_context(spec, None)
    assert context.start == spec.start
    request = RepairRequest(spec.start, (), frozenset())
    kept = start_dstar_lite(context).repair(request)
    fresh = start_dstar_lite(dataclasses.replace(context, start=None)).repair(request)
    assert kept.status is fresh.status is RepairStatus.REPAIRED
    assert kept.expansions == 0 < fresh.expansions
    assert kept.actions == fresh.actions
