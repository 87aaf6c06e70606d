"""What new users hit (issue 29): commands on a plug-in robot and right after ``make demo``.

The plug-in robot is ``tests/data/robots/hopper.py``: its ``hop`` leaves the 3x3 cells around
the robot (the compiled planner cannot take it) and selfrepair ships no table for it.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from extras import need
from selfrepair.cli import main
from selfrepair.robots.registry import domain_names, load_plugin

HOPPER = Path(__file__).parent / "data" / "robots" / "hopper.py"
P = ["--plugin", str(HOPPER)]
HOP_ROUTE = ["narrow-short", "--domain", "hopper", "--start", "7,13,W", "--goal", "1,8"]
ROUTE = ["narrow-short", "--start", "1,1,E", "--goal", "13,13"]


@pytest.fixture(autouse=True)
def _hopper() -> None:
    load_plugin(HOPPER)


def _no_pddl(monkeypatch: pytest.MonkeyPatch) -> None:
    """This installation as ``make demo`` leaves it: no ``pddl`` extra."""
    from selfrepair.baselines import adapt

    monkeypatch.setattr(adapt, "lpg_available", lambda: False)


# --- 1. compare runs every strategy that can run here ---------------------------------------


def test_compare_without_the_pddl_extra_skips_lpg_adapt_and_says_why(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    _no_pddl(monkeypatch)
    assert main(["compare", *ROUTE, "--faults", "FL:F", "--no-warm-up"]) == 0
    out = capsys.readouterr().out
    assert "skipped lpg-adapt: the lpg-adapt strategy needs the pddl extra" in out
    assert "dstar-lite" in out and "replacement[handwritten,flat]" in out


def test_compare_on_a_plug_in_robot_runs_all_but_lpg_adapt(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main([*P, "compare", *HOP_ROUTE, "--faults", "HOP", "--no-warm-up", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [r["strategy"].split("[")[0] for r in data["runs"]] == [
        "replan",
        "replacement",
        "lookahead",
        "dstar-lite",
    ]
    assert [s["strategy"] for s in data["skipped"]] == ["lpg-adapt"]
    assert "four-wheel robot only" in data["skipped"][0]["reason"]


def test_compare_asked_for_a_strategy_that_cannot_run_is_exit_2(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = [*P, "compare", *HOP_ROUTE, "--faults", "HOP", "--strategies", "replan,lpg-adapt"]
    assert main(args) == 2
    assert "lpg-adapt" in capsys.readouterr().err


# --- 5. a robot without a hand-written table gets a generated one --------------------------


def test_run_on_a_plug_in_robot_needs_no_table_option(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*P, "run", *HOP_ROUTE, "--faults", "HOP", "--no-warm-up"]) == 0
    out = capsys.readouterr().out
    assert "table: generated from the hopper robot model" in out
    assert "replacements" in out


def test_the_four_wheel_robot_still_gets_the_hand_written_table(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", *ROUTE, "--faults", "FL:F", "--no-warm-up"]) == 0
    assert "table: handwritten, the four-wheel robot's bundled table" in capsys.readouterr().out
    assert main(["run", *ROUTE, "--faults", "FL:F", "--no-warm-up", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["table"] == "handwritten"
    assert main(["run", *ROUTE, "--table", "generated-indexed", "--no-warm-up"]) == 0
    assert "table:" not in capsys.readouterr().out.split("\n┏")[0]


def test_the_three_action_robot_gets_its_bundled_table(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["run", "narrow-short", "--domain", "three-action", "--start", "1,1,E"]
    assert main([*args, "--goal", "13,13", "--faults", "R", "--no-warm-up", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["table"] == "three-action"


# --- 10. the compare verdict names what it names -------------------------------------------


def test_verdict_ties_are_ties(capsys: pytest.CaptureFixture[str]) -> None:
    args = [*P, "compare", *HOP_ROUTE, "--faults", "HOP", "--strategies", "replan,replacement"]
    assert main([*args, "--json", "--no-warm-up"]) == 0
    verdict = json.loads(capsys.readouterr().out)["verdict"]
    assert "fewest ticks: a tie at 20 (every strategy)" in verdict


def test_verdict_names_the_most_as_such_and_uses_the_motion_distance(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # Rear-left wheel cannot go forward: the hand-written table swaps each blocked move for a
    # slower one of the same motion, so the path is kept (motion distance 0) while the plain
    # plan distance ties with replanning's (54).
    args = ["compare", *ROUTE, "--faults", "RL:F", "--strategies", "replan,replacement"]
    assert main([*args, "--json", "--no-warm-up"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [r["plan_distance"] for r in data["runs"]] == [54, 54]
    assert [r["plan_distance_motion"] for r in data["runs"]] == [46, 0]
    verdict = data["verdict"]
    assert "fewest ticks: replan (51), most: replacement[handwritten,flat] (76)" in verdict
    assert "closest to the initial plan by motion: replacement[handwritten,flat] (distance 0)" in (
        verdict
    )
    assert "faster than the slowest, " in verdict


# --- 4. the backend that ran ----------------------------------------------------------------


def test_explicit_numba_on_a_robot_the_kernels_cannot_take_is_refused(
    capsys: pytest.CaptureFixture[str],
) -> None:
    need("numba", "fast")
    for command in (["run"], ["plan"]):
        args = [*P, *command, *HOP_ROUTE, "--faults", "HOP", "--backend", "numba"]
        assert main(args) == 2
        err = capsys.readouterr().err
        assert "hop facing N leaves the 3x3 cells" in err and err.count("\n") == 1


def test_auto_falls_back_and_the_row_says_which_backend_ran(
    capsys: pytest.CaptureFixture[str],
) -> None:
    need("numba", "fast")
    assert main([*P, "run", *HOP_ROUTE, "--faults", "HOP", "--no-warm-up", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert (row["backend"], row["backend_ran"]) == ("auto", "python")
    assert row["kernel_load_ms"] == 0  # no kernel is loaded for a robot they cannot take
    assert main(["run", *ROUTE, "--no-warm-up", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert (row["backend"], row["backend_ran"]) == ("auto", "numba")
    assert main(["run", *ROUTE, "--no-warm-up", "--json", "--backend", "python"]) == 0
    assert json.loads(capsys.readouterr().out)["backend_ran"] == "python"


def test_kernel_refusal_names_the_action() -> None:
    from selfrepair.robots.registry import get_domain
    from selfrepair.search.backend import kernel_refusal

    assert kernel_refusal(get_domain("four-wheel")) is None
    assert kernel_refusal(get_domain("three-action")) is None
    expected = "action hop facing N leaves the 3x3 cells around the robot"
    assert kernel_refusal(get_domain("hopper")) == expected


# --- 8. every command takes the robot; help names the robots --------------------------------


def test_plan_and_actions_take_a_domain(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*P, "plan", *HOP_ROUTE, "--faults", "HOP", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "hop" not in data["actions"]
    assert set(data["actions"]) <= {"step", "back", "left", "right"}
    assert main([*P, "plan", *HOP_ROUTE, "--faults", "FL:F"]) == 2
    assert "--faults" in capsys.readouterr().err
    assert main([*P, "actions", "--domain", "hopper", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert rows[1] == {
        "action": "hop", "motion": "hop", "level": 0, "duration": "1", "end": "0,-2,N",
        "cells": "0,0 0,-1 0,-2",
    }  # fmt: skip
    assert main(["actions", "--domain", "omni-wheel"]) == 2
    assert "--domain" in capsys.readouterr().err


def test_pddl_refuses_another_robot_clearly(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main([*P, "pddl", *HOP_ROUTE, "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "--domain: the PDDL export encodes the four-wheel robot only" in err
    assert not list(tmp_path.iterdir())


def test_help_lists_the_registered_robots_and_their_fault_examples(
    capsys: pytest.CaptureFixture[str],
) -> None:
    for command in (["run"], ["plan"], ["table", "generate"]):
        assert main([*P, *command, "--help"]) == 0
        # help wraps at hyphens too ("four-" at a line's end, "wheel" on the next)
        out = " ".join(capsys.readouterr().out.split()).replace("- ", "-")
        # every registered robot, in the registry's order (other tests may register more)
        assert ", ".join(domain_names()) in out, command
        assert {"four-wheel", "hopper", "three-action"} <= set(domain_names())
    assert main([*P, "compare", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    for example in ("FL:F,RR:B (four-wheel)", "STEP,RIGHT (hopper)", "F,R (three-action)"):
        assert example in out


# --- 3. a trace of a plug-in robot stands alone -------------------------------------------


def _cli(*argv: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """The command line in a fresh process (a process keeps the robot it loaded first)."""
    code = "import sys\nfrom selfrepair.cli import main\nsys.exit(main(sys.argv[1:]))\n"
    return subprocess.run(
        [sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=cwd, check=False
    )


def test_replay_and_view_load_the_plug_in_the_trace_records(tmp_path: Path) -> None:
    robot = tmp_path / "robot.py"
    shutil.copy(HOPPER, robot)
    trace = tmp_path / "t.jsonl"
    route = [*HOP_ROUTE, "--faults", "HOP", "--no-warm-up", "--trace", str(trace)]
    assert _cli("--plugin", str(robot), "run", *route, cwd=tmp_path).returncode == 0
    header = json.loads(trace.read_text().splitlines()[0])
    assert header["plugin"] == {
        "path": str(robot.resolve()),
        "sha256": hashlib.sha256(robot.read_bytes()).hexdigest(),
    }
    done = _cli("replay", str(trace), cwd=tmp_path)
    assert done.returncode == 0 and "ok: all 20 steps hold" in done.stdout, done.stderr
    assert _cli("view", str(trace), "-o", str(tmp_path / "t.html"), cwd=tmp_path).returncode == 0
    back = '"back": (-1, 0, Fraction({}))'
    robot.write_text(robot.read_text().replace(back.format(2), back.format(3)))
    for command in (["replay", str(trace)], ["view", str(trace), "-o", str(tmp_path / "u.html")]):
        done = _cli(*command, cwd=tmp_path)
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert "changed since the trace was written" in done.stderr
        assert "pass --plugin FILE with the hopper robot" in done.stderr
    robot.unlink()
    done = _cli("replay", str(trace), cwd=tmp_path)
    assert done.returncode == 2 and "cannot be read here" in done.stderr
    assert _cli("--plugin", str(HOPPER), "replay", str(trace), cwd=tmp_path).returncode == 0


def test_a_trace_of_another_version_of_a_loaded_robot_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = tmp_path / "t.jsonl"
    route = [*HOP_ROUTE, "--faults", "HOP", "--no-warm-up", "--trace", str(trace)]
    assert main([*P, "run", *route]) == 0
    lines = trace.read_text().splitlines()
    header = json.loads(lines[0])
    header["plugin"]["sha256"] = "0" * 64
    trace.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    capsys.readouterr()
    assert main(["replay", str(trace)]) == 2
    assert "but this process loaded 'hopper'" in capsys.readouterr().err


# --- 2. editing a robot given with --plugin never reuses its old results -----------------

EXPERIMENT = """\
name = "hopper"
domain = "hopper"
seed = 3
[[mazes]]
bundled = "narrow-short"
[faults]
sets = "singles"
[[strategies]]
name = "replan"
"""


def test_the_robot_file_given_with_plugin_enters_the_mission_keys(tmp_path: Path) -> None:
    robot = tmp_path / "robot.py"
    shutil.copy(HOPPER, robot)
    config = tmp_path / "hopper.toml"
    config.write_text(EXPERIMENT)
    db = tmp_path / "r.sqlite"
    args = ["--plugin", str(robot), "experiment", str(config), "--db", str(db), "--jobs", "1"]
    first = _cli(*args, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    assert "20 missions, 0 already stored, 20 run" in first.stdout
    # 10. the findings that do not apply to this experiment are left out, one line each
    out = " ".join(first.stdout.split())
    assert "Nothing to compare" not in out and "INCONCLUSIVE" not in out
    assert "Finding 2 left out: it compares a replacement variant at clearance weight 0" in out
    for number in ("3", "4"):
        assert (
            f"Finding {number} left out: it is about the paper's hand-written table, which is "
            "the four-wheel robot's; this experiment's robot is hopper." in out
        )
    again = _cli(*args, cwd=tmp_path)
    assert "20 missions, 20 already stored, 0 run" in again.stdout, again.stdout
    back = '"back": (-1, 0, Fraction({}))'
    robot.write_text(robot.read_text().replace(back.format(2), back.format(3)))
    edited = _cli(*args, cwd=tmp_path)
    assert edited.returncode == 0, edited.stderr
    assert "20 missions, 0 already stored, 20 run" in edited.stdout, edited.stdout


# --- 9. table check and coverage on the generator's own tables ------------------------------


def test_table_check_does_not_warn_about_the_generators_empty_entries(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    table = tmp_path / "indexed.json"
    args = ["table", "generate", "--domain", "hopper", "--shape", "fault-indexed", "-o"]
    assert main([*P, *args, str(table)]) == 0
    capsys.readouterr()
    assert main([*P, "table", "check", str(table)]) == 0
    out = capsys.readouterr().out
    assert "warning:" not in out and "0 errors, 0 warnings" in out
    assert "(5 empty fault-indexed entries mark an action without a replacement" in out


def test_table_coverage_says_when_uncovered_pairs_need_longer_sub_plans(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    table = tmp_path / "short.json"
    args = ["table", "generate", "--domain", "hopper", "--shape", "fault-indexed"]
    assert main([*P, *args, "--max-length", "3", "-o", str(table)]) == 0
    capsys.readouterr()
    assert main([*P, "table", "coverage", str(table), "--no-walls"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert (
        "6 of the 21 replaceable pairs (6 uncovered) need longer sub-plans: 5 to 6 actions, "
        "more than the table's 3; regenerate with --max-length 6." in out
    )
    longer = tmp_path / "long.json"
    assert main([*P, *args, "--max-length", "6", "-o", str(longer)]) == 0
    capsys.readouterr()
    assert main([*P, "table", "coverage", str(longer), "--no-walls", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "longer_needed" not in data and data["totals"]["coverage"] == 1
