"""A changing world in team missions (issue 28, item 5): world events in team scenarios and on
the command line, every robot's simulator applying the one schedule, sensing by range or by bump,
each robot repairing a blocked move by its own strategy (detour or replan), the team strategies
seeing the cells, traces that record the events and replay, and the team page greying the cells
out at their times."""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.execution.result import StepSource
from selfrepair.experiment.teamview import team_payload
from selfrepair.geometry import parse_pose
from selfrepair.repair.strategies import RepairSource
from selfrepair.team.engine import run_team
from selfrepair.team.model import IncidentKind, RobotSpec, Task, TeamScenario
from selfrepair.team.result import TeamOptions, TeamResult
from selfrepair.team.scenario import parse_scenario
from selfrepair.team.trace import parse_team_trace, read_team_trace, replay_team
from selfrepair.team.tracewrite import team_trace_lines
from selfrepair.world.events import Sensing, WorldSchedule, parse_events, random_world
from selfrepair.world.maze import parse_maze
from test_viewer_browser import driver  # noqa: F401  (the browser fixture and its skip policy)

OPEN = parse_maze("############\n#..........#\n#..........#\n#..........#\n############\n")
"""Three free rows: room for a local detour round one blocked cell."""

DOORS = parse_maze("#########\n#...#...#\n#.......#\n#...#...#\n#.......#\n#########\n")
"""Two rooms joined by two doors, 4,2 and 4,4."""

ONE_DOOR = parse_maze(
    "###########\n#....#....#\n#.........#\n#....#....#\n#....#....#\n###########\n"
)
"""Two rooms joined by one door, 5,2."""


def _scenario(
    maze: Any, starts: str, task: tuple[tuple[int, int], tuple[int, int]], events: str,
    sensing: Sensing = Sensing.RANGE,
) -> TeamScenario:  # fmt: skip
    robots = tuple(RobotSpec(f"r{i}", parse_pose(p)) for i, p in enumerate(starts.split(), 1))
    return TeamScenario(
        maze, robots, (Task("i1", *task),), world=WorldSchedule(parse_events(events), sensing, 2)
    )


def _swept_blocked(result: TeamResult) -> list[str]:
    """An independent re-simulation: every executed motion against the cells its schedule
    blocks at the motion's start (the cell the robot stands on aside); every bump must touch
    one. Empty when all holds."""
    scenario, scale, bad = result.scenario, result.scale, []
    domain = scenario.domain
    for m in result.moves:
        blocked = scenario.world.blocked_at(Fraction(m.start, scale))
        swept = domain.footprint(m.before, m.action)[1:]
        if m.source is StepSource.BUMPED:
            if m.after != m.before or not blocked.intersection(swept):
                bad.append(f"{m.robot} at {m.start}: a bump that touched no blocked cell")
        elif m.source is not StepSource.FAILED_ATTEMPT and blocked.intersection(swept):
            bad.append(f"{m.robot} at {m.start}: {m.before} sweeps {sorted(blocked & set(swept))}")
    return bad


# --- a robot repairs by its own strategy --------------------------------------------------------


def test_a_cell_blocked_in_front_of_robot_1_is_passed_by_a_local_detour() -> None:
    """Cell 6,2 closes at tick 3 while r1 drives east along row 2; its range sensors see it one
    cell ahead and its replacement strategy answers with a detour from the detour table at 5,2,E
    (tick 4), through row 3; no motion sweeps 6,2 after it closed."""
    result = run_team(_scenario(OPEN, "1,2,E 1,3,E", ((9, 2), (10, 1)), "6,2@3"))
    assert result.all_delivered and result.makespan == 20
    (own,) = result.own_repairs
    assert (own.at, own.robot, str(own.pose)) == (12, "r1", "5,2,E")
    assert own.source is RepairSource.DETOUR
    assert own.status.value == "repaired" and not result.incidents
    cells = [m.after.cell for m in result.moves if m.robot == "r1"]
    assert (6, 2) not in cells and (6, 3) in cells
    assert _swept_blocked(result) == []


