"""Team missions: actions, reservations, space-time planning, team tables and their validity,
the engine's strategies on the three-robots scenario, and the re-simulation of team traces."""

from __future__ import annotations

import itertools
import json
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.execution.faults import Persistence
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.team import engine
from selfrepair.team.binding import Incident, Maps, bind
from selfrepair.team.experiment import FaultCase, TeamCase, build_scenario, run_case
from selfrepair.team.model import (
    IncidentKind,
    Load,
    RobotSpec,
    Task,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    Trigger,
    drive,
    drop,
    handover,
    parse_team_action,
    pick,
)
from selfrepair.team.reservations import FOREVER, Reservations
from selfrepair.team.result import TeamOptions, TeamSource
from selfrepair.team.scenario import GripperMix, resolve_scenario
from selfrepair.team.spacetime import lattice_of, plan_spacetime, schedule_path
from selfrepair.team.state import Entry
from selfrepair.team.table import HANDWRITTEN, KEYS, Place, Role, _canonical, generate_table
from selfrepair.team.trace import (
    header_json,
    parse_team_trace,
    read_team_trace,
    replay_team,
    write_team_trace,
)
from selfrepair.world.bundled import load_bundled
from selfrepair.world.maze import Maze, parse_maze

OPEN = parse_maze(".......\n.......\n.......\n")


# --- actions and reservations ---------------------------------------------------------------------


@given(
    st.sampled_from(["r1", "robot-2", "a_b"]),
    st.tuples(st.integers(-5, 50), st.integers(-5, 50)),
    st.tuples(st.integers(-5, 50), st.integers(-5, 50)),
)
def test_drive_text_round_trips(
    robot: str, source: tuple[int, int], target: tuple[int, int]
) -> None:
    action = drive(robot, source, target)
    assert parse_team_action(str(action)) == action


def test_act_texts_round_trip() -> None:
    for action in (pick("r1", "i1"), drop("r2", "box"), handover("r1", "r3", "i9")):
        assert parse_team_action(str(action)) == action


def test_reservations_half_open_and_release() -> None:
    res = Reservations()
    res.reserve("a", [(1, 1), (2, 1)], 0, 6)
    assert not res.free([(2, 1)], 5, 7, "b")
    assert res.free([(2, 1)], 6, 9, "b")  # a leaves at 6, b may enter at 6
    assert res.free([(2, 1)], 0, 6, "a")  # own reservations never block
    assert res.clear_after([(1, 1)], 2, 5, "b") == 6
    res.park("a", (2, 1), 6)
    assert res.clear_after([(2, 1)], 0, 3, "b") >= FOREVER
    res.release_from("a", 4)
    assert res.free([(2, 1)], 4, 100, "b") and not res.free([(1, 1)], 3, 4, "b")


# --- space-time planning --------------------------------------------------------------------------


def _actions() -> tuple[object, ...]:
    from selfrepair.search.lattice import planning_actions

    return planning_actions(FOUR_WHEEL, frozenset())


def test_cooperative_astar_avoids_a_parked_robot() -> None:
    res = Reservations()
    res.park("other", (3, 1), 0)
    lattice = lattice_of(OPEN, FOUR_WHEEL, _actions(), 3)  # type: ignore[arg-type]
    steps, _ = plan_spacetime(
        res, "me", lattice, frozenset(), Pose(0, 1, Heading.E), 0, (6, 1),
        wait=3, horizon=300, max_expansions=20_000,
    )  # fmt: skip
    assert steps is not None and steps[-1].after.cell == (6, 1)
    assert all((3, 1) not in s.cells for s in steps)
    for a, b in itertools.pairwise(steps):
        assert b.before == a.after and b.start >= a.end


def test_schedule_path_waits_for_a_crossing_robot() -> None:
    res = Reservations()
    res.reserve("other", [(2, 1)], 0, 9)  # someone crosses (2, 1) until unit 9
    forward = FOUR_WHEEL.parse_action("FFFF")
    steps = schedule_path(
        res, "me", FOUR_WHEEL, 3, OPEN, Pose(0, 1, Heading.E), 0, [forward, forward, forward],
        max_wait=30,
    )  # fmt: skip
    assert steps is not None
    assert steps[0].start == 0 and steps[1].start == 9  # waits on (1, 1), then goes on
    assert (
        schedule_path(
            res, "me", FOUR_WHEEL, 3, OPEN, Pose(0, 1, Heading.E), 0, [forward] * 3, max_wait=3
        )
        is None
    )


