"""``selfrepair run``, ``replay``, ``table show`` and ``table check``, driven in-process."""

from __future__ import annotations

import json
import re
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
    out = capsys.readouterr().out
    expected = rf"{re.escape(str(trace))}: ok: all \d+ steps hold under the robot model\n"
    assert re.fullmatch(expected, out)
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
    assert code == 0 and row["seed"] == 3
    assert {e["persistence"] for e in row["fault_schedule"]["events"]} == {"intermittent"}


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
    assert row["plan_cost_before"] > 1_000_000 and row["status"] == "reached"


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
    assert code == 0 and row["fault_schedule"]["events"][0]["persistence"] == "transient"
    assert main(["run", *ROUTE, "--transient", "2", "--intermittent", "0.5"]) == 2


def _floats(value: object) -> list[float]:
    if isinstance(value, float):
        return [value]
    if isinstance(value, dict):
        return [f for v in value.values() for f in _floats(v)]
    if isinstance(value, list):
        return [f for v in value for f in _floats(v)]
    return []


def test_run_json_numbers_are_numbers(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", *ROUTE, "--faults", "FL:F,RR:B", "--strategy", "replan", "--json"])
    row = json.loads(capsys.readouterr().out)
    assert code == 0
    assert isinstance(row["ticks"], int) and row["ticks_exact"] == str(row["ticks"])
    assert isinstance(row["plan_cost_after"], int) and isinstance(row["plan_cost_after_exact"], str)
    assert not [k for k in row if k.endswith("_float")]
    assert row["reached"] is True
    assert isinstance(row["compute_per_action_ns"], int)
    assert isinstance(row["repair_latencies_ns"], list)
    assert all(isinstance(v, int) for v in row["repair_latencies_ns"])
    assert all(len(repr(f).split(".")[-1]) <= 6 for f in _floats(row))  # no unrounded floats
    assert set(row) >= {"kernel_load_ms", "warm_up"} and row["warm_up"] is True


def test_run_fractional_ticks_keep_an_exact_twin(capsys: pytest.CaptureFixture[str]) -> None:
    # With FL:F the fastest turn left is 4/3 ticks: the ticks are fractional.
    code = main(["run", *ROUTE, "--faults", "FR:F,RR:F", "--strategy", "replan", "--json"])
    row = json.loads(capsys.readouterr().out)
    assert code == 0
    assert isinstance(row["ticks"], int | float) and isinstance(row["ticks_exact"], str)
    from fractions import Fraction

    assert abs(Fraction(row["ticks_exact"]) - Fraction(str(row["ticks"]))) < Fraction(1, 10**6)


def test_run_text_says_what_the_times_leave_out(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", *ROUTE, "--faults", "FL:F"]) == 0
    assert "timed after an untimed warm-up run" in capsys.readouterr().out
    assert main(["run", *ROUTE, "--faults", "FL:F", "--no-warm-up"]) == 0
    assert "no warm-up run" in capsys.readouterr().out


def test_replay_partial_trace(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = tmp_path / "t.jsonl"
    assert main(["run", *ROUTE, "--faults", "FL:F", "--trace", str(trace), "--json"]) == 0
    capsys.readouterr()
    lines = trace.read_text().splitlines()
    trace.write_text("\n".join(lines[:-3]) + "\n")  # cut short: no summary line
    assert main(["replay", str(trace)]) == 2
    assert "--partial" in capsys.readouterr().err
    assert main(["replay", str(trace), "--partial"]) == 0
    assert "partial trace" in capsys.readouterr().out
    assert main(["replay", str(trace), "--max-trace-bytes", "10"]) == 2
    assert "--max-trace-bytes" in capsys.readouterr().err


def test_compare_every_strategy_side_by_side(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["compare", *ROUTE, "--faults", "FL:F,RR:B"])
    out = capsys.readouterr().out
    assert code == 0
    for label in ("replan", "replacement[handwritten,flat]", "lookahead[handwritten,flat,k=3]"):
        assert label in out
    for header in ("status", "ticks", "replans", "replacements", "latency", "plan distance"):
        assert header in out
    verdict = [line for line in out.splitlines() if line.startswith("verdict: ")]
    assert len(verdict) == 1 and "fastest repair" in verdict[0] and "fewest ticks" in verdict[0]
    assert "timed after an untimed warm-up run" in out


def test_compare_json_matches_run(capsys: pytest.CaptureFixture[str]) -> None:
    args = [*ROUTE, "--faults", "FL:F,RR:B"]
    code = main(["compare", *args, "--strategies", "replan,replacement", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and [r["strategy"] for r in data["runs"]] == [
        "replan",
        "replacement[handwritten,flat]",
    ]
    assert data["warm_up"] is True and data["verdict"].endswith(".")
    for run in data["runs"]:
        strategy = run["strategy"].split("[")[0]
        assert main(["run", *args, "--strategy", strategy, "--json"]) == 0
        row = json.loads(capsys.readouterr().out)
        assert (run["ticks"], run["replans"], run["replacements"], run["plan_distance"]) == (
            row["ticks"],
            row["replans"],
            row["replacements"],
            row["plan_distance"],
        )


def test_compare_without_faults_says_so(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compare", *ROUTE, "--json"]) == 0
    assert "no faulty action was met" in json.loads(capsys.readouterr().out)["verdict"]


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--strategies", "replan,pray"], "--strategies"),
        (["--table", "nosuch.json"], "nosuch.json"),
        (["--heuristic", "psychic"], "--heuristic"),
        (["--backend", "gpu"], "--backend"),
    ],
)
def test_compare_bad_input_is_exit_2(
    args: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["compare", *ROUTE, *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("selfrepair: error:") and expected in err and err.count("\n") == 1