def test_with_bump_sensing_the_robot_bumps_once_then_detours() -> None:
    result = run_team(
        _scenario(OPEN, "1,2,E 1,3,E", ((9, 2), (10, 1)), "6,2@3", Sensing.BUMP)
    )
    bumps = [m for m in result.moves if m.source is StepSource.BUMPED]
    assert [(m.robot, m.start, m.end, str(m.before)) for m in bumps] == [("r1", 12, 15, "5,2,E")]
    assert [o.source for o in result.own_repairs] == [RepairSource.DETOUR]
    assert result.all_delivered and result.makespan == 21
    assert _swept_blocked(result) == []


@pytest.mark.parametrize("strategy", ["replacement", "replan"])
def test_a_door_that_closes_in_front_of_robot_1_makes_it_replan_through_the_other(
    strategy: str,
) -> None:
    """Door 4,2 closes at tick 2 as r1 nears it; no detour of the table fits (the other door is
    too far), so both strategies replan at 3,2,E (tick 2) through door 4,4."""
    scenario = _scenario(DOORS, "1,2,E 1,4,E", ((7, 2), (7, 1)), "4,2@2")
    result = run_team(scenario, TeamOptions(robot_strategy=strategy))
    (own,) = result.own_repairs
    assert (own.at, str(own.pose), own.source) == (6, "3,2,E", RepairSource.REPLAN)
    path = [m.after.cell for m in result.moves if m.robot == "r1"]
    assert (4, 4) in path and (4, 2) not in path
    assert result.all_delivered and result.makespan == 18
    assert _swept_blocked(result) == []


def test_a_cell_that_opens_again_lets_the_waiting_robot_through() -> None:
    """Column 6 is closed from tick 3, its cell 6,3 only until tick 30: r1 waits, the team gives
    the item up when r1's waits run out, and offers it again when r1's sensors see 6,3 open."""
    scenario = _scenario(OPEN, "1,2,E 1,3,E", ((9, 2), (10, 1)), "6,1@3;6,2@3;6,3@3..30")
    result = run_team(scenario)
    assert result.all_delivered and result.makespan == 44
    first = min(m.start for m in result.moves if m.robot == "r1" and m.after.cell == (6, 3))
    assert first >= 30 * result.scale
    assert [i.kind for i in result.incidents] == [IncidentKind.BLOCKED]
    assert _swept_blocked(result) == []


def test_a_goal_blocked_for_a_while_is_waited_for_not_an_error() -> None:
    """A single robot's goal (and a team robot's drive target) blocked by a world event: no plan
    reaches it while it is blocked (before, the planner refused the goal as a wall: an error),
    so the robot waits and arrives once it is free."""
    import selfrepair as sr

    corridor = parse_maze("#######\n#.....#\n#.....#\n#######\n")
    world = WorldSchedule(parse_events("5,1@1..10"))
    result = sr.run_mission(sr.MissionSpec(corridor, parse_pose("1,1,E"), (5, 1), world=world))
    assert result.status.value == "reached"
    assert sum(s.duration for s in result.steps) >= 10
    team = run_team(_scenario(OPEN, "1,2,E 1,3,E", ((6, 2), (10, 1)), "6,2@1..25"))
    assert team.all_delivered
    pick = next(a for a in team.acts if a.action.kind.value == "pick")
    assert pick.start >= 25 * team.scale
    assert _swept_blocked(team) == []


# --- the team strategies see the cells ----------------------------------------------------------


@pytest.mark.parametrize(
    ("strategy", "delivered", "by"),
    [("team-replacement", True, "fetch-deliver"), ("reallocation", True, ""), ("alone", False, "")],
)
def test_team_strategies_see_a_door_closed_before_robot_1_sets_off(
    strategy: str, delivered: bool, by: str
) -> None:
    """The only door, 5,2, is closed from tick 0: r1, allocated the item, sees it and cannot
    reach the item on the known map (a ``blocked`` incident). The team strategies plan on the
    known map, which has the door: team replacement and reallocation give the item to r2, which
    stands on the item's side; ``alone`` waits for a door that never opens."""
    scenario = _scenario(ONE_DOOR, "3,2,E 9,4,W", ((7, 2), (9, 1)), "5,2@0")
    result = run_team(scenario, TeamOptions(strategy=strategy))
    assert [(i.at, i.robot, i.kind) for i in result.incidents] == [(0, "r1", IncidentKind.BLOCKED)]
    assert result.all_delivered is delivered
    assert result.repairs[0].candidate == by
    if delivered:
        assert {a.action.robot for a in result.acts} == {"r2"}
    assert not [m for m in result.moves if m.robot == "r1"]


