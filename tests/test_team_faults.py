"""Team robots with their own simulators: detection on use, intermittent wheel faults, the delay
of discovering a fault, failed attempts in team traces and their replay, on a hand-made box.

The box: a 7x5 room. Robot r1 starts at 1,1 facing east and delivers i1 from 6,1 to 6,4: it
drives five cells east (five 1-tick forward moves, ticks 0 to 5), picks i1 (ticks 5 to 7) and
then turns right on the spot (``FBFB``: the right wheels go backward) to drive south. Its wheel
fault ``FR:B`` (front-right wheel cannot go backward) is present from tick 0 and forbids exactly
that turn. Robot r2 works alone in the bottom row.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from selfrepair.cli import main
from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection, Persistence
from selfrepair.execution.result import StepSource
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.team.engine import run_team
from selfrepair.team.metrics import team_row
from selfrepair.team.model import RobotSpec, Task, TeamFault, TeamFaultKind, TeamScenario
from selfrepair.team.result import TeamOptions, TeamResult
from selfrepair.team.trace import read_team_trace, replay_team, team_trace_lines
from selfrepair.world.maze import Maze

SCALE = 3  # units per tick of the four-wheel robot
TURN = FOUR_WHEEL.parse_action("FBFB")
FR_B = FOUR_WHEEL.parse_faults("FR:B")


def _box() -> Maze:
    walls = np.zeros((7, 9), dtype=bool)
    walls[0, :] = walls[-1, :] = walls[:, 0] = walls[:, -1] = True
    return Maze(walls, name="box")


def _scenario(detection: Detection, fault: TeamFault | None = None) -> TeamScenario:
    fault = fault or TeamFault(TeamFaultKind.WHEELS, "r1", wheel_faults="FR:B")
    return TeamScenario(
        _box(),
        (RobotSpec("r1", Pose(1, 1, Heading.E)), RobotSpec("r2", Pose(1, 5, Heading.E))),
        (Task("i1", (6, 1), (6, 4)), Task("i2", (3, 5), (7, 5))),
        (fault,),
        name="box",
        detection=detection,
    )


def _replayed(result: TeamResult, tmp_path: Path) -> str:
    path = tmp_path / "team.jsonl"
    path.write_text("\n".join(team_trace_lines(result)) + "\n")
    report = replay_team(read_team_trace(path))
    assert report.ok, str(report)
    return path.read_text()


def _r1(result: TeamResult) -> list[tuple[float, str, StepSource]]:
    return [
        (m.start / SCALE, FOUR_WHEEL.format_action(m.action), m.source)
        for m in result.moves
        if m.robot == "r1"
    ]


def test_on_use_the_robot_learns_its_fault_when_the_turn_fails(tmp_path: Path) -> None:
    result = run_team(_scenario(Detection.ON_USE))
    assert result.all_delivered
    moves = _r1(result)
    assert moves[:5] == [(float(t), "FFFF", StepSource.PLAN) for t in range(5)]
    assert moves[5] == (7.0, "FBFB", StepSource.FAILED_ATTEMPT)  # after the 2-tick pick
    assert moves[6] == (8.0, "FSFS", StepSource.REPLACEMENT)  # the table's replacement
    [found] = result.discoveries
    assert (found.robot, found.index, found.at, found.delay) == ("r1", 0, 7 * SCALE, 7 * SCALE)
    [own] = result.own_repairs
    assert own.action == TURN and own.at == 8 * SCALE
    row = team_row(result)
    assert row["detection"] == "on-use" and row["failed_attempts"] == 1
    assert row["discovery_delay_max_ticks"] == 7.0
    assert json.loads(str(row["discovery_delays_ticks"])) == [7.0]
    text = _replayed(result, tmp_path)
    assert '"failed-attempt"' in text and '"discovery_delays_ticks": "[7.0]"' in text


def test_detection_now_senses_the_fault_at_once() -> None:
    result = run_team(_scenario(Detection.NOW))
    assert result.all_delivered
    assert all(source is not StepSource.FAILED_ATTEMPT for _, _, source in _r1(result))
    [found] = result.discoveries
    assert (found.at, found.delay) == (0, 0)
    assert "FBFB" not in [action for _, action, _ in _r1(result)]


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_an_intermittent_fault_bites_when_its_draw_says_so(seed: int, tmp_path: Path) -> None:
    """The turn is r1's command number 5 (after five forward moves): it fails exactly when the
    intermittent draw of fault 0 at that step, ``default_rng([seed, 0, 5])``, is below 0.5."""
    fault = TeamFault(
        TeamFaultKind.WHEELS, "r1", wheel_faults="FR:B",
        persistence=Persistence.INTERMITTENT, probability=0.5,
    )  # fmt: skip
    result = run_team(_scenario(Detection.ON_USE, fault), TeamOptions(seed=seed))
    assert result.all_delivered
    bites = float(np.random.default_rng([seed, 0, 5]).random()) < 0.5
    failed = [m for m in _r1(result) if m[2] is StepSource.FAILED_ATTEMPT]
    assert failed == ([(7.0, "FBFB", StepSource.FAILED_ATTEMPT)] if bites else [])
    assert [(d.at, d.delay) for d in result.discoveries] == ([(21, 21)] if bites else [])
    _replayed(result, tmp_path)


def test_replay_refuses_a_failed_attempt_the_true_faults_allow(tmp_path: Path) -> None:
    result = run_team(_scenario(Detection.ON_USE))
    lines = team_trace_lines(result)
    tampered = [
        line.replace('"FBFB"', '"FFFF"') if '"failed-attempt"' in line else line for line in lines
    ]
    assert tampered != lines
    path = tmp_path / "t.jsonl"
    path.write_text("\n".join(tampered) + "\n")
    report = replay_team(read_team_trace(path))
    assert not report.ok and "true faults allow it" in report.problem


def test_intermittent_team_faults_need_a_probability() -> None:
    with pytest.raises(ProblemError, match="probability"):
        TeamFault(TeamFaultKind.WHEELS, "r1", wheel_faults="FR:B",
                  persistence=Persistence.INTERMITTENT)  # fmt: skip
    with pytest.raises(ProblemError, match="wheel faults"):
        TeamFault(TeamFaultKind.GRIPPER, "r1", persistence=Persistence.INTERMITTENT,
                  probability=0.5)  # fmt: skip


SCENARIO = """\
name = "box"
maze = "box.maze"
detection = "now"