# --- team tables ----------------------------------------------------------------------------------


def test_generated_table_contains_every_hand_written_candidate() -> None:
    generated = generate_table()
    for key, template in HANDWRITTEN.rows():
        shapes = {_canonical(t.steps): t.name for t in generated.entries.get(key, ())}
        assert shapes.get(_canonical(template.steps)) == template.name, (key, template.name)


def test_generated_candidates_never_use_the_blocked_drive_or_an_immobile_robot() -> None:
    generated = generate_table()
    for key in KEYS:
        for template in generated.entries.get(key, ()):
            mine = [s for s in template.steps if s.role is Role.FAULTY and s.kind == "drive"]
            if key[1] is IncidentKind.STUCK:
                assert not mine, template
            if mine and key[1] is IncidentKind.BLOCKED:
                assert mine[0].place is not Place.TARGET, template


# --- the three-robots scenario (one of three robots immobilised while carrying) -------------------


@pytest.fixture(scope="module")
def three() -> TeamScenario:
    return resolve_scenario("three-robots")


@pytest.fixture(scope="module")
def runs(three: TeamScenario) -> dict[str, object]:
    out: dict[str, object] = {"fault-free": engine.run_team(three.without_faults())}
    for strategy in ("team-replacement", "reallocation", "alone"):
        out[strategy] = engine.run_team(three, TeamOptions(strategy=strategy))
    return out


def test_team_replacement_delivers_everything_after_an_immobilised_carrier(runs: dict) -> None:
    team = runs["team-replacement"]
    assert team.all_delivered and team.status == "delivered"
    first = team.repairs[0]
    assert (first.robot, first.kind, first.candidate) == ("r2", "stuck", "handover-deliver")
    assert team.incidents[0].load is Load.CARRYING
    handovers = [a for a in team.acts if a.action.kind == "handover"]
    assert handovers and handovers[0].action.robot == "r2"


def test_team_replacement_replies_with_less_work_than_reallocation(runs: dict) -> None:
    """The deterministic side of 'replies faster' (timings: benchmarks/team_repair.py): the
    team replacement changes one teammate's plan and plans at most one drive; re-allocation
    changes every robot's plan and plans every changed robot's drive."""
    team, realloc = runs["team-replacement"].repairs[0], runs["reallocation"].repairs[0]
    assert runs["reallocation"].all_delivered
    assert len(team.disturbed) < len(realloc.disturbed) == 2
    assert team.plans < realloc.plans or team.plans == realloc.plans == 0
    assert team.messages <= realloc.messages + 1


def test_alone_loses_the_dead_robots_tasks(runs: dict, three: TeamScenario) -> None:
    alone = runs["alone"]
    assert alone.status == "stalled" and not alone.all_delivered
    dead = {a.action.item for a in alone.acts if a.action.robot == "r2"}
    assert dead and not dead & {item for item, _ in alone.delivered}
    assert not any(r.source is TeamSource.TEAM_REPLACEMENT for r in alone.repairs)


def test_every_run_re_simulates(runs: dict, tmp_path: Path) -> None:
    for name, result in runs.items():
        path = tmp_path / f"{name}.jsonl"
        write_team_trace(result, path)
        report = replay_team(read_team_trace(path))
        assert report.ok, (name, str(report))


def test_runs_are_deterministic(three: TeamScenario, runs: dict) -> None:
    again = engine.run_team(three, TeamOptions(strategy="team-replacement"))
    assert again.moves == runs["team-replacement"].moves
    assert again.acts == runs["team-replacement"].acts


# --- validity: health, equipment and the recursion guard -----------------------------------------


def _world(scenario: TeamScenario) -> object:
    world = engine._world(scenario, TeamOptions())
    engine._allocate(world)
    return world


