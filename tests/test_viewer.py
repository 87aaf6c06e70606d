"""The mission viewer: its payload (from the library, checked against the trace), the page, and
``selfrepair view`` in-process (traces, results databases, bad input)."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from selfrepair.cli import main
from selfrepair.errors import InputError, TraceError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.tolerance import mission_tolerance
from selfrepair.execution.trace import Trace, parse_trace, spec_from_header, trace_lines
from selfrepair.experiment.report import pick_mission
from selfrepair.experiment.store import ResultStore
from selfrepair.experiment.viewer import mission_payload, render_html, wall_runs
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import fault_model
from selfrepair.robots import four_wheel
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze


def mission_trace(strategy: str = "replacement", detection: str = "on-use") -> Trace:
    """A mission whose faults appear late (one transient), are learned on use, and get repaired."""
    route = bundled_routes("narrow-short")[0]
    events = (
        FaultEvent(four_wheel.parse_fault("FL:F"), at=3),
        FaultEvent(four_wheel.parse_fault("RR:B"), at=2, persistence="transient", duration=6),
    )
    spec = MissionSpec(
        load_bundled("narrow-short"),
        route.start,
        route.goal,
        schedule=FaultSchedule(events, detection),
        strategy=strategy,
        seed=3,
    )
    return parse_trace("\n".join(trace_lines(run_mission(spec))), source="mission.jsonl")


@pytest.fixture(scope="module")
def trace() -> Trace:
    return mission_trace()


@pytest.fixture(scope="module")
def payload(trace: Trace) -> dict[str, Any]:
    return mission_payload(trace)


def _pose(data: dict[str, Any]) -> Pose:
    return Pose(data["x"], data["y"], Heading[data["heading"]])


def test_frames_hold_the_pose_after_each_step_with_the_models_heading(
    trace: Trace, payload: dict[str, Any]
) -> None:
    frames = payload["frames"]
    assert len(frames) == len(trace.steps) + 1
    assert _pose(frames[0]["pose"]) == spec_from_header(trace.header).start
    for k, step in enumerate(trace.steps, start=1):
        pose = frames[k]["pose"]
        assert _pose(pose) == step.end
        assert (pose["dx"], pose["dy"]) == step.end.heading.vector
        assert pose["angle"] == 90 * step.end.heading.value


def test_plan_and_steps_are_the_robot_models_segments(
    trace: Trace, payload: dict[str, Any]
) -> None:
    pose = spec_from_header(trace.header).start
    assert len(payload["plan"]) == len(trace.header["initial_plan"])
    for segment, code in zip(payload["plan"], trace.header["initial_plan"], strict=True):
        end, swept, _ = four_wheel.step(pose, four_wheel.parse_action(code))
        assert _pose(segment["from"]) == pose and _pose(segment["to"]) == end
        assert [tuple(c) for c in segment["swept"]] == list(swept)
        pose = end
    for segment, step in zip(payload["steps"], trace.steps, strict=True):
        assert (segment["step"], segment["source"], segment["action"]) == (
            step.step,
            step.source,
            step.action.code,
        )
        assert _pose(segment["from"]) == step.start and _pose(segment["to"]) == step.end
    failed = [s for s in payload["steps"] if s["source"] == "failed-attempt"]
    assert failed and all(s["kind"] == "failed" for s in failed)
    arcs = [s for s in payload["steps"] + payload["plan"] if s["kind"] == "arc"]
    assert all(s["via"] is not None for s in arcs)


def test_true_faults_come_from_the_schedule_and_known_ones_from_the_steps(
    trace: Trace, payload: dict[str, Any]
) -> None:
    spec = spec_from_header(trace.header)
    ticks = Fraction(0)
    for k, frame in enumerate(payload["frames"]):
        true = spec.schedule.active_faults(k, ticks, spec.seed)
        assert frame["true"] == sorted(str(f) for f in true) and frame["tick"] == str(ticks)
        if k < len(trace.steps):
            assert frame["known"] == sorted(str(f) for f in trace.steps[k].known)
            ticks += trace.steps[k].duration
    events = {(e["fault"], e["kind"]): e["frame"] for e in payload["fault_events"]}
    assert events[("FL:F", "appears")] == 3 and events[("RR:B", "appears")] == 2
    assert events[("RR:B", "clears")] == 8  # transient for 6 steps
    # learned on use: known only after a failed attempt, so strictly after it appeared
    assert events[("FL:F", "becomes known")] > 3
    timeline = {row["fault"]: row for row in payload["fault_timeline"]}
    assert timeline["RR:B"]["active"] == [[2, 8]]
    assert timeline["FL:F"]["known"][0][0] == events[("FL:F", "becomes known")]


def test_repairs_carry_their_source_candidate_latency_and_path(
    trace: Trace, payload: dict[str, Any]
) -> None:
    repairs = payload["repairs"]
    assert repairs and len(repairs) == len(trace.repairs)
    for shown, line in zip(repairs, trace.repairs, strict=True):
        assert shown["step"] == line.step and _pose(shown["pose"]) == line.pose
        assert shown["latency_ns"] == line.latency_ns and shown["latency"].endswith("s")
        assert shown["source"] == line.source and shown["actions"] == [
            a.code for a in line.actions
        ]
        pose = line.pose
        for segment, action in zip(shown["path"], line.actions, strict=True):
            assert _pose(segment["from"]) == pose
            pose = four_wheel.step(pose, action)[0]
        for number in shown["executed"]:
            assert trace.steps[number].source == line.source
        if shown["executed"]:
            assert shown["executed"][0] == line.step
        if line.source == "replacement":
            assert f"table candidate index {line.candidate_index}" in shown["how"]
    assert any(r["source"] == "replacement" and r["executed"] for r in repairs)


def test_a_fallback_repair_says_what_found_nothing_before_it() -> None:
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(
        load_bundled("narrow-short"),
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(four_wheel.parse_faults("FL:F,RR:B")),
        options=StrategyOptions(table="generated-agnostic"),
    )
    trace = parse_trace("\n".join(trace_lines(run_mission(spec))))
    repairs = mission_payload(trace)["repairs"]
    fallbacks = [r for r in repairs if r["attempts"] == ["replacement", "replan"]]
    assert fallbacks and all(r["source"] == "replan" for r in fallbacks)
    assert all(r["how"] == "replan from scratch (after replacement found none)" for r in fallbacks)
    direct = [r for r in repairs if r["attempts"] == ["replacement"]]
    assert direct and all(r["how"].startswith("table candidate index ") for r in direct)


def test_lookahead_and_replan_repairs_say_so() -> None:
    for strategy, word in (("lookahead", "lookahead window"), ("replan", "replan")):
        repairs = mission_payload(mission_trace(strategy))["repairs"]
        assert repairs and all(word in r["how"] for r in repairs if r["source"] == strategy)


def test_the_initial_plans_tolerance_is_in_the_payload_per_plan_step(
    trace: Trace, payload: dict[str, Any]
) -> None:
    """The heat strip's data: the initial plan's tolerance, step by step, as the checker finds
    it. On narrow-short r1 (hand-written table, flat) the optimum covers all 240 single-fault
    pairs and 1,385 of the 1,560 pairs with double faults (docs/tolerance.md)."""
    spec = spec_from_header(trace.header)
    shown = payload["tolerance"]
    _, expected = mission_tolerance(spec, fault_model(spec.domain, 1))
    assert expected is not None and shown == expected.to_json(spec.domain)
    assert [s["action"] for s in shown["steps"]] == [seg["action"] for seg in payload["plan"]]
    assert [s["pose"][:2] for s in shown["steps"]] == [
        [seg["from"]["x"], seg["from"]["y"]] for seg in payload["plan"]
    ]
    assert (shown["covered"], shown["pairs"], shown["tolerant"]) == (240, 240, True)
    double = mission_payload(trace, tolerance=2)["tolerance"]
    assert (double["model"], double["covered"], double["pairs"]) == ("k=2", 1385, 1560)
    assert any(s["uncovered"] for s in double["steps"])
    assert mission_payload(trace, tolerance=0)["tolerance"] is None
    assert mission_payload(mission_trace("replan"))["tolerance"] is None


def test_wall_runs_rebuild_the_maze() -> None:
    rng = np.random.default_rng(4)
    maze = Maze(rng.random((7, 11)) < 0.4)
    walls = np.zeros((7, 11), dtype=bool)
    for x, y, length in wall_runs(maze):
        assert not walls[y, x : x + length].any()
        walls[y, x : x + length] = True
    assert (walls == maze.walls).all()


def _page_data(page: str) -> Any:
    match = re.search(r'<script type="application/json" id="mission-data">(.*?)</script>', page)
    assert match is not None
    return json.loads(match.group(1))


def test_the_page_is_self_contained_and_carries_the_payload(payload: dict[str, Any]) -> None:
    page = render_html(payload)
    assert _page_data(page) == payload
    assert "default-src 'none'" in page  # the browser may load nothing at all
    assert not re.search(r"<(link|script|img|iframe)[^>]*(src|href)=\"(?!data:)", page)
    assert re.findall(r"https?://[^\s\"']+", page) == ["http://www.w3.org/2000/svg"] * 3
    assert "{{" not in page


def test_text_from_the_trace_cannot_break_out_of_the_page(trace: Trace) -> None:
    header = dict(trace.header)
    header["maze"] = {**header["maze"], "name": "</script><script>alert(1)</script>&"}
    summary = {**(trace.summary or {}), "odd": float("nan")}  # json.loads accepts NaN
    evil = replace(trace, header=header, summary=summary)
    page = render_html(mission_payload(evil))
    assert page.count("</script>") == 2 and "<script>alert" not in page
    data = _page_data(page)
    assert data["maze"]["name"] == header["maze"]["name"]
    assert data["summary"]["odd"] == "nan"  # JSON.parse in the page would reject NaN


def test_old_traces_without_repair_lines_are_viewed_with_a_note(trace: Trace) -> None:
    old = replace(trace, repairs=(), repair_lines=())
    data = mission_payload(old)
    assert data["repairs"] == [] and data["has_repair_lines"] is False


def test_limits_and_traces_that_do_not_replay_are_refused(trace: Trace) -> None:
    with pytest.raises(TraceError, match="--max-steps"):
        mission_payload(trace, max_steps=len(trace.steps) - 1)
    assert mission_payload(trace, max_steps=len(trace.steps))["frames"]
    lines = trace_lines(run_mission(spec_from_header(trace.header)))
    step = next(i for i, line in enumerate(lines) if '"type": "step"' in line)
    data = json.loads(lines[step])
    data["to"] = [99, 99, "N"]
    lines[step] = json.dumps(data)
    with pytest.raises(TraceError, match="does not replay"):
        mission_payload(parse_trace("\n".join(lines)))


def test_pick_mission_names_the_database_and_the_ambiguity() -> None:
    rows = [{"key": "abc1"}, {"key": "abc2"}, {"key": "def0"}]
    assert pick_mission(rows, "abc1", "db")["key"] == "abc1"
    with pytest.raises(InputError, match=r"^db: .*exactly one stored mission.*2 match 'abc'.*more"):
        pick_mission(rows, "abc", "db")
    with pytest.raises(InputError, match="0 match 'zz'") as caught:
        pick_mission(rows, "zz", "db")
    assert "--" not in str(caught.value)  # the library names no command-line flag
    with pytest.raises(InputError, match="0 match ''"):
        pick_mission(rows, "", "db")


# --- the command ----------------------------------------------------------------------------------


def test_view_a_trace(tmp_path: Path, trace: Trace, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "t.jsonl"
    path.write_text("\n".join(trace_lines(run_mission(spec_from_header(trace.header)))) + "\n")
    out = tmp_path / "mission.html"
    assert main(["view", str(path), "-o", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    data = _page_data(out.read_text(encoding="utf-8"))
    assert data["origin"] == {"kind": "trace", "source": str(path)}
    assert len(data["frames"]) == len(trace.steps) + 1
    assert data["tolerance"]["model"] == "k=1"  # the heat strip's default
    assert 'id="tolerance-strip"' in out.read_text(encoding="utf-8")
    assert main(["view", str(path), "-o", str(out), "--tolerance", "2"]) == 0
    assert _page_data(out.read_text(encoding="utf-8"))["tolerance"]["model"] == "k=2"
    assert main(["view", str(path), "-o", str(out), "--tolerance", "0"]) == 0
    assert _page_data(out.read_text(encoding="utf-8"))["tolerance"] is None


def _one_error(capsys: pytest.CaptureFixture[str], *words: str) -> None:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("selfrepair: error:"), err
    for word in words:
        assert word in err, err


def test_view_refuses_bad_input_with_one_line(
    tmp_path: Path, trace: Trace, capsys: pytest.CaptureFixture[str]
) -> None:
    out = str(tmp_path / "m.html")
    assert main(["view", str(tmp_path / "missing.jsonl"), "-o", out]) == 2
    _one_error(capsys, "missing.jsonl", "expected a trace file")
    text = tmp_path / "notes.txt"
    text.write_text("hello\n")
    assert main(["view", str(text), "-o", out]) == 2
    _one_error(capsys, "notes.txt", "JSON")
    text.write_text('{"type": "step"}\n')
    assert main(["view", str(text), "-o", out]) == 2
    _one_error(capsys, "notes.txt", "header")
    assert main(["view", str(tmp_path), "-o", out]) == 2
    _one_error(capsys, "expected a trace file")
    good = tmp_path / "t.jsonl"
    good.write_text("\n".join(trace_lines(run_mission(spec_from_header(trace.header)))))
    assert main(["view", str(good), "-o", str(tmp_path / "m.png")]) == 2
    _one_error(capsys, ".html")
    assert main(["view", str(good), "-o", out, "--key", "abc"]) == 2
    _one_error(capsys, "--key", "not one")
    assert main(["view", str(good), "-o", str(tmp_path / "no" / "such" / "m.html")]) == 2
    _one_error(capsys)
    assert not Path(out).exists()


TINY = """\
name = "tiny-view"
seed = 5
[[mazes]]
bundled = "narrow-short"
[faults]
sets = ["FL:F"]
[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
"""


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("results")
    config = folder / "tiny.toml"
    config.write_text(TINY)
    db = folder / "r.sqlite"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    return db


def test_view_a_stored_mission_by_key_prefix(
    tmp_path: Path, results: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with ResultStore(results, read_only=True) as store:
        rows = store.rows()
    row = max(rows, key=lambda r: int(r["replacements"] or 0))
    key = str(row["key"])
    out = tmp_path / "stored.html"
    before = results.read_bytes()
    assert main(["view", str(results), "--key", key[:10], "-o", str(out)]) == 0
    assert results.read_bytes() == before  # viewing never changes the database
    data = _page_data(out.read_text(encoding="utf-8"))
    assert data["origin"]["kind"] == "results" and data["origin"]["key"] == key
    assert data["origin"]["agrees"] is True
    assert len(data["frames"]) == int(row["steps"]) + 1
    assert len([r for r in data["repairs"] if r["source"] == "replacement"]) == row["replacements"]
    capsys.readouterr()
    assert main(["view", str(results), "--key", "zzzz", "-o", str(out)]) == 2
    _one_error(capsys, "r.sqlite", "key prefix", "0 match 'zzzz'")
    assert main(["view", str(results), "--key", "", "-o", str(out)]) == 2
    _one_error(capsys, "--key")
    assert main(["view", str(results), "-o", str(out)]) == 2
    _one_error(capsys, "choose one with --key")
