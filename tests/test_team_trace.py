"""Team traces: a real trace replays clean, and each tampered copy of it is caught (issue 29,
item 18): an act that lasts 1 tick instead of 2, a changed makespan or incident count in the
summary, an item picked again after its delivery, a removed "clear" line of a transient fault,
a header that no longer matches its scenario file or its maze digest. A Hypothesis property:
every trace of random small team missions replays clean (no conflict: reservations never let two
robots hold one cell at once)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.execution.faults import Persistence
from selfrepair.team.engine import run_team
from selfrepair.team.model import TeamFault, TeamFaultKind
from selfrepair.team.randomteam import random_scenario
from selfrepair.team.replay import replay_team
from selfrepair.team.result import TeamOptions
from selfrepair.team.scenario import load_scenario
from selfrepair.team.traceformat import TEAM_TRACE_VERSION, maze_digest
from selfrepair.team.traceread import parse_team_trace
from selfrepair.team.tracewrite import team_trace_lines, write_team_trace
from selfrepair.world.bundled import resolve_maze

SCENARIO = """name = "transient"
maze = "wide-short"

[[robots]]
name = "r1"
start = "1,1,E"

[[robots]]
name = "r2"
start = "22,13,W"

[[tasks]]
item = "i1"
pickup = "5,4"
dropoff = "16,1"

[[tasks]]
item = "i2"
pickup = "20,13"
dropoff = "3,1"

