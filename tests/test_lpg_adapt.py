"""The ``lpg-adapt`` strategy (:mod:`selfrepair.baselines.adapt`) and every strategy's answer to a
goal that the faults make unreachable.

The tests that run LPG need the ``pddl`` extra and are skipped with that reason without it (pytest
-ra lists the reason); the others run everywhere (the extra's absence is simulated where a test
needs it). No test asserts a time.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from extras import LPG
from selfrepair.baselines import adapt
from selfrepair.cli import main
from selfrepair.errors import ProblemError
from selfrepair.execution.context import mission_context
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionSpec, MissionStatus, StepSource
from selfrepair.execution.trace import read_trace, replay, write_trace
from selfrepair.repair.strategies import (
    RepairRequest,
    RepairSource,
    RepairStatus,
    StrategyOptions,
    get_strategy,
    strategy_names,
    uses_table,
)
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.search.lattice import plan_cost
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled

needs_lpg = LPG

NO_MOTION = "FL:F,FL:B,FR:F,FR:B,RL:F,RL:B,RR:F,RR:B"
"""Every wheel can only stop: the robot cannot move, so no goal elsewhere can be reached."""


def mission(
    faults: str,
    strategy: str = "lpg-adapt",
    maze: str = "narrow-short",
    route: int = 0,
    **options: object,
) -> MissionSpec:
    """A bundled route with ``faults`` present from step 0 and detected at once."""
    r = bundled_routes(maze)[route]
    events = tuple(FaultEvent(f, at=0) for f in FOUR_WHEEL.parse_faults(faults))
    return MissionSpec(
        load_bundled(maze),
        r.start,
        r.goal,
        schedule=FaultSchedule(events=events),
        strategy=strategy,
        options=StrategyOptions(**options),  # type: ignore[arg-type]
    )


def pretend_installed(monkeypatch: pytest.MonkeyPatch, installed: bool) -> None:
    monkeypatch.setattr(adapt, "lpg_available", lambda: installed)


# --- registration and misuse -----------------------------------------------------------------


def test_registered_by_name_without_a_table() -> None:
    assert "lpg-adapt" in strategy_names() and "dstar-lite" in strategy_names()
    assert get_strategy("lpg-adapt") is adapt.start_lpg_adapt
    assert not uses_table("lpg-adapt")


def test_without_the_extra_the_strategy_says_so_in_one_line(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    pretend_installed(monkeypatch, False)
    with pytest.raises(ProblemError, match=r"needs the pddl extra .*selfrepair\[pddl\]") as info:
        run_mission(mission("FL:F"))
    assert "\n" not in str(info.value)


def test_without_the_extra_the_cli_exits_2_with_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    pretend_installed(monkeypatch, False)
    args = ["run", "narrow-short", "--start", "1,1,E", "--goal", "13,13", "--faults", "FL:F"]
    code = main([*args, "--strategy", "lpg-adapt"])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "pddl extra" in err


def test_other_robots_and_bad_time_limits_are_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    pretend_installed(monkeypatch, True)
    with pytest.raises(ProblemError, match="four-wheel robot only"):
        adapt.check_lpg_adapt(THREE_ACTION.name)
    with pytest.raises(ProblemError, match="at most 3600"):
        run_mission(mission("FL:F", lpg_time_limit_s=4000.0))
    with pytest.raises(ProblemError, match="lpg_time_limit_s"):
        StrategyOptions(lpg_time_limit_s=0)
    with pytest.raises(ProblemError, match="lpg_time_limit_s"):
        StrategyOptions(lpg_time_limit_s=float("nan"))


def test_a_maze_beyond_lpg_falls_back_at_once_and_says_why(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """wide-long has more free cells than LPG-td takes: every repair is a replan, recorded."""
    pretend_installed(monkeypatch, True)
    spec = mission("FL:F", maze="wide-long")
    assert adapt.lpg_objects(spec.maze) > 2000
    result = run_mission(spec)
    assert result.reached and result.repairs
    for record in result.repairs:
        assert record.repair.attempts == ("lpg-adapt:error", "replan")
        assert record.repair.source is RepairSource.REPLAN
    row = mission_row(result)
    assert row["fallbacks"] == len(result.repairs) and row["plan_repairs"] == 0
    assert json.loads(str(row["repair_attempts"]))["lpg-adapt:error"] == len(result.repairs)


# --- with LPG --------------------------------------------------------------------------------


@needs_lpg
def test_lpg_plan_is_executed_when_it_re_simulates(tmp_path: Path) -> None:
    spec = mission("FR:B", lpg_time_limit_s=60.0, lpg_seed=1)  # LPG-adapt solves this one
    result = run_mission(spec)
    assert result.status is MissionStatus.REACHED
    (record,) = result.repairs
    assert record.repair.attempts == ("lpg-adapt",)
    assert record.repair.source is RepairSource.PLAN_REPAIR
    assert record.repair.consumed == len(result.initial_plan.actions) - record.step
    # LPG's plan is what was executed after the repair, and it is valid under the faults
    after = [s for s in result.steps if s.step >= record.step]
    assert all(s.source is StepSource.PLAN_REPAIR for s in after)
    problem = PlanningProblem(
        spec.maze, record.pose, spec.goal, faults=FOUR_WHEEL.parse_faults("FR:B")
    )
    assert plan_cost(problem, record.repair.actions) > 0  # raises if it does not re-simulate
    row = mission_row(result)
    assert row["plan_repairs"] == 1 and row["fallbacks"] == 0 and row["replans"] == 0
    trace = tmp_path / "lpg.jsonl"
    write_trace(result, trace)
    parsed = read_trace(trace)
    assert parsed.header["options"]["lpg_seed"] == 1
    assert replay(parsed).ok
    assert parsed.repairs[0].source is RepairSource.PLAN_REPAIR


@needs_lpg
def test_a_time_out_is_recorded_and_replanning_takes_over() -> None:
    result = run_mission(mission("FR:B", lpg_time_limit_s=0.001))
    assert result.status is MissionStatus.REACHED
    (record,) = result.repairs
    assert record.repair.attempts == ("lpg-adapt:timeout", "replan")
    assert record.repair.source is RepairSource.REPLAN and record.repair.replans == 1
    row = mission_row(result)
    assert row["fallbacks"] == 1 and row["replans"] == 1
    assert json.loads(str(row["repair_attempts"])) == {"lpg-adapt:timeout": 1, "replan": 1}


@needs_lpg
def test_cli_runs_lpg_adapt(capsys: pytest.CaptureFixture[str]) -> None:
    route = ["narrow-short", "--start", "7,13,W", "--goal", "1,8", "--faults", "FR:B"]
    code = main(["run", *route, "--strategy", "lpg-adapt", "--lpg-time-limit", "60", "--json"])
    row = json.loads(capsys.readouterr().out)
    assert code == 0 and row["strategy"] == "lpg-adapt" and row["status"] == "reached"


# --- an unreachable goal ---------------------------------------------------------------------

STRATEGIES = [
    "replan",
    "replacement",
    "lookahead",
    "dstar-lite",
    pytest.param("lpg-adapt", marks=needs_lpg),
]


@pytest.mark.timeout(120)
@pytest.mark.parametrize("strategy", STRATEGIES)
def test_an_unreachable_goal_is_stuck_for_every_strategy(strategy: str) -> None:
    """Faults that leave the robot no move: each strategy ends its mission ``stuck`` (no hang, no
    exception), and the reason says that no plan exists."""
    result = run_mission(mission(NO_MOTION, strategy))
    assert result.status is MissionStatus.STUCK
    assert "no plan exists" in result.reason
    assert result.repairs[-1].repair.status is RepairStatus.STUCK
    if strategy == "lpg-adapt":
        assert result.repairs[-1].repair.attempts == ("lpg-adapt:no-plan", "replan")


@pytest.mark.timeout(120)
@pytest.mark.parametrize("strategy", ["dstar-lite", pytest.param("lpg-adapt", marks=needs_lpg)])
def test_a_baseline_repairer_answers_stuck_directly(strategy: str) -> None:
    """The repairer itself (not only the mission) answers ``stuck`` for the unreachable goal."""
    spec = mission(NO_MOTION, strategy)
    context = mission_context(spec, None)
    repairer = get_strategy(strategy)(context)

    initial = context.plan(spec.start, spec.goal, None, frozenset(), None)
    known = FOUR_WHEEL.parse_faults(NO_MOTION)
    repair = repairer.repair(RepairRequest(spec.start, initial.actions, known))
    assert repair.status is RepairStatus.STUCK and repair.actions == ()
