"""Repair lines in traces: what is written, where, how it reads back, and what is refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from selfrepair.errors import TraceError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.execution.trace import parse_trace, replay, trace_lines
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots import four_wheel
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze


def _mission(strategy: str = "replacement", detection: str = "now") -> MissionResult:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[1]
    events = (
        FaultEvent(four_wheel.parse_fault("FL:F"), at=2),
        FaultEvent(
            four_wheel.parse_fault("RR:B"), at=1, persistence="intermittent", probability=0.4
        ),
    )
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule(events, detection),
        strategy=strategy,
        options=StrategyOptions(window=2),
        seed=11,
    )
    return run_mission(spec)


def _stuck_mission() -> MissionResult:
    """A corridor where every wheel command but S fails from step 1 on: the robot is stuck (at
    once: no waits, which would interleave wait steps and stuck repairs)."""
    all_moves = four_wheel.parse_faults("FL:F,FR:F,RL:F,RR:F,FL:B,FR:B,RL:B,RR:B")
    spec = MissionSpec(
        Maze(np.zeros((1, 6), dtype=bool), name="corridor"),
        Pose(0, 0, Heading.E),
        (5, 0),
        schedule=FaultSchedule.permanent(all_moves, at=1),
        options=StrategyOptions(max_wait=0),
    )
    return run_mission(spec)


def _objects(result: MissionResult) -> list[dict[str, object]]:
    return [json.loads(line) for line in trace_lines(result)]


@pytest.mark.parametrize("strategy", ["replan", "replacement", "lookahead"])
def test_every_repair_is_written_just_before_the_step_it_takes_effect_at(strategy: str) -> None:
    result = _mission(strategy)
    assert result.repairs
    objects = _objects(result)
    repairs = [o for o in objects if o["type"] == "repair"]
    assert len(repairs) == len(result.repairs)
    for index, obj in enumerate(objects):
        if obj["type"] == "repair":
            after = objects[index + 1]
            assert after["type"] in ("repair", "step", "summary")
            if after["type"] == "step":
                assert after["step"] == obj["step"]
    for obj, record in zip(repairs, result.repairs, strict=True):
        assert obj == {
            "type": "repair",
            "step": record.step,
            "pose": [record.pose.x, record.pose.y, record.pose.heading.name],
            "action": None if record.action is None else record.action.code,
            "status": record.repair.status,
            "source": record.repair.source,
            "attempts": list(record.repair.attempts),
            "actions": [a.code for a in record.repair.actions],
            "consumed": record.repair.consumed,
            "candidate_index": record.repair.candidate_index,
            "depth": record.repair.depth,
            "latency_ns": record.latency_ns,
        }


def test_parse_trace_exposes_the_repairs() -> None:
    result = _mission("lookahead")
    trace = parse_trace("\n".join(trace_lines(result)))
    assert len(trace.repairs) == len(result.repairs) == len(trace.repair_lines)
    for parsed, record in zip(trace.repairs, result.repairs, strict=True):
        assert (parsed.step, parsed.pose, parsed.action) == (
            record.step,
            record.pose,
            record.action,
        )
        assert parsed.actions == record.repair.actions
        assert (parsed.status, parsed.source, parsed.attempts) == (
            record.repair.status,
            record.repair.source,
            record.repair.attempts,
        )
        assert parsed.latency_ns == record.latency_ns
    assert replay(trace).ok


def test_a_table_replacement_names_the_candidate_it_used() -> None:
    result = _mission("replacement")
    table = StrategyOptions().resolved_table()
    hits = [r for r in result.repairs if r.repair.source == "replacement"]
    assert hits
    for record in hits:
        known = result.steps[record.step].known
        assert record.action is not None and record.repair.candidate_index is not None
        candidates = table.candidates(record.action, known)
        assert candidates[record.repair.candidate_index] == record.repair.actions
    others = [r for r in result.repairs if r.repair.source != "replacement"]
    assert all(r.repair.candidate_index is None for r in others)


def test_traces_without_repair_lines_still_parse_and_replay() -> None:
    lines = [
        line for line in trace_lines(_mission("replacement")) if '"type": "repair"' not in line
    ]
    trace = parse_trace("\n".join(lines))
    assert trace.repairs == () and trace.steps and replay(trace).ok


def test_a_repair_that_ends_the_mission_comes_after_the_last_step() -> None:
    result = _stuck_mission()
    assert result.status == "stuck"
    objects = _objects(result)
    assert [o["type"] for o in objects] == ["header", "step", "repair", "summary"]
    assert objects[2]["status"] == "stuck" and objects[2]["actions"] == []
    trace = parse_trace("\n".join(trace_lines(result)))
    assert trace.repairs[0].status == "stuck" and trace.repair_lines == (3,)
    assert replay(trace).ok
    text = trace_lines(result)
    text[-1] = text[-1].replace('"steps": 1', '"steps": 7')
    report = replay(parse_trace("\n".join(text)))
    assert not report.ok and report.line == 4  # the summary's own line, past the repair line


def _with_repair_changed(**changes: object) -> tuple[str, int]:
    lines = trace_lines(_mission("replacement"))
    index = next(i for i, line in enumerate(lines) if '"type": "repair"' in line)
    data = json.loads(lines[index])
    for key, value in changes.items():
        if value is KeyError:
            del data[key]
        else:
            data[key] = value
    lines[index] = json.dumps(data)
    return "\n".join(lines), index + 1


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"step": "3"}, "'step' to be an integer"),
        ({"step": True}, "'step' to be an integer"),
        ({"step": 999}, "expected a repair for step"),
        ({"pose": [1, 2]}, "'pose'"),
        ({"action": "FFFX"}, "bad action"),
        ({"action": 7}, "'action' to be a string"),
        ({"status": "fixed"}, "'status' in repaired, stuck, budget_exhausted"),
        ({"source": "plan"}, "'source' in replacement, lookahead, replan"),
        ({"attempts": "replacement"}, "'attempts' to be a list"),
        ({"actions": ["FFFF", 3]}, "'actions' to be a list of strings"),
        ({"consumed": -1}, "'consumed' to be an integer >= 0"),
        ({"candidate_index": 1.5}, "'candidate_index' to be an integer"),
        ({"depth": "0"}, "'depth' to be an integer"),
        ({"latency_ns": None}, "'latency_ns' to be an integer"),
        ({"latency_ns": KeyError}, "key 'latency_ns'"),
    ],
)
def test_bad_repair_lines_raise_naming_the_line(changes: dict[str, object], message: str) -> None:
    text, line = _with_repair_changed(**changes)
    with pytest.raises(TraceError, match=message) as err:
        parse_trace(text, source="t.jsonl")
    assert err.value.line == line and "t.jsonl" in str(err.value)
