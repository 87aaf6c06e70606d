"""The executor and its strategies: properties over random small mazes, routes and faults."""

from __future__ import annotations

import os
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.metrics import (
    ROW_COLUMNS,
    executed_cost,
    latency_stats,
    mission_row,
    plan_distance,
)
from selfrepair.execution.result import MissionResult, MissionSpec, MissionStatus
from selfrepair.execution.trace import parse_trace, replay, trace_lines
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import StrategyName, StrategyOptions
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze

STRATEGIES = (StrategyName.REPLAN, StrategyName.REPLACEMENT, StrategyName.LOOKAHEAD)
"""The strategies every mission test runs (the baselines have their own tests)."""

FAULT_SETS = (frozenset(), *FOUR_WHEEL.fault_sets)
PROPERTY = settings(
    max_examples=int(os.environ.get("SELFREPAIR_EXAMPLES", "40")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)


@st.composite
def routes(draw: st.DrawFn) -> tuple[Maze, Pose, tuple[int, int]]:
    """A random small maze with a start pose and a distinct goal cell, both free."""
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    width, height = draw(st.integers(3, 8)), draw(st.integers(3, 8))
    walls = rng.random((height, width)) < draw(st.sampled_from([0.0, 0.15, 0.3]))
    free = [(x, y) for y in range(height) for x in range(width) if not walls[y, x]]
    if len(free) < 2:
        walls[0, 0] = walls[-1, -1] = False
        free = [(0, 0), (width - 1, height - 1)]
    i, j = rng.choice(len(free), size=2, replace=False)
    start = Pose(*free[int(i)], draw(st.sampled_from(list(Heading))))
    return Maze(walls, name="random"), start, free[int(j)]


def _spec(
    route,
    faults,
    strategy: str,
    *,
    recursion: str = "flat",
    detection: str = "now",
    events: tuple[FaultEvent, ...] | None = None,
    seed: int = 0,
) -> MissionSpec:
    maze, start, goal = route
    schedule = (
        FaultSchedule(events, detection)
        if events is not None
        else FaultSchedule.permanent(faults, detection=detection)
    )
    return MissionSpec(
        maze,
        start,
        goal,
        schedule=schedule,
        strategy=strategy,
        options=StrategyOptions(recursion=recursion, window=2),
        seed=seed,
        backend="python",
    )


def _check_mission(result: MissionResult) -> None:
    """The invariants every mission must keep, whatever happened."""
    spec = result.spec
    assert result.status in set(MissionStatus) and result.status != "collision"
    if result.reached:
        assert result.final_pose.cell == spec.goal
    else:
        assert result.reason
    for step in result.steps:
        if step.source == "failed-attempt":
            assert step.start == step.end
            continue
        assert four_wheel.available(step.action, step.known), "used a known-faulty action"
        end, swept, duration = four_wheel.step(step.start, step.action)
        assert spec.maze.all_free(swept), "swept a wall"
        assert (end, duration) == (step.end, step.duration)
    report = replay(parse_trace("\n".join(trace_lines(result))))
    assert report.ok, str(report)
    row = mission_row(result)
    assert list(row) == list(ROW_COLUMNS)
    assert all(v is None or isinstance(v, int | float | str) for v in row.values())


@PROPERTY
@given(
    routes(),
    st.sampled_from(FAULT_SETS),
    st.sampled_from(list(STRATEGIES)),
    st.sampled_from(list(RecursionMode)),
    st.sampled_from(["now", "on-use"]),
)
def test_every_mission_reaches_the_goal_or_says_why(
    route, faults, strategy, recursion, detection
) -> None:  # type: ignore[no-untyped-def]
    result = run_mission(_spec(route, faults, strategy, recursion=recursion, detection=detection))
    _check_mission(result)
    maze, start, goal = route
    healthy = plan(PlanningProblem(maze, start, goal), backend="python")
    if healthy.status is PlanStatus.UNSOLVABLE:
        assert result.status == "no_initial_plan"
    with_faults = plan(PlanningProblem(maze, start, goal, faults=faults), backend="python")
    if with_faults.status is PlanStatus.SOLVED and result.status != "reached":
        # Only possible when the robot moved into a place it cannot leave with the faults.
        assert result.status == "stuck" and result.steps


@PROPERTY
@given(
    routes(),
    st.sampled_from(FAULT_SETS),
    st.sampled_from(list(STRATEGIES)),
    st.integers(0, 6),
    st.sampled_from(["permanent", "transient", "intermittent"]),
    st.sampled_from(["now", "on-use"]),
    st.integers(0, 100),
)
def test_timed_and_flaky_faults_keep_the_invariants(
    route, faults, strategy, at, persistence, detection, seed
) -> None:  # type: ignore[no-untyped-def]
    events = tuple(
        FaultEvent(
            f,
            at=at,
            persistence=persistence,
            duration=3 if persistence == "transient" else None,
            probability=0.5 if persistence == "intermittent" else None,
        )
        for f in sorted(faults)
    )
    spec = _spec(route, faults, strategy, detection=detection, events=events, seed=seed)
    _check_mission(run_mission(spec))


@PROPERTY
@given(routes(), st.sampled_from(list(STRATEGIES)))
def test_without_faults_every_strategy_executes_the_initial_plan(route, strategy) -> None:  # type: ignore[no-untyped-def]
    result = run_mission(_spec(route, frozenset(), strategy))
    if result.status == "no_initial_plan":
        return
    assert result.reached
    assert tuple(s.action for s in result.steps) == result.initial_plan.actions
    assert all(s.source == "plan" for s in result.steps) and not result.repairs
    assert mission_row(result)["plan_distance"] == 0
    assert result.ticks == result.initial_plan.duration


@PROPERTY
@given(routes(), st.sampled_from(FAULT_SETS), st.sampled_from(list(RecursionMode)))
def test_replacement_never_replans_more_than_replan(route, faults, recursion) -> None:  # type: ignore[no-untyped-def]
    by_replan = mission_row(run_mission(_spec(route, faults, "replan")))
    by_table = mission_row(run_mission(_spec(route, faults, "replacement", recursion=recursion)))
    assert by_table["replans"] <= by_replan["replans"] <= 1
    assert by_table["plan_length_before"] == by_replan["plan_length_before"]


def test_bundled_mission_with_two_faults() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    faults = four_wheel.parse_faults("FL:F,RR:B")
    results = {
        s: run_mission(
            MissionSpec(
                maze, route.start, route.goal, schedule=FaultSchedule.permanent(faults), strategy=s
            )
        )
        for s in STRATEGIES
    }
    for result in results.values():
        _check_mission(result)
        assert result.reached
    assert mission_row(results["replan"])["replans"] == 1
    table_row = mission_row(results["replacement"])
    assert table_row["replacements"] > 0 and table_row["replans"] == 0
    assert table_row["faulty_encounters"] == table_row["replacements"]
    assert mission_row(results["lookahead"])["lookaheads"] > 0
    # The faults are known from step 0, so every executed action is healthy, and only the
    # initial plan's faulty actions were replaced.
    steps = results["replacement"].steps
    assert all(four_wheel.available(s.action, faults) for s in steps)
    faulty_in_plan = sum(
        not four_wheel.available(a, faults) for a in results["replacement"].initial_plan.actions
    )
    assert table_row["replacements"] == faulty_in_plan


def test_on_use_detection_records_failed_attempts() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(four_wheel.parse_faults("FL:F"), detection="on-use"),
        strategy="replacement",
    )
    result = run_mission(spec)
    _check_mission(result)
    failed = [s for s in result.steps if s.source == "failed-attempt"]
    assert len(failed) == 1 and failed[0].duration == 1
    assert result.steps[failed[0].step + 1].known == four_wheel.parse_faults("FL:F")
    assert mission_row(result)["failed_attempts"] == 1