def test_a_carrier_walled_off_from_its_drop_off_waits_the_incident_out() -> None:
    """r1 picks the item, then door 5,2 to the drop-off is closed (ticks 3 to 40): reallocation
    gives r1 the same drive again, which meets the same incident at the same instant; the robot
    then waits it out (one incident, one repair, not one per pass of the engine) and delivers
    once it sees the door open."""
    scenario = _scenario(ONE_DOOR, "8,2,W 9,4,W", ((7, 2), (2, 2)), "5,2@3..40")
    result = run_team(scenario, TeamOptions(strategy="reallocation"))
    assert [(i.at, i.robot, i.kind) for i in result.incidents] == [(9, "r1", IncidentKind.BLOCKED)]
    assert len(result.repairs) == 1
    assert result.all_delivered and result.makespan == 48
    assert _swept_blocked(result) == []


# --- scenario files and the command line --------------------------------------------------------

SCENARIO = """
name = "door"
maze = "wide-short"

[[robots]]
name = "r1"
start = "1,1,E"

[[tasks]]
item = "i1"
pickup = "5,4"
dropoff = "16,1"

[world]
events = "4,1@2; 3,4@1..9"
sensing = "bump"
range = 1
"""


def test_the_world_section_of_a_scenario_file_is_read_with_the_one_parser() -> None:
    scenario = parse_scenario(SCENARIO, source="door.toml")
    assert scenario.world == WorldSchedule(parse_events("4,1@2; 3,4@1..9"), Sensing.BUMP, 1)
    assert parse_scenario(SCENARIO.split("[world]")[0]).world == WorldSchedule()


