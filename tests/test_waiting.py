"""Waiting is a repair (issue 29 item 7): when no plan exists under the known faults, the robot
waits in place (its domain's wait action, source ``wait``) up to ``StrategyOptions.max_wait``
steps in all and asks again, so a fault that clears does not end the mission ``stuck``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from selfrepair.cli import main
from selfrepair.execution import executor
from selfrepair.execution.faults import FaultEvent, FaultSchedule, Persistence
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionSpec, StepSource
from selfrepair.execution.trace import read_trace, replay, write_trace
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots import four_wheel
from selfrepair.robots.registry import get_domain
from selfrepair.world.maze import Maze

CORRIDOR = Maze(np.array([[True, False, True], [True, False, True], [True, False, True]]))
"""A one-cell corridor (column 1) from (1, 2) facing north to the goal (1, 0)."""

LEFT_STOPPED = "FL:F,RL:F,FL:B,RL:B"
"""Both left wheels can only stop: the robot can turn in place but never leave its cell, so no
plan exists while these faults last; the all-stop ``SSSS`` stays available."""


def _spec(persistence: Persistence, *, max_wait: int = 20, detection: str = "now") -> MissionSpec:
    events = tuple(
        FaultEvent(f, persistence=persistence, duration=5 if persistence == "transient" else None)
        for f in four_wheel.parse_faults(LEFT_STOPPED)
    )
    return MissionSpec(
        CORRIDOR,
        Pose(1, 2, Heading.N),
        (1, 0),
        schedule=FaultSchedule(events, detection),  # type: ignore[arg-type]
        strategy="lookahead",
        options=StrategyOptions(max_wait=max_wait),
        backend="python",
    )


def test_lookahead_waits_out_a_transient_fault_and_reaches_the_goal() -> None:
    result = executor.run_mission(_spec(Persistence.TRANSIENT))
    waits = [s for s in result.steps if s.source is StepSource.WAIT]
    assert result.status == "reached", result.reason
    # The faults last steps 0 to 4: the robot waits five steps in place, then drives.
    assert [s.step for s in waits] == [0, 1, 2, 3, 4]
    assert all(s.start == s.end and s.action == four_wheel.parse_action("SSSS") for s in waits)
    assert all(four_wheel.available(s.action, s.known) for s in waits)
    row = mission_row(result)
    assert row["waits"] == 5 and row["reached"] == 1


def test_without_waits_the_same_mission_is_stuck() -> None:
    result = executor.run_mission(_spec(Persistence.TRANSIENT, max_wait=0))
    assert result.status == "stuck" and "no plan exists" in result.reason
    assert "waiting" not in result.reason and mission_row(result)["waits"] == 0


def test_a_permanent_fault_runs_the_wait_bound_out_and_says_so() -> None:
    result = executor.run_mission(_spec(Persistence.PERMANENT, max_wait=3))
    assert result.status == "stuck"
    assert result.reason.endswith("no plan exists after waiting 3 steps"), result.reason
    assert [s.source for s in result.steps] == [StepSource.WAIT] * 3
    assert mission_row(result)["waits"] == 3 and result.ticks == 3


def test_on_use_detection_never_waits() -> None:
    # Faults learned on use are never forgotten: a wait could not change the plan.
    result = executor.run_mission(_spec(Persistence.TRANSIENT, detection="on-use"))
    assert result.status == "stuck" and mission_row(result)["waits"] == 0


def test_wait_actions_come_from_the_motion_table() -> None:
    four = get_domain("four-wheel")
    assert four.parse_action("SSSS") in four.waits
    for action in four.waits:
        for heading in Heading:
            pose = Pose(3, 3, heading)
            assert four.apply(pose, action) == pose and set(four.footprint(pose, action)) == {
                pose.cell
            }
    assert get_domain("three-action").waits == ()  # it cannot stand still: it never waits


def test_a_waiting_trace_replays(tmp_path: Path) -> None:
    result = executor.run_mission(_spec(Persistence.TRANSIENT))
    path = tmp_path / "wait.jsonl"
    write_trace(result, path)
    report = replay(path)
    assert report.ok, report.reason
    assert read_trace(path).header["options"]["max_wait"] == 20
    assert main(["replay", str(path)]) == 0


@pytest.mark.parametrize(("bound", "status", "waits"), [("0", "stuck", 0), ("5", "reached", 5)])
def test_cli_max_wait(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], bound: str, status: str, waits: int
) -> None:
    maze = tmp_path / "corridor.txt"
    maze.write_text("#.#\n#.#\n#.#\n")
    trace = tmp_path / "run.jsonl"
    args = ["run", str(maze), "--start", "1,2,N", "--goal", "1,0", "--faults", LEFT_STOPPED]
    args += ["--transient", "5", "--strategy", "lookahead", "--max-wait", bound, "--json"]
    code = main([*args, "--trace", str(trace)])
    row = json.loads(capsys.readouterr().out)
    assert (row["status"], row["waits"]) == (status, waits)
    assert code == (0 if status == "reached" else 1)
    assert main(["replay", str(trace)]) == 0


def test_cli_help_names_the_wait_bound(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--help"]) == 0
    assert "--max-wait" in capsys.readouterr().out