def test_stuck_when_no_plan_exists_with_the_faults() -> None:
    # With both left wheels stuck at S the left side never drives, so the robot can only turn.
    maze = Maze(np.array([[True, False, True], [True, False, True], [True, False, True]]))
    faults = four_wheel.parse_faults("FL:F,RL:F,FL:B,RL:B")
    spec = MissionSpec(
        maze,
        Pose(1, 2, Heading.N),
        (1, 0),
        schedule=FaultSchedule.permanent(faults),
        strategy="replacement",
        options=StrategyOptions(recursion="guarded"),
        backend="python",
    )
    result = run_mission(spec)
    _check_mission(result)
    assert result.status == "stuck" and "replacement then replan" in result.reason


def test_unknown_strategy_is_a_problem_error() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    with pytest.raises(ProblemError, match="unknown strategy"):
        run_mission(MissionSpec(maze, route.start, route.goal, strategy="pray"))


@pytest.mark.parametrize("strategy", ["replacement", "lookahead"])
def test_a_table_of_another_domain_is_a_problem_error(strategy: str) -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(
        maze, route.start, route.goal, strategy=strategy,
        options=StrategyOptions(table="three-action"),
    )  # fmt: skip
    with pytest.raises(ProblemError, match="'three-action' domain"):
        run_mission(spec)


