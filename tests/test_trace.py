"""Traces: the JSON Lines format, reading it back, and replay."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from selfrepair.errors import TraceError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.execution.trace import (
    parse_trace,
    read_trace,
    replay,
    spec_from_header,
    write_trace,
)
from selfrepair.robots import four_wheel
from selfrepair.world.bundled import bundled_routes, load_bundled


def _mission(detection: str = "now", strategy: str = "replacement") -> MissionResult:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[1]
    events = (
        FaultEvent(four_wheel.parse_fault("FL:F"), at=2),
        FaultEvent(
            four_wheel.parse_fault("RR:B"), at=1, persistence="intermittent", probability=0.4
        ),
    )
    return run_mission(
        MissionSpec(
            maze,
            route.start,
            route.goal,
            schedule=FaultSchedule(events, detection),
            strategy=strategy,
            seed=11,
        )
    )


@pytest.fixture
def trace_file(tmp_path: Path) -> Path:
    path = tmp_path / "mission.jsonl"
    write_trace(_mission("on-use"), path)
    return path


def test_trace_lines_have_the_documented_fields(trace_file: Path) -> None:
    lines = [json.loads(t) for t in trace_file.read_text().splitlines()]
    header, body, summary = lines[0], lines[1:-1], lines[-1]
    steps = [line for line in body if line["type"] == "step"]
    assert {line["type"] for line in body} == {"step", "repair"}
    assert header["type"] == "header" and header["format"] == "selfrepair-trace"
    assert header["maze"]["name"] == "narrow-short" and header["maze"]["rows"][0].startswith("#")
    assert header["seed"] == 11 and header["strategy"] == "replacement"
    assert header["schedule"]["detection"] == "on-use"
    for number, step in enumerate(steps):
        assert step["step"] == number
        assert set(step) == {"type", "step", "action", "from", "to", "duration", "source", "known"}
        assert isinstance(step["from"][2], str) and len(step["from"]) == 3
    assert any(s["source"] == "failed-attempt" for s in steps)
    assert summary["type"] == "summary" and summary["steps"] == len(steps)


@pytest.mark.parametrize("detection", ["now", "on-use"])
@pytest.mark.parametrize("strategy", ["replan", "replacement", "lookahead"])
def test_traces_replay(tmp_path: Path, detection: str, strategy: str) -> None:
    path = tmp_path / "t.jsonl"
    write_trace(_mission(detection, strategy), path)
    report = replay(path)
    assert report.ok and report.steps_checked == len(read_trace(path).steps)


def test_the_header_runs_the_same_mission_again(trace_file: Path) -> None:
    trace = read_trace(trace_file)
    again = run_mission(spec_from_header(trace.header))
    assert tuple(s.action for s in again.steps) == tuple(s.action for s in trace.steps)
    assert tuple(s.source for s in again.steps) == tuple(s.source for s in trace.steps)


def _step_index(path: Path, number: int) -> int:
    """The index (from 0) of step ``number``'s line; repair lines sit between step lines."""
    lines = [json.loads(t) for t in path.read_text().splitlines()]
    return next(i for i, d in enumerate(lines) if d["type"] == "step" and d["step"] == number)


def _edit(path: Path, index: int, **changes: object) -> None:
    lines = path.read_text().splitlines()
    data = json.loads(lines[index])
    data.update(changes)
    lines[index] = json.dumps(data)
    path.write_text("\n".join(lines) + "\n")


def test_replay_names_the_first_step_that_does_not_hold(trace_file: Path) -> None:
    index = _step_index(trace_file, 3)
    _edit(trace_file, index, to=[0, 0, "N"])
    report = replay(trace_file)
    assert not report.ok and report.first_bad_step == 3 and report.line == index + 1


def test_replay_rejects_a_known_faulty_action(trace_file: Path) -> None:
    trace = read_trace(trace_file)
    index = next(i for i, s in enumerate(trace.steps) if s.known and s.source != "failed-attempt")
    step = trace.steps[index]
    faulty = next(
        a
        for a in four_wheel.ACTIONS
        if not four_wheel.available(a, step.known) and four_wheel.step(step.start, a)[0] == step.end
    )
    _edit(trace_file, _step_index(trace_file, index), action=faulty.code)
    report = replay(trace_file)
    assert not report.ok and report.first_bad_step == index
    assert "known-faulty" in report.reason or "true faults" in report.reason


def test_replay_checks_the_summary(trace_file: Path) -> None:
    lines = trace_file.read_text().splitlines()
    _edit(trace_file, len(lines) - 1, steps=3)
    report = replay(trace_file)
    assert not report.ok and report.first_bad_step is None and "summary" in str(report)


def test_malformed_traces_raise_with_line(tmp_path: Path, trace_file: Path) -> None:
    lines = trace_file.read_text().splitlines()
    bad = tmp_path / "bad.jsonl"
    bad.write_text("\n".join([lines[0], lines[1], "{not json", *lines[2:]]))
    with pytest.raises(TraceError) as err:
        read_trace(bad)
    assert err.value.line == 3 and str(bad) in str(err.value)
    bad.write_text(lines[1])
    with pytest.raises(TraceError, match="header"):
        read_trace(bad)
    with pytest.raises(TraceError, match="source"):
        parse_trace("\n".join([lines[0], lines[1].replace('"plan"', '"magic"')]))
    with pytest.raises(TraceError, match="cannot read"):
        read_trace(tmp_path / "missing.jsonl")


def test_a_table_object_is_named_so_the_header_can_be_run_again(tmp_path: Path) -> None:
    from selfrepair.repair.strategies import StrategyOptions
    from selfrepair.tables.fileformat import bundled_table

    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(four_wheel.parse_faults("FL:F")),
        options=StrategyOptions(table=bundled_table("handwritten")),
    )
    path = tmp_path / "t.jsonl"
    write_trace(run_mission(spec), path)
    header = read_trace(path).header
    assert header["options"]["table"] == "handwritten"
    assert run_mission(spec_from_header(header)).reached


@pytest.mark.parametrize("field", ["options", "planner", "schedule"])
def test_header_field_of_the_wrong_type_is_a_trace_error(trace_file: Path, field: str) -> None:
    lines = trace_file.read_text().splitlines()
    header = json.loads(lines[0])
    header[field] = [1]
    with pytest.raises(TraceError, match="header"):
        replay(parse_trace("\n".join([json.dumps(header), *lines[1:]])))


def test_replay_checks_known_faults_under_detection_now(tmp_path: Path) -> None:
    path = tmp_path / "now.jsonl"
    write_trace(_mission("now"), path)
    assert replay(path).ok
    _edit(path, _step_index(path, 4), known=["FL:F", "RL:F"])  # a claim never sensed
    report = replay(path)
    assert not report.ok and report.first_bad_step == 4 and "senses" in report.reason