@pytest.mark.parametrize(
    ("section", "message", "line"),
    [
        ('events = "4,1@2; 3,4@x"', "'world.events' (events, event 2): expected the time T", 15),
        ('events = "4,1@2; 99,4@1"', "tick 1 on cell 99,4: the cell is off the maze", 15),
        ('events = "4,1"', "events, event 1): expected X,Y@T", 15),
        ('sensing = "sonar"', "sensing", 15),
    ],
)
def test_a_bad_world_section_is_one_line_naming_file_and_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], section: str, message: str, line: int
) -> None:
    path = tmp_path / "door.toml"
    path.write_text(SCENARIO.split("[world]")[0] + "[world]\n" + section + "\n", encoding="utf-8")
    assert main(["team", "run", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("selfrepair: error: ")
    assert f"{path}:{line}:" in err and message in err, err


def test_bad_events_on_the_command_line_are_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["team", "run", "three-robots", "--events", "5,4@1; 7,x@2"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--events, event 2: expected y as an integer" in err
    assert main(["team", "run", "three-robots", "--sensing", "sonar"]) == 2
    assert "--sensing" in capsys.readouterr().err


# --- traces -------------------------------------------------------------------------------------


def test_a_team_trace_records_the_events_and_replays(tmp_path: Path) -> None:
    trace = tmp_path / "t.jsonl"
    code = main([
        "team", "run", "three-robots", "--events", "5,4@3..60; 7,6@2..40; 6,4@1",
        "--sensing", "bump", "--trace", str(trace),
    ])  # fmt: skip
    assert code == 0
    parsed = read_team_trace(trace)
    assert parsed.scenario.world == WorldSchedule(
        parse_events("5,4@3..60; 7,6@2..40; 6,4@1"), Sensing.BUMP
    )
    assert any(m.source is StepSource.BUMPED for m in parsed.moves)
    report = replay_team(parsed)
    assert report.ok, report
    assert main(["team", "replay", str(trace)]) == 0


def test_replay_refuses_a_move_through_a_cell_blocked_at_that_time() -> None:
    """The same trace with one event moved earlier, so that an executed motion sweeps its cell
    while it is blocked: the replay names the move's line and the cell."""
    scenario = _scenario(OPEN, "1,2,E 1,3,E", ((9, 2), (10, 1)), "6,2@3")
    lines = team_trace_lines(run_team(scenario))
    assert replay_team(parse_team_trace("\n".join(lines))).ok
    early = replace(scenario, world=WorldSchedule(parse_events("3,2@0"), Sensing.RANGE, 2))
    tampered = team_trace_lines(replace(run_team(scenario), scenario=early))
    report = replay_team(parse_team_trace("\n".join([tampered[0], *lines[1:]])))
    assert not report.ok and "sweeps cell 3,2, blocked at unit" in report.problem
    assert report.line is not None and report.line > 1


def test_a_team_trace_without_events_has_no_world_in_its_header() -> None:
    scenario = _scenario(OPEN, "1,2,E 1,3,E", ((9, 2), (10, 1)), "")
    header = team_trace_lines(run_team(scenario))[0]
    assert '"world"' not in header


NARROW = parse_maze(
    "##########\n#........#\n#.##.###.#\n#........#\n#.###.##.#\n#........#\n##########\n"
)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    rate=st.sampled_from([5.0, 20.0, 60.0]),
    sensing=st.sampled_from(list(Sensing)),
    strategy=st.sampled_from(["replan", "replacement"]),
)
def test_no_team_motion_sweeps_a_cell_blocked_at_that_time(
    seed: int, rate: float, sensing: Sensing, strategy: str
) -> None:
    """Random world events near every cell of the maze, for two robots and two tasks: the
    engine's moves pass the independent re-simulation, and the trace replays."""
    starts = (RobotSpec("r1", parse_pose("1,1,E")), RobotSpec("r2", parse_pose("8,5,W")))
    tasks = (Task("i1", (8, 1), (1, 5)), Task("i2", (4, 3), (8, 3)))
    free = NARROW.free_cells()
    exclude = [r.start.cell for r in starts] + [c for t in tasks for c in (t.pickup, t.dropoff)]
    world = random_world(
        free, free, seed=seed, rate=rate, duration=12, distance=0, horizon=120,
        exclude=exclude, sensing=sensing,
    )  # fmt: skip
    scenario = TeamScenario(NARROW, starts, tasks, world=world)
    result = run_team(scenario, TeamOptions(robot_strategy=strategy, max_ticks=400))
    assert _swept_blocked(result) == []
    report = replay_team(parse_team_trace("\n".join(team_trace_lines(result))))
    assert report.ok, report


# --- the team page ------------------------------------------------------------------------------


def _door_trace(tmp_path: Path) -> Path:
    path = tmp_path / "door.toml"
    path.write_text(SCENARIO.replace('sensing = "bump"', 'sensing = "range"'), encoding="utf-8")
    trace = tmp_path / "door.jsonl"
    assert main(["team", "run", str(path), "--trace", str(trace)]) == 0
    return trace


def test_the_team_payload_greys_each_blocked_cell_at_its_time(tmp_path: Path) -> None:
    trace = read_team_trace(_door_trace(tmp_path))
    payload = team_payload(trace, max_steps=10_000)
    world, scale = trace.scenario.world, trace.scale
    at = [f["at"] for f in payload["frames"]]
    assert {e.at * scale for e in world.events} <= set(at)  # a frame at every change
    for frame in payload["frames"]:
        expected = sorted(world.blocked_at(Fraction(frame["at"], scale)))
        assert frame["blocked"] == [list(c) for c in expected]
    assert any(f["blocked"] for f in payload["frames"])


def test_the_team_page_greys_out_blocked_cells_at_their_time(
    driver: Any,  # noqa: F811
    tmp_path: Path,
) -> None:
    trace_path = _door_trace(tmp_path)
    html = tmp_path / "door.html"
    assert main(["view", str(trace_path), "-o", str(html)]) == 0
    trace = read_team_trace(trace_path)
    frames = team_payload(trace, max_steps=10_000)["frames"]
    driver.get_log("browser")
    driver.get(html.as_uri())
    world = trace.scenario.world
    for k in sorted({0, 1, 2, 3, len(frames) // 2, len(frames) - 1}):
        driver.execute_script(
            "const s = document.getElementById('slider'); s.value = arguments[0];"
            "s.dispatchEvent(new Event('input', {bubbles: true}));",
            k,
        )
        drawn = driver.execute_script(
            "return [...document.querySelectorAll('#layer-blocked .blocked-cell')]"
            ".map(r => r.getAttribute('data-cell')).sort();"
        )
        ticks = Fraction(frames[k]["at"], trace.scale)
        assert drawn == sorted(f"{x},{y}" for x, y in world.blocked_at(ticks)), k
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors
