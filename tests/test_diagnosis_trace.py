"""Hidden-fault traces record what the robot observed and believed after each step (issue 24
item 6, trace version 2), and replay re-derives the belief from the readings and checks it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from selfrepair.diagnosis import ObservationModel
from selfrepair.diagnosis.cooperative import Observer, SensingRange
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.execution.trace import parse_trace, read_trace, replay, trace_lines, write_trace
from selfrepair.execution.traceobserve import spec_model
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.bundled import bundled_routes, load_bundled

TEAM = tuple(Observer(f"t{i}", 0.05, SensingRange(3)) for i in (1, 2))


def _result(
    strategy: str = "active-diagnosis",
    noise: float = 0.05,
    observers: tuple[Observer, ...] = TEAM,
    faults: str = "FL:F",
) -> MissionResult:
    maze = load_bundled("narrow-long")
    route = bundled_routes("narrow-long")[0]
    schedule = FaultSchedule.permanent(FOUR_WHEEL.parse_faults(faults), detection=Detection.HIDDEN)
    spec = MissionSpec(
        maze, route.start, route.goal, schedule=schedule, strategy=strategy, seed=3,
        observation=ObservationModel(noise), observers=observers,
    )  # fmt: skip
    return run_mission(spec)


def _lines(result: MissionResult) -> list[dict[str, object]]:
    return [json.loads(line) for line in trace_lines(result)]


def test_every_step_records_its_readings_and_the_belief() -> None:
    result = _result()
    lines = _lines(result)
    header = lines[0]
    assert header["version"] == 2
    hidden = header["hidden"]
    assert isinstance(hidden, dict)
    model = spec_model(result.spec)
    assert hidden["hypotheses"][0] == "none" and len(hidden["hypotheses"]) == model.size == 79
    assert sorted(i for c in hidden["classes"] for i in c) == list(range(79))
    steps = [line for line in lines if line["type"] == "step"]
    assert len(steps) == len(result.steps)
    for line, belief in zip(steps, result.beliefs, strict=True):
        assert int(str(line["belief"]), 16) == belief
        assert len(str(line["belief"])) <= 20  # a bit set of 79 hypotheses, never their names
        assert isinstance(line["best"], int) and isinstance(line["surprise"], bool)
    # the teammates' readings are there, named as in the header
    names = {str(seen[0]) for line in steps for seen in line.get("seen", [])}  # type: ignore[attr-defined]
    assert names == {"t1", "t2"}
    # FL:F stalls the front-left wheel: a surprise comes, the hypotheses shrink, and the most
    # probable class at the end holds the truth
    assert any(line["surprise"] for line in steps)
    alive = [bin(int(str(line["belief"]), 16)).count("1") for line in steps]
    assert alive[0] <= 79 and alive[-1] < alive[0] and alive == sorted(alive, reverse=True)
    truth = model.sets.index(FOUR_WHEEL.parse_faults("FL:F"))
    assert truth in hidden["classes"][int(str(steps[-1]["best"]))]


@pytest.mark.parametrize("strategy", ["active-diagnosis", "diagnose", "trial-and-error", "oracle"])
def test_hidden_fault_traces_replay_with_their_observations(
    tmp_path: Path, strategy: str
) -> None:
    result = _result(strategy)
    path = tmp_path / "t.jsonl"
    write_trace(result, path)
    trace = read_trace(path)
    assert len(trace.observations) == len(trace.steps)
    assert all(o is not None for o in trace.observations)
    keeps = strategy not in ("trial-and-error", "oracle")  # no belief to record
    assert all((o.belief is not None) == keeps for o in trace.observations if o is not None)
    assert replay(trace).ok


def _tampered(result: MissionResult, index: int, **fields: object) -> str:
    lines = _lines(result)
    steps = [i for i, line in enumerate(lines) if line["type"] == "step"]
    lines[steps[index]].update(fields)
    return "\n".join(json.dumps(line) for line in lines) + "\n"


def test_replay_names_a_recorded_belief_the_readings_do_not_give() -> None:
    result = _result()
    late = len(result.steps) - 1
    wrong = format(spec_model(result.spec).all, "x")  # every hypothesis still possible
    report = replay(parse_trace(_tampered(result, late, belief=wrong)))
    assert not report.ok and report.first_bad_step == late
    assert "79 hypotheses possible" in report.reason
    last_class = len(spec_model(result.spec).classes) - 1
    report = replay(parse_trace(_tampered(result, late, best=last_class)))
    assert not report.ok and "most probable" in report.reason


def test_replay_names_an_impossible_reading_surprise_or_observer() -> None:
    result = _result(noise=0.0, observers=TEAM[:1])
    end = result.steps[0].end
    far = [end.x + 3, end.y, end.heading.name]
    first = next(line for line in _lines(result) if line["type"] == "step")
    checks = [
        ({"read": far}, "odometry at 0 cannot"),
        ({"surprise": not first["surprise"]}, "surprise"),
        ({"seen": [["t9", [end.x, end.y, end.heading.name]]]}, "not among the header's observers"),
        ({"bumped": None}, "bump switch"),
    ]
    for fields, expected in checks:
        report = replay(parse_trace(_tampered(result, 0, **fields)))
        assert not report.ok and report.first_bad_step == 0 and expected in report.reason


def test_old_traces_still_read_and_replay() -> None:
    result = _result()
    lines = _lines(result)
    lines[0]["version"] = 1
    for line in lines:  # a version-1 hidden-fault trace: no readings, no belief
        for key in ("read", "bumped", "seen", "surprise", "belief", "best"):
            line.pop(key, None)
    trace = parse_trace("\n".join(json.dumps(line) for line in lines) + "\n")
    assert trace.observations == ()
    assert replay(trace).ok


def test_other_traces_record_no_observation() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    schedule = FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FL:F"))
    spec = MissionSpec(maze, route.start, route.goal, schedule=schedule)
    lines = _lines(run_mission(spec))
    assert "hidden" not in lines[0]
    assert all("read" not in line for line in lines)