[[robots]]
name = "r1"
start = "1,1,E"

[[robots]]
name = "r2"
start = "1,5,E"

[[tasks]]
item = "i1"
pickup = "6,1"
dropoff = "6,4"

[[tasks]]
item = "i2"
pickup = "3,5"
dropoff = "7,5"

[[faults]]
kind = "wheels"
robot = "r1"
wheel_faults = "FR:B"
persistence = "intermittent"
probability = 1.0
"""


def test_cli_team_run_on_use_writes_a_trace_that_replays(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = ["#" * 9] + ["#" + "." * 7 + "#"] * 5 + ["#" * 9]
    (tmp_path / "box.maze").write_text("\n".join(rows) + "\n")
    scenario = tmp_path / "box.toml"
    scenario.write_text(SCENARIO)
    trace = tmp_path / "box.jsonl"
    assert main(["team", "run", str(scenario), "--detect", "on-use", "--trace", str(trace)]) == 0
    out = capsys.readouterr().out
    assert "r1 learns of fault 0" in out and "7 ticks after it started (detection on-use)" in out
    assert main(["team", "replay", str(trace)]) == 0
    summary = json.loads(trace.read_text().splitlines()[-1])
    assert summary["detection"] == "on-use" and summary["discovery_delays_ticks"] == "[7.0]"
    assert main(["team", "run", str(scenario), "--detect", "sometimes"]) == 2
    assert "detection" in capsys.readouterr().err


def test_the_scenario_detection_reaches_the_robots() -> None:
    now = run_team(_scenario(Detection.NOW))
    on_use = run_team(replace(_scenario(Detection.NOW), detection=Detection.ON_USE))
    assert now.discoveries[0].delay == 0 and on_use.discoveries[0].delay == 7 * SCALE


def test_own_replacements_count_only_replacements_that_ran() -> None:
    """Issue 29 item 17: robot r1 (wheel faults RL:B,RL:F from tick 9) replaces BBBB by BBSS at
    19,11 (unit 27), but the repaired drive cannot be placed around r2 and cooperative A* plans
    it again: the replacement never runs, and the row does not count it."""
    from selfrepair.team.experiment import FaultCase, TeamCase, build_scenario
    from selfrepair.team.randomteam import GripperMix
    from selfrepair.world.bundled import load_bundled

    case = TeamCase(2, 4, GripperMix.ALL, FaultCase.WHEELS, seed=5)
    result = run_team(build_scenario(load_bundled("wide-short"), case))
    assert result.all_delivered
    [own] = result.own_repairs
    assert (own.robot, own.at, FOUR_WHEEL.format_action(own.action)) == ("r1", 27, "BBBB")
    assert [FOUR_WHEEL.format_action(a) for a in own.actions] == ["BBSS"]
    after = [m for m in result.moves if m.robot == "r1" and m.start >= own.at]
    assert after and all(m.source is StepSource.REPLAN for m in after[:10])
    row = team_row(result)
    assert row["own_repairs"] == 1 and row["own_replacements"] == 0


@pytest.mark.parametrize("strategy", ["team-replacement", "reallocation", "alone"])
def test_an_item_given_up_during_a_blockage_is_offered_again(strategy: str, tmp_path: Path) -> None:
    """Issue 29 item 14: item i7 lies on 6,2, blocked from tick 3 to 83. Robot r2's drive there
    meets the blockage at tick 6; team replacement falls back to re-allocation, which cannot
    reach i7 on the known map and gives it to nobody. When the cell opens at tick 83 the item is
    offered again and delivered (as ``alone``, which waits, always did)."""
    walls = np.zeros((7, 11), dtype=bool)
    walls[0, :] = walls[-1, :] = walls[:, 0] = walls[:, -1] = True
    blocked = TeamFault(
        TeamFaultKind.BLOCKED, cells=((6, 2),), at=3, persistence=Persistence.TRANSIENT,
        duration=80,
    )  # fmt: skip
    scenario = TeamScenario(
        Maze(walls, name="room"),
        (RobotSpec("r1", Pose(1, 1, Heading.E)), RobotSpec("r2", Pose(1, 5, Heading.E))),
        (Task("i1", (3, 1), (3, 5)), Task("i7", (6, 2), (1, 3))),
        (blocked,),
        name="room",
    )
    result = run_team(scenario, TeamOptions(strategy=strategy))
    assert [(i.at, i.robot, i.kind.value) for i in result.incidents] == [(18, "r2", "blocked")]
    assert result.all_delivered, result.reason
    picked = [
        a.start for a in result.acts if a.action.kind.value == "pick" and a.action.item == "i7"
    ]
    assert picked and min(picked) >= 83 * SCALE  # not before the cell opened
    _replayed(result, tmp_path)