def test_bind_respects_the_recursion_guard_and_equipment(three: TeamScenario) -> None:
    world = _world(three)
    r2 = world.robots["r2"]
    r2.holding, world.items["i2"].cell = "i2", None
    r2.stuck = True
    entry = Entry(drive("r2", (1, 22), (20, 22)))
    incident = Incident("r2", entry, IncidentKind.STUCK, Load.CARRYING, "i2", 0)
    maps = Maps(world.known_map("r2"), "auto")
    template = HANDWRITTEN.candidates(incident.entry.action.kind, incident.known)[0]
    found = bind(world, incident, template, "r1", maps)
    assert found is not None and found.template.name == "handover-deliver"
    reach = next(a for a in dict(found.actions)["r1"] if a.kind == "drive")
    guarded = Entry(entry.action, guard=frozenset({reach}))
    again = Incident("r2", guarded, IncidentKind.STUCK, Load.CARRYING, "i2", 0)
    assert bind(world, again, template, "r1", maps) is None  # the guard forbids it
    world.robots["r1"].gripper_ok = False
    assert bind(world, incident, template, "r1", maps) is None  # the taker must grip
    assert bind(world, incident, template, "r2", maps) is None  # never itself


def test_robots_without_a_gripper_are_never_helpers() -> None:
    maze = load_bundled("wide-short")
    for seed in range(3):
        case = TeamCase(6, 6, GripperMix.MIXED, FaultCase.IMMOBILISED_CARRYING, seed=seed)
        result, _ = run_case(maze, case, TeamOptions())
        bare = {r.name for r in result.scenario.robots if not r.gripper}
        assert bare and not bare & {r.helper for r in result.repairs}
        assert not {a.action.robot for a in result.acts if a.action.kind == "pick"} & bare


def test_transient_immobilisation_lets_the_lone_robot_finish() -> None:
    maze = load_bundled("wide-short")
    case = TeamCase(3, 3, GripperMix.ALL, FaultCase.IMMOBILISED, Persistence.TRANSIENT, 30, seed=4)
    result, baseline = run_case(maze, case, TeamOptions(strategy="alone"))
    assert result.all_delivered and result.makespan >= baseline
    assert [f.active for f in result.faults] == [True, False]


def test_a_blocked_corridor_is_repaired_and_re_simulates(tmp_path: Path) -> None:
    maze = load_bundled("wide-short")
    for strategy in ("team-replacement", "alone"):
        found = False
        for seed in range(6):
            case = TeamCase(3, 3, GripperMix.ALL, FaultCase.BLOCKED, seed=seed)
            result, _ = run_case(maze, case, TeamOptions(strategy=strategy))
            assert result.scenario.faults[0].kind is TeamFaultKind.BLOCKED
            path = tmp_path / f"{strategy}-{seed}.jsonl"
            write_team_trace(result, path)
            assert replay_team(read_team_trace(path)).ok
            found |= any(i.kind is IncidentKind.BLOCKED for i in result.incidents)
            assert result.all_delivered
        assert found  # some drive met the block


# --- the re-simulation can fail -------------------------------------------------------------------


def _empty_trace_header() -> dict[str, object]:
    maze = Maze(np.zeros((3, 5), dtype=bool), name="open")
    scenario = TeamScenario(
        maze, (RobotSpec("a", Pose(0, 1, Heading.E)), RobotSpec("b", Pose(2, 1, Heading.W))), ()
    )
    return header_json(engine.run_team(scenario))


def _move(robot: str, start: int, before: list[object], after: list[object]) -> str:
    return json.dumps(
        {"type": "move", "robot": robot, "start": start, "end": start + 3, "action": "FFFF",
         "from": before, "to": after, "source": "plan"}
    )  # fmt: skip


def test_replay_finds_a_conflict_and_a_teleport() -> None:
    head = json.dumps(_empty_trace_header())
    clash = [head, _move("a", 0, [0, 1, "E"], [1, 1, "E"]), _move("b", 0, [2, 1, "W"], [1, 1, "W"])]
    report = replay_team(parse_team_trace("\n".join(clash), partial=True))
    assert not report.ok and "conflict" in report.problem and "1,1" in report.problem
    jump = [head, _move("a", 0, [0, 1, "E"], [1, 1, "E"]), _move("a", 3, [3, 1, "E"], [4, 1, "E"])]
    report = replay_team(parse_team_trace("\n".join(jump), partial=True))
    assert not report.ok and "teleport" in report.problem
    fine = [head, _move("a", 0, [0, 1, "E"], [1, 1, "E"]), _move("b", 3, [2, 1, "W"], [1, 1, "W"])]
    assert not replay_team(parse_team_trace("\n".join(fine), partial=True)).ok  # b enters too soon
    late = [head, _move("a", 0, [0, 1, "E"], [1, 1, "E"])]
    assert replay_team(parse_team_trace("\n".join(late), partial=True)).ok