[[faults]]
kind = "immobilised"
robot = "r1"
at = 4
persistence = "transient"
duration = 6
"""


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[dict[str, Any]]]:
    """A scenario file and the lines of its trace, as objects."""
    folder = tmp_path_factory.mktemp("trace")
    path = folder / "transient.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    result = run_team(load_scenario(path))
    assert result.all_delivered and [f.active for f in result.faults] == [True, False]
    return path, [json.loads(line) for line in team_trace_lines(result)]


def _replay(lines: list[dict[str, Any]]) -> Any:
    return replay_team(parse_team_trace("\n".join(json.dumps(o) for o in lines)))


def _copy(lines: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return json.loads(json.dumps(lines))


def test_the_real_trace_replays_and_records_its_files(written: Any) -> None:
    path, lines = written
    header = lines[0]
    assert header["version"] == TEAM_TRACE_VERSION
    assert (
        header["scenario_file"]["path"] == str(path)
        and len(header["scenario_file"]["sha256"]) == 64
    )
    assert header["maze"]["sha256"] == maze_digest(header["maze"]["rows"])
    assert header["robot_table"] == "handwritten"
    report = _replay(lines)
    assert report.ok, str(report)
    assert report.delivered == 2 and f"header matches scenario file {path}" in str(report)


def test_an_act_of_one_tick_is_caught(written: Any) -> None:
    lines = _copy(written[1])
    act = next(o for o in lines if o["type"] == "act")
    act["end"] = act["start"] + lines[0]["scale"]  # 1 tick instead of 2
    report = _replay(lines)
    assert not report.ok and "lasts 3 units, not 2 ticks (6 units)" in report.problem


@pytest.mark.parametrize("key", ["makespan", "incidents", "repairs", "delivered", "moves"])
def test_a_changed_summary_is_caught(written: Any, key: str) -> None:
    lines = _copy(written[1])
    lines[-1][key] += 1
    report = _replay(lines)
    assert not report.ok and f"the summary says {key}" in report.problem


def test_an_item_picked_again_after_delivery_is_caught(written: Any) -> None:
    lines = _copy(written[1])

    def last_cell(robot: str) -> list[int]:
        return [o["to"][:2] for o in lines if o["type"] == "move" and o["robot"] == robot][-1]

    drops = [o for o in lines if o["type"] == "act" and o["action"].startswith("drop(")]
    # the robot that stays on its drop-off picks the delivered item up again after the mission
    drop = next(d for d in drops if last_cell(d["action"][5:-1].split(",")[0]) == d["cells"][0])
    robot, item = drop["action"][5:-1].split(",")
    end = max(o.get("end", 0) for o in lines)
    again = {"type": "act", "start": end, "end": end + 6, "action": f"pick({robot},{item})",
             "cells": drop["cells"]}  # fmt: skip
    lines.insert(len(lines) - 1, again)
    lines[-1]["acts"] += 1
    report = _replay(lines)
    assert not report.ok and f"item {item} was delivered at unit {drop['end']}" in report.problem


def test_a_removed_clear_line_is_caught(written: Any) -> None:
    lines = [o for o in _copy(written[1]) if not (o["type"] == "fault" and not o["active"])]
    assert len(lines) == len(written[1]) - 1
    report = _replay(lines)
    assert not report.ok and "is logged as [(12, True)], not [(12, True), (30, False)]" in (
        report.problem
    )


def test_a_header_that_no_longer_matches_its_scenario_file_is_caught(
    written: Any, tmp_path: Path
) -> None:
    lines = written[1]
    moved = _copy(lines)
    moved[0]["tasks"][0]["dropoff"] = [17, 1]
    report = _replay(moved)
    assert not report.ok and "the header's tasks differ from the scenario file" in report.problem
    other = tmp_path / "edited.toml"
    other.write_text(SCENARIO.replace("duration = 6", "duration = 7"), encoding="utf-8")
    edited = _copy(lines)
    edited[0]["scenario_file"]["path"] = str(other)
    report = _replay(edited)
    assert not report.ok and "changed since the trace was written" in report.problem
    gone = _copy(lines)
    gone[0]["scenario_file"]["path"] = str(tmp_path / "gone.toml")
    report = _replay(gone)
    assert report.ok and "not found, not checked" in str(report)


def test_maze_rows_that_do_not_match_their_digest_are_caught(written: Any) -> None:
    lines = _copy(written[1])
    rows = lines[0]["maze"]["rows"]
    rows[-2] = rows[-2][:3] + "#" + rows[-2][4:]  # a cell of the bottom corridor walled up
    lines[0]["scenario_file"]["sha256"] = ""
    report = _replay(lines)
    assert not report.ok and "do not match the maze's sha256" in report.problem


def test_cli_replay_exits_1_on_a_tampered_summary(
    written: Any, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lines = _copy(written[1])
    lines[-1]["makespan"] = 1.0
    path = tmp_path / "t.jsonl"
    path.write_text("\n".join(json.dumps(o) for o in lines) + "\n", encoding="utf-8")
    assert main(["team", "replay", str(path)]) == 1
    assert "the summary says makespan 1.0" in capsys.readouterr().out


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**32 - 1),
    robots=st.integers(1, 4),
    tasks=st.integers(1, 4),
    strategy=st.sampled_from(["team-replacement", "reallocation", "alone"]),
    fault=st.sampled_from(["none", "immobilised", "gripper", "transient"]),
)
def test_every_trace_of_a_random_small_mission_replays_clean(
    tmp_path_factory: pytest.TempPathFactory,
    seed: int,
    robots: int,
    tasks: int,
    strategy: str,
    fault: str,
) -> None:
    maze = resolve_maze("wide-short")
    scenario = random_scenario(maze, robots, tasks, np.random.default_rng(seed))
    if fault != "none":
        kind = TeamFaultKind.GRIPPER if fault == "gripper" else TeamFaultKind.IMMOBILISED
        transient = fault == "transient"
        scenario = scenario.__class__(
            scenario.maze, scenario.robots, scenario.tasks,
            (TeamFault(kind, "r1", at=seed % 7,
                       persistence=Persistence.TRANSIENT if transient else Persistence.PERMANENT,
                       duration=5 if transient else None),),
            name="random",
        )  # fmt: skip
    result = run_team(scenario, TeamOptions(strategy=strategy))
    path = tmp_path_factory.mktemp("random") / "t.jsonl"
    write_team_trace(result, path)
    report = replay_team(parse_team_trace(path.read_text(encoding="utf-8")))
    assert report.ok, str(report)
    assert report.delivered == len(result.delivered)


def test_a_plug_in_robots_team_trace_replays_in_a_fresh_process(tmp_path: Path) -> None:
    import subprocess
    import sys

    hopper = Path(__file__).parent / "data" / "robots" / "hopper.py"
    text = SCENARIO.replace('maze = "wide-short"', f'maze = "wide-short"\ndomain = "hopper"\n'
                            f'plugins = ["{hopper}"]')  # fmt: skip
    path = tmp_path / "hop.toml"
    path.write_text(text, encoding="utf-8")
    trace = tmp_path / "hop.jsonl"
    assert main(["team", "run", str(path), "--trace", str(trace)]) == 0
    header = json.loads(trace.read_text(encoding="utf-8").splitlines()[0])
    assert header["domain"] == "hopper" and header["plugin"]["path"] == str(hopper.resolve())
    assert header["robot_table"] == "generated"
    replay = subprocess.run(
        [sys.executable, "-c", "from selfrepair.cli import run; run()", "team", "replay",
         str(trace)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert replay.returncode == 0, replay.stderr
    assert "header matches scenario file" in replay.stdout