def test_negative_seed_is_a_problem_error() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    with pytest.raises(ProblemError, match="seed"):
        MissionSpec(maze, route.start, route.goal, seed=-1)


def test_one_off_costs_stay_out_of_the_first_repair() -> None:
    """The first table hit of a process on a fresh maze must not be charged for building the
    maze's free grid (slow on a large maze): run_mission builds it before any clock starts,
    even in a mission that never repairs."""
    from selfrepair.caching import clear_caches
    from selfrepair.repair.replacement import table_reach
    from selfrepair.world.maze import _FREE_GRIDS

    maze = Maze(np.zeros((30, 30), dtype=bool))
    spec = MissionSpec(maze, Pose(5, 15, Heading.E), (25, 15), strategy="replacement")
    clear_caches()
    result = run_mission(spec)
    assert result.reached and not result.repairs
    assert (maze, max(2, table_reach(spec.options.resolved_table()))) in _FREE_GRIDS


def test_metrics_helpers() -> None:
    assert plan_distance("aabc", "abd").total == 3
    assert plan_distance("aabc", "abd").removed == 2
    stats = latency_stats(range(1, 101))
    assert (stats.count, stats.median_ns, stats.p99_ns, stats.max_ns) == (100, 50, 99, 100)
    assert latency_stats([]).median_ns is None


def test_row_has_exact_and_float_twins() -> None:
    maze = load_bundled("wide-short")
    route = bundled_routes("wide-short")[0]
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(four_wheel.parse_faults("FR:F")),
        clearance_weight=Fraction(1, 3),
    )
    result = run_mission(spec)
    row = mission_row(result)
    cost_after = Fraction(str(row["plan_cost_after"]))
    assert cost_after == executed_cost(result)
    assert cost_after >= sum(s.duration for s in result.executed)  # penalties are >= 0
    assert row["plan_cost_after_float"] == pytest.approx(float(cost_after))
    assert row["plan_cost_before"] == str(result.initial_plan.cost)
    assert row["clearance_weight"] == "1/3"
    assert isinstance(row["initial_planning_ns"], int)


def test_docs_describe_every_row_column() -> None:
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs/replacement.md").read_text()
    section = doc.split("## Metric columns")[1].split("## Command line")[0]
    for column in ROW_COLUMNS:
        assert f"`{column}`" in section, column


def test_planning_with_the_faults_known_needs_no_repair() -> None:
    maze = load_bundled("wide-short")
    route = bundled_routes("wide-short")[2]
    faults = four_wheel.parse_faults("FL:F,RR:B")
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(faults),
        initial_faults_known=True,
    )
    result = run_mission(spec)
    _check_mission(result)
    assert result.reached and not result.repairs
    assert all(four_wheel.available(a, faults) for a in result.initial_plan.actions)
    blind = run_mission(
        MissionSpec(maze, route.start, route.goal, schedule=FaultSchedule.permanent(faults))
    )
    assert blind.repairs and blind.ticks >= result.ticks


@pytest.mark.slow
@pytest.mark.parametrize("name", ["narrow-short", "wide-short", "narrow-long", "wide-long"])
def test_bundled_routes_under_every_fault_set(name: str) -> None:
    """Every bundled route under every single and double fault, every strategy: the invariants
    hold, and replacement never replans more than replan."""
    maze = load_bundled(name)
    for route in bundled_routes(name):
        for faults in FOUR_WHEEL.fault_sets:
            rows = {}
            for strategy in STRATEGIES:
                spec = MissionSpec(
                    maze,
                    route.start,
                    route.goal,
                    schedule=FaultSchedule.permanent(faults),
                    strategy=strategy,
                )
                result = run_mission(spec)
                _check_mission(result)
                rows[strategy] = mission_row(result)
            assert rows["replacement"]["replans"] <= rows["replan"]["replans"]
