"""``selfrepair run``, ``replay``, ``table show`` and ``table check``, driven in-process."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from selfrepair.cli import main

ROUTE = ["narrow-short", "--start", "1,1,E", "--goal", "13,13"]


def test_run_shows_picture_and_metrics(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", *ROUTE, "--faults", "FL:F,RR:B", "--strategy", "replacement"])
    out = capsys.readouterr().out
    assert code == 0
    picture = out.split("\n\n")[0].splitlines()
    assert picture[0] == "#" * 15 and picture[1].startswith("#>")
    assert "R" in out.split("#        wall")[0]
    assert "repair site" in out and "replacements" in out and "reached" in out


def test_run_json_row(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["run", *ROUTE, "--faults", "FL:F", "--detect", "on-use", "--strategy", "replan", "--json"]
    )
    row = json.loads(capsys.readouterr().out)
    assert code == 0
    assert row["strategy"] == "replan" and row["detection"] == "on-use"
    assert row["failed_attempts"] == 1 and row["replans"] == 1 and row["status"] == "reached"


def test_run_trace_then_replay(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = tmp_path / "t.jsonl"
    assert (
        main(
            [
                "run",
                *ROUTE,
                "--faults",
                "FR:F",
                "--at",
                "3",
                "--strategy",
                "lookahead",
                "--window",
                "2",
                "--recursion",
                "guarded",
                "--trace",
                str(trace),
                "--json",
            ]
        )
        == 0
    )
    capsys.readouterr()
    assert main(["replay", str(trace)]) == 0
    assert "steps replay" in capsys.readouterr().out
    lines = trace.read_text().splitlines()
    step = json.loads(lines[2])
    step["to"] = [99, 99, "N"]
    lines[2] = json.dumps(step)
    trace.write_text("\n".join(lines) + "\n")
    assert main(["replay", str(trace)]) == 1
    assert "step 1 (line 3) does not hold" in capsys.readouterr().out


def test_run_intermittent_faults(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["run", *ROUTE, "--faults", "FL:F", "--intermittent", "0.5", "--seed", "3", "--json"]
    )
    row = json.loads(capsys.readouterr().out)
    assert code == 0 and row["seed"] == 3 and "intermittent" in row["fault_schedule"]


def test_run_reports_a_stuck_mission(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", *ROUTE, "--faults", "FL:F,RL:F,FL:B,RL:B", "--json"])
    row = json.loads(capsys.readouterr().out)
    assert code == 1 and row["status"] == "stuck" and "no plan exists" in row["reason"]


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--strategy", "pray"], "--strategy"),
        (["--recursion", "deep"], "--recursion"),
        (["--faults", "FL:X"], "--faults"),
        (["--detect", "later"], "--detect"),
        (["--table", "nosuch.json"], "nosuch.json"),
        (["--clearance-weight", "1e308"], "--clearance-weight"),  # was an OverflowError
        (["--clearance-weight", "x"], "--clearance-weight"),
    ],
)
def test_run_bad_input_is_exit_2(
    args: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", *ROUTE, *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("selfrepair: error:") and expected in err and err.count("\n") == 1


def test_run_at_the_weight_bound_has_finite_metrics(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", *ROUTE, "--clearance-weight", "1000000", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert row["plan_cost_before_float"] > 1_000_000 and row["status"] == "reached"


def test_table_show(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["table", "show", "handwritten"]) == 0
    out = capsys.readouterr().out
    assert "four-wheel, fault-agnostic, made by hand" in out and "FBFB FBFB FBFB" in out
    assert main(["table", "show", "three-action"]) == 0
    assert "(no replacement)" in capsys.readouterr().out
    assert main(["table", "show", "handwritten", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["made_by"] == "hand"


def test_table_check(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["table", "check", "handwritten"]) == 0
    assert "0 errors, 0 warnings" in capsys.readouterr().out
    bad = tmp_path / "bad.json"
    bad.write_text(
        json.dumps(
            {
                "format": "selfrepair-table",
                "version": 1,
                "domain": "four-wheel",
                "shape": "fault-agnostic",
                "made_by": "hand",
                "parameters": {},
                "entries": [{"action": "BFBF", "candidates": [["FBFB"]]}],
            },
            indent=1,
        )
    )
    assert main(["table", "check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "entry 0 (action BFBF" in err
    indexed = tmp_path / "indexed.json"
    indexed.write_text(
        json.dumps(
            {
                "format": "selfrepair-table",
                "version": 1,
                "domain": "four-wheel",
                "shape": "fault-indexed",
                "made_by": "generator",
                "parameters": {"max_length": 1},
                "entries": [{"action": "FFFF", "faults": "FL:F", "candidates": [["FFSS"]]}],
            }
        )
    )
    assert main(["table", "check", str(indexed)]) == 1
    assert "error: entry 0 (FFFF)" in capsys.readouterr().out


def test_table_show_a_file_and_transient_faults(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "mine.json"
    assert main(["table", "show", "three-action", "--json"]) == 0
    path.write_text(capsys.readouterr().out)
    assert main(["table", "show", str(path)]) == 0
    assert "L L L" in capsys.readouterr().out
    code = main(
        [
            "run",
            *ROUTE,
            "--faults",
            "FL:F",
            "--transient",
            "4",
            "--at",
            "2",
            "--plan-with-faults",
            "--json",
        ]
    )
    row = json.loads(capsys.readouterr().out)
    assert code == 0 and '"transient"' in row["fault_schedule"]
    assert main(["run", *ROUTE, "--transient", "2", "--intermittent", "0.5"]) == 2
