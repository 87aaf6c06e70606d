"""World events: the schedule value, its text and JSON forms, the seeded generator, the simulator
holding the true occupancy over time, sensing and bumps, and missions that never sweep a cell
blocked at that time (checked by an independent re-simulation)."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import selfrepair as sr
from selfrepair.cli import main
from selfrepair.errors import InputError
from selfrepair.execution.replay import replay
from selfrepair.execution.result import MissionResult, StepSource
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.execution.traceread import spec_from_header
from selfrepair.geometry import Heading, Pose
from selfrepair.world.events import Sensing, WorldEvent, WorldSchedule, parse_events, random_world
from selfrepair.world.maze import parse_maze

ROBOT = sr.get_domain("four-wheel")
FORWARD = next(a for a in ROBOT.actions if ROBOT.motion_class(a) == "forward")

CORRIDOR = parse_maze("#########\n#.......#\n#.......#\n#########\n")


def test_text_form_reads_blocks_spans_and_frees() -> None:
    events = parse_events("3,1@5; 4,2@0..7 ; -3,1@9")
    assert events == (
        WorldEvent((3, 1), True, 5),
        WorldEvent((4, 2), True, 0),
        WorldEvent((4, 2), False, 7),
        WorldEvent((3, 1), False, 9),
    )
    world = WorldSchedule(events)
    assert [e.at for e in world.events] == [0, 5, 7, 9]  # sorted by time
    assert world.blocked_at(0) == {(4, 2)}
    assert world.blocked_at(6) == {(4, 2), (3, 1)}
    assert world.blocked_at(8) == {(3, 1)}
    assert world.blocked_at(9) == frozenset()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("3,1", "event 1: expected X,Y@T"),
        ("3,1@2;3@4", "event 2: expected a cell X,Y"),
        ("3,1@4..2", "event 1: expected U > T"),
        ("-3,1@4..6", "event 1: a free event takes one time"),
        ("3,y@4", "event 1: expected y as an integer"),
    ],
)
def test_bad_text_names_the_event(text: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        parse_events(text)


def test_json_round_trip() -> None:
    world = WorldSchedule(parse_events("3,1@5..8;2,2@1"), Sensing.BUMP, 3)
    assert WorldSchedule.from_json(world.to_json()) == world
    with pytest.raises(InputError, match="expected one of range, bump"):
        WorldSchedule((), "sonar")  # type: ignore[arg-type]


def test_random_world_is_seeded_near_the_route_and_never_doubles_a_block() -> None:
    route = [(x, 1) for x in range(1, 8)]
    free = CORRIDOR.free_cells()
    kwargs = dict(rate=50.0, duration=6, distance=0, horizon=200, exclude=[(1, 1), (7, 1)])
    first = random_world(route, free, seed=[3, 1], **kwargs)  # type: ignore[arg-type]
    again = random_world(route, free, seed=[3, 1], **kwargs)  # type: ignore[arg-type]
    other = random_world(route, free, seed=[3, 2], **kwargs)  # type: ignore[arg-type]
    assert first == again and first != other
    assert len(first.events) > 20
    assert all(e.cell in route[1:-1] for e in first.events)
    for t in range(200):  # a cell is never blocked twice over: every block ends at its free
        blocked_now = first.blocked_at(t)
        assert all(c in route[1:-1] for c in blocked_now)
    blocks = [e for e in first.events if e.blocked]
    frees = [e for e in first.events if not e.blocked]
    assert len(blocks) == len(frees)


def test_simulator_bumps_into_a_blocked_cell_and_the_robot_learns_it() -> None:
    world = WorldSchedule(parse_events("3,1@0"), Sensing.BUMP)
    sim = Simulator(ROBOT, CORRIDOR, Pose(2, 1, Heading.E), sr.FaultSchedule(), world=world)
    assert sim.sense_cells(frozenset()) == frozenset()  # bump sensing: nothing seen
    assert sim.advance(FORWARD) is Outcome.BUMPED
    assert sim.pose == Pose(2, 1, Heading.E) and sim.ticks == 1 and sim.steps == 1
    assert sim.last_bumped == ((3, 1),)
    ranged = Simulator(
        ROBOT, CORRIDOR, Pose(1, 1, Heading.E), sr.FaultSchedule(),
        world=WorldSchedule(parse_events("3,1@0..2"), Sensing.RANGE, 2),
    )  # fmt: skip
    seen = ranged.sense_cells(frozenset())
    assert seen == {(3, 1)}
    assert ranged.advance(FORWARD) is Outcome.MOVED  # (2, 1) is free
    ranged.wait_until(2 * ranged.unit)
    assert ranged.sense_cells(seen) == frozenset()  # freed at tick 2, and seen to be


def test_a_block_on_the_robots_own_cell_does_not_trap_it() -> None:
    world = WorldSchedule(parse_events("2,1@0"))
    sim = Simulator(ROBOT, CORRIDOR, Pose(2, 1, Heading.E), sr.FaultSchedule(), world=world)
    assert sim.advance(FORWARD) is Outcome.MOVED
    assert sim.pose.cell == (3, 1)


def swept_blocked(result: MissionResult) -> list[str]:
    """The independent re-simulation: every executed motion, from the trace's steps, against the
    schedule's occupancy at the tick it started (the reference, not the simulator's buffer)."""
    spec, world = result.spec, result.spec.world
    ticks = Fraction(0)
    bad = []
    for step in result.steps:
        blocked = world.blocked_at(ticks)
        if step.source is StepSource.BUMPED:
            cells = spec.domain.footprint(step.start, step.action)[1:]
            if step.end != step.start or not blocked.intersection(cells):
                bad.append(f"step {step.step}: a bump that touched no blocked cell")
        elif step.end != step.start or step.source is not StepSource.FAILED_ATTEMPT:
            swept = spec.domain.footprint(step.start, step.action)[1:]
            if blocked.intersection(swept) or not spec.maze.all_free(list(swept)):
                bad.append(f"step {step.step}: {step.start} sweeps {sorted(blocked & set(swept))}")
            if spec.domain.apply(step.start, step.action) != step.end:
                bad.append(f"step {step.step}: teleport")
        ticks += step.duration
    return bad


NARROW = sr.load_bundled("narrow-short")
ROUTE = sr.bundled_routes("narrow-short")[0]


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    rate=st.sampled_from([2.0, 10.0, 40.0]),
    sensing=st.sampled_from(list(Sensing)),
    strategy=st.sampled_from(["replan", "replacement"]),
)
def test_no_executed_motion_sweeps_a_cell_blocked_at_that_time(
    seed: int, rate: float, sensing: Sensing, strategy: str
) -> None:
    plan = sr.run_mission(sr.MissionSpec(NARROW, ROUTE.start, ROUTE.goal, strategy="replan"))
    cells = [ROUTE.start.cell, *(s.end.cell for s in plan.steps)]
    world = random_world(
        cells, NARROW.free_cells(), seed=seed, rate=rate, duration=15, distance=1, horizon=400,
        exclude=[ROUTE.start.cell, ROUTE.goal], sensing=sensing,
    )  # fmt: skip
    spec = sr.MissionSpec(
        NARROW, ROUTE.start, ROUTE.goal, strategy=strategy, world=world, max_steps=2000,
        schedule=sr.FaultSchedule.permanent(ROBOT.parse_faults("FL:F")),
    )  # fmt: skip
    result = sr.run_mission(spec)
    assert swept_blocked(result) == []
    assert result.status.value in {"reached", "stuck", "step_limit"}


def test_replanning_goes_round_a_blocked_cell() -> None:
    wide = sr.load_bundled("wide-short")
    route = sr.bundled_routes("wide-short")[0]
    plan = sr.run_mission(sr.MissionSpec(wide, route.start, route.goal, strategy="replan"))
    cell = plan.steps[6].end.cell
    world = WorldSchedule((WorldEvent(cell, True, 2),))
    result = sr.run_mission(
        sr.MissionSpec(wide, route.start, route.goal, strategy="replan", world=world)
    )
    assert result.reached
    assert cell not in {s.end.cell for s in result.steps}
    assert sr.mission_row(result)["replans"] >= 1
    assert swept_blocked(result) == []


def test_a_robot_in_a_blocked_corridor_waits_until_the_cell_is_free() -> None:
    plan = sr.run_mission(sr.MissionSpec(NARROW, ROUTE.start, ROUTE.goal, strategy="replan"))
    cell = plan.steps[4].end.cell  # narrow-short is a tree: no way round
    for until, reached in ((12, True), (None, False)):
        events = [WorldEvent(cell, True, 2)]
        if until is not None:
            events.append(WorldEvent(cell, False, until))
        result = sr.run_mission(
            sr.MissionSpec(
                NARROW,
                ROUTE.start,
                ROUTE.goal,
                strategy="replan",
                world=WorldSchedule(tuple(events)),
            )
        )
        assert result.reached is reached
        assert swept_blocked(result) == []
        if not reached:
            assert "no plan exists after waiting 20 steps" in result.reason


def test_cli_events_are_checked(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["run", "narrow-short", "--start", "7,13,W", "--goal", "1,8", "--strategy", "replan"]
    assert main([*args, "--events", "5,13@3..x"]) == 2
    assert "--events, event 1: expected the time U as an integer" in capsys.readouterr().err
    assert main([*args, "--sensing", "sonar"]) == 2
    assert main([*args, "--events", "5,13@0..10", "--sensing-range", "3"]) == 0
    assert main([*args, "--events", "5,13@0..10", "--sensing", "bump"]) == 1  # never sees it free


def test_traces_record_the_world_and_replay_it(tmp_path: Path) -> None:
    wide = sr.load_bundled("wide-short")
    route = sr.bundled_routes("wide-short")[0]
    plan = sr.run_mission(sr.MissionSpec(wide, route.start, route.goal, strategy="replan"))
    cells = [route.start.cell, *(s.end.cell for s in plan.steps)]
    world = random_world(cells, wide.free_cells(), seed=4, rate=40.0, duration=10, distance=0,
                         horizon=200, exclude=[route.start.cell, route.goal],
                         sensing=Sensing.BUMP)  # fmt: skip
    result = sr.run_mission(sr.MissionSpec(wide, route.start, route.goal, world=world))
    assert sr.mission_row(result)["bumps"] >= 1
    path = tmp_path / "t.jsonl"
    sr.write_trace(result, path)
    trace = sr.read_trace(path)
    assert spec_from_header(trace.header).world == world
    assert replay(trace).ok
    first = next(s for s in result.steps if s.source is StepSource.PLAN and s.start != s.end)
    lines = path.read_text().splitlines()
    header = json.loads(lines[0])
    swept = ROBOT.footprint(first.start, first.action)[1]
    header["world"]["events"].insert(0, {"cell": list(swept), "blocked": True, "at": 0})
    path.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    report = replay(path)
    assert not report.ok and "blocked at tick 0 by world events" in report.reason


def test_the_viewer_greys_out_each_blocked_cell_at_its_time() -> None:
    from selfrepair.execution.traceread import parse_trace
    from selfrepair.execution.tracewrite import trace_lines
    from selfrepair.experiment.viewer import mission_payload, render_html

    world = WorldSchedule(parse_events("4,1@0..3;6,2@2"))
    spec = sr.MissionSpec(CORRIDOR, Pose(1, 1, Heading.E), (7, 1), strategy="replan", world=world)
    result = sr.run_mission(spec)
    payload = mission_payload(parse_trace("\n".join(trace_lines(result))))
    ticks = [Fraction(f["tick"]) for f in payload["frames"]]
    assert [f["blocked"] for f in payload["frames"]] == [
        [list(c) for c in sorted(world.blocked_at(t))] for t in ticks
    ]
    assert [4, 1] in payload["frames"][0]["blocked"] and [6, 2] in payload["frames"][-1]["blocked"]
    assert payload["world"] == "3 world events, sensing range 2"
    assert "drawBlocked" in render_html(payload)
