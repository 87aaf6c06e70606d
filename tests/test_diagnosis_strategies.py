"""The strategies for hidden faults, run by the one stepper loop: oracle, diagnose, conformant,
active diagnosis and trial and error."""

from __future__ import annotations

from dataclasses import replace

import pytest

from selfrepair.diagnosis import ObservationModel
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionSpec, StepSource
from selfrepair.repair.strategies import ROBOT, StrategyName, StrategyOptions, strategy_entry
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.world.bundled import bundled_routes, load_bundled

HIDDEN = (
    StrategyName.ORACLE,
    StrategyName.DIAGNOSE,
    StrategyName.CONFORMANT,
    StrategyName.ACTIVE_DIAGNOSIS,
    StrategyName.TRIAL_AND_ERROR,
)
TIMING = ("_ns", "latenc", "compute")


def _spec(faults: str, strategy: str, noise: float = 0.0, seed: int = 0, route: int = 0,
          maze: str = "narrow-long") -> MissionSpec:  # fmt: skip
    r = bundled_routes(maze)[route]
    schedule = FaultSchedule.permanent(FOUR_WHEEL.parse_faults(faults), detection=Detection.HIDDEN)
    return MissionSpec(
        load_bundled(maze), r.start, r.goal, schedule=schedule, strategy=strategy, seed=seed,
        observation=ObservationModel(noise, bumps=True), max_steps=3000,
    )  # fmt: skip


def _stable(row: dict[str, object]) -> dict[str, object]:
    return {k: v for k, v in row.items() if not any(t in k for t in TIMING)}


@pytest.mark.parametrize("strategy", HIDDEN)
@pytest.mark.parametrize("faults", ["FL:F", "RL:F,FR:B"])
def test_every_strategy_reaches_the_goal_with_hidden_faults(strategy: str, faults: str) -> None:
    result = run_mission(_spec(faults, strategy))
    row = mission_row(result)
    assert result.reached, result.reason
    assert row["detection"] == "hidden" and row["behaviour"] == "stall"
    assert row["observation_noise"] == 0.0
    assert row["bumps"] == sum(s.source is StepSource.BUMPED for s in result.steps)
    if strategy == StrategyName.ORACLE:
        assert row["bumps"] == 0 and row["surprise_step"] is None
    else:
        assert row["surprise_step"] is not None  # the initial plan meets the fault
    if row["isolation_actions"] is not None:
        assert row["isolated_right"] == 1  # exact observations never isolate a wrong class


@pytest.mark.parametrize("faults", ["FR:B,RL:S", "RL:B,RL:S"])
def test_a_conformant_robot_without_a_conformant_plan_falls_back(faults: str) -> None:
    # here no plan avoids every fault still credible near the goal: the robot assumes the most
    # probable class instead of giving up (it was stuck before)
    result = run_mission(_spec(faults, StrategyName.CONFORMANT, maze="wide-short"))
    assert result.reached, result.reason


def test_a_strategy_that_does_not_observe_is_lost_with_hidden_faults() -> None:
    result = run_mission(_spec("FL:F", StrategyName.REPLACEMENT))
    assert not result.reached and mission_row(result)["bumps"] > 100


def test_the_oracle_is_replacement_told_its_faults() -> None:
    told = run_mission(_spec("FL:F,RR:B", StrategyName.ORACLE))
    spec = _spec("FL:F,RR:B", StrategyName.REPLACEMENT)
    now = run_mission(replace(spec, schedule=replace(spec.schedule, detection=Detection.NOW)))
    assert [(s.action, s.end) for s in told.steps] == [(s.action, s.end) for s in now.steps]
    assert strategy_entry(StrategyName.ORACLE, ROBOT).told


def test_active_diagnosis_isolates_a_single_fault_quickly() -> None:
    result = run_mission(_spec("FL:F", StrategyName.ACTIVE_DIAGNOSIS))
    row = mission_row(result)
    assert row["isolated_right"] == 1 and row["isolation_actions"] <= 3
    assert row["probes"] >= 1
    assert any(s.source is StepSource.PROBE for s in result.steps)


def test_the_same_seed_gives_the_same_rows_with_noise() -> None:
    first = _stable(mission_row(run_mission(_spec("FL:F", StrategyName.DIAGNOSE, 0.05, seed=3))))
    again = _stable(mission_row(run_mission(_spec("FL:F", StrategyName.DIAGNOSE, 0.05, seed=3))))
    assert first == again and first["observation_noise"] == 0.05


def test_a_robot_without_a_behaviour_model_diagnoses_from_failed_commands() -> None:
    maze = load_bundled("narrow-short")
    r = bundled_routes("narrow-short")[0]
    schedule = FaultSchedule.permanent({"R"}, detection=Detection.HIDDEN)
    spec = MissionSpec(
        maze, r.start, r.goal, schedule=schedule, strategy=StrategyName.DIAGNOSE,
        options=StrategyOptions(table="three-action"), domain=THREE_ACTION, max_steps=500,
    )  # fmt: skip
    result = run_mission(spec)
    row = mission_row(result)
    assert result.reached, result.reason
    assert row["failed_attempts"] >= 1 and row["behaviour"] is None
    assert row["isolated_right"] == 1