def test_replay_checks_faults_and_acts() -> None:
    scenario = TeamScenario(
        Maze(np.zeros((3, 6), dtype=bool), name="open"),
        (RobotSpec("a", Pose(0, 1, Heading.E)),),
        (Task("i1", (2, 1), (5, 1)),),
        (TeamFault(TeamFaultKind.IMMOBILISED, "a", at=1, trigger=Trigger.TICK),),
    )
    result = engine.run_team(scenario)
    head = json.dumps(header_json(result))
    moving = _move("a", 3, [0, 1, "E"], [1, 1, "E"])  # after the fault started at tick 1
    report = replay_team(parse_team_trace(head + "\n" + moving, partial=True))
    assert not report.ok and "is logged as []" in report.problem  # the fault line is missing
    fault = json.dumps({"type": "fault", "at": 3, "index": 0, "active": True})
    report = replay_team(parse_team_trace(f"{head}\n{fault}\n{moving}", partial=True))
    assert not report.ok and "faults forbid" in report.problem
    lines = f"{head}\n{fault}"
    act = json.dumps(
        {"type": "act", "start": 0, "end": 6, "action": "pick(a,i1)", "cells": [[0, 1]]}
    )
    report = replay_team(parse_team_trace(lines + "\n" + act, partial=True))
    assert not report.ok and "cannot happen" in report.problem


def test_a_truncated_trace_is_refused(tmp_path: Path, runs: dict) -> None:
    path = tmp_path / "t.jsonl"
    write_team_trace(runs["team-replacement"], path)
    lines = path.read_text().splitlines()
    path.write_text("\n".join(lines[:-1]) + "\n")
    from selfrepair.errors import TraceError

    with pytest.raises(TraceError, match="truncated"):
        read_team_trace(path)


# --- scenarios of the experiment ------------------------------------------------------------------


def test_experiment_cases_share_the_team_across_fault_cases() -> None:
    maze = load_bundled("wide-short")
    a = build_scenario(maze, TeamCase(4, 4, GripperMix.ALL, FaultCase.GRIPPER, seed=9))
    b = build_scenario(maze, TeamCase(4, 4, GripperMix.ALL, FaultCase.WHEELS, seed=9))
    assert a.robots == b.robots and a.tasks == b.tasks and a.faults != b.faults
    assert a.faults[0].robot in {r.name for r in a.robots}


def test_queue_helpers_keep_drives_consistent(three: TeamScenario) -> None:
    from selfrepair.team.binding import strip_item
    from selfrepair.team.state import resource

    world = _world(three)
    r1 = world.robots["r1"]
    before = [e.action for e in r1.queue]
    item = before[1].item
    strip_item(r1, item)
    resource(r1)
    after = [e.action for e in r1.queue]
    assert all(a.item != item for a in after) and len(after) == len(before) - 4
    assert after[0].source == r1.pose.cell
    r1.queue = deque(Entry(a) for a in after)


def test_the_team_strategy_is_started_once_per_mission(three: TeamScenario) -> None:
    """Issue 23 item 3: a team strategy lives for the mission, as a robot's repairer does (the
    strategy lifecycle); it used to be started again for every incident."""
    from dataclasses import replace as with_field

    from selfrepair.repair.strategies import StrategyName, register, strategy_entry
    from selfrepair.team.strategies import TEAM

    entry = strategy_entry(StrategyName.TEAM_REPLACEMENT, TEAM)
    started: list[object] = []
    asked: list[object] = []

    class Counting:
        def __init__(self, world: Any) -> None:
            started.append(world)
            self.inner = entry.start(world)

        def repair(self, incident: Any) -> Any:
            asked.append(incident)
            return self.inner.repair(incident)

    register(with_field(entry, start=Counting), replace=True)
    try:
        result = engine.run_team(three, TeamOptions(strategy=StrategyName.TEAM_REPLACEMENT))
    finally:
        register(entry, replace=True)
    assert len(result.repairs) >= 2
    assert len(started) == 1 and len(asked) == len(result.repairs)
