"""The fault-behaviour model (``Domain.effective``) and the simulator with hidden faults."""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

import pytest

from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.result import MissionSpec, StepSource
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import FaultBehaviour, check_domain
from selfrepair.robots.four_wheel import BEHAVIOURS, FOUR_WHEEL, parse_action
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.world.maze import parse_maze

OPEN = parse_maze(".....\n.....\n.....\n.....\n.....\n", name="open")
CORRIDOR = parse_maze("#####\n##.##\n##.##\n##.##\n#####\n", name="corridor")


def _hidden(faults: str, detection: Detection = Detection.HIDDEN) -> FaultSchedule:
    return FaultSchedule.permanent(FOUR_WHEEL.parse_faults(faults), detection=detection)


def test_the_four_wheel_robot_keeps_the_contract() -> None:
    check_domain(FOUR_WHEEL)
    assert FOUR_WHEEL.behaviour_names() == ("stall", "runaway-backward", "reverse")
    assert FOUR_WHEEL.behaviour() is BEHAVIOURS[0]
    for model in FOUR_WHEEL.behaviour_names():
        for faults in FOUR_WHEEL.fault_sets:
            for action in FOUR_WHEEL.actions:
                got = FOUR_WHEEL.effective(action, faults, model)
                assert (got == action) == FOUR_WHEEL.available(action, faults)


@pytest.mark.parametrize(
    ("model", "action", "faults", "performed"),
    [
        ("stall", "FFFF", "FL:F", "SFFF"),
        ("stall", "BBBB", "RR:B", "BBBS"),
        ("stall", "SSSS", "FL:S", "FSSS"),
        ("stall", "FFFF", "FL:F,FL:S", "BFFF"),  # the one mode the wheel still has
        ("stall", "FFFF", "FL:F,RL:F", "SFSF"),
        ("runaway-backward", "SSSS", "FL:S", "BSSS"),
        ("runaway-backward", "FFFF", "FL:F", "SFFF"),
        ("reverse", "FFFF", "FL:F", "BFFF"),
        ("reverse", "FFFF", "FL:F,FL:B", "SFFF"),
        ("stall", "FSBF", "FR:F", "FSBF"),  # available: itself
    ],
)
def test_known_effective_actions(model: str, action: str, faults: str, performed: str) -> None:
    got = FOUR_WHEEL.effective(parse_action(action), FOUR_WHEEL.parse_faults(faults), model)
    assert got == parse_action(performed)


def test_unknown_models_and_domains_without_one_fail_clearly() -> None:
    with pytest.raises(ProblemError, match=r"unknown fault behaviour 'melt'.*stall"):
        FOUR_WHEEL.effective(parse_action("FFFF"), FOUR_WHEEL.parse_faults("FL:F"), "melt")
    assert THREE_ACTION.behaviours == ()
    forbidden = next(
        (a, frozenset({f}))
        for a in THREE_ACTION.actions
        for f in THREE_ACTION.faults
        if not THREE_ACTION.available(a, frozenset({f}))
    )
    with pytest.raises(ProblemError, match="no fault-behaviour model"):
        THREE_ACTION.effective(*forbidden)
    action = THREE_ACTION.actions[0]
    assert THREE_ACTION.effective(action, frozenset()) is action


def test_check_domain_rejects_a_model_that_changes_an_available_action() -> None:
    spin = parse_action("SFSF")

    def wrong(action: object, faults: frozenset[object]) -> object:
        return spin

    bad = replace(FOUR_WHEEL, name="bad", behaviours=(FaultBehaviour("wrong", "", wrong),))
    with pytest.raises(ProblemError, match="available action FFFF into SFSF"):
        check_domain(bad)
    dupes = replace(FOUR_WHEEL, name="dupes", behaviours=(BEHAVIOURS[0], BEHAVIOURS[0]))
    with pytest.raises(ProblemError, match="distinct"):
        check_domain(dupes)


def test_hidden_faults_move_the_robot_differently() -> None:
    sim = Simulator(FOUR_WHEEL, OPEN, Pose(2, 3, Heading.N), _hidden("FL:F"))
    assert sim.sense() == frozenset()
    outcome = sim.execute(parse_action("FFFF"))
    # SFFF: left drive 1, right 2: an arc forward to the left, ending facing west
    assert outcome.status is Outcome.MOVED
    assert outcome.end == Pose(1, 2, Heading.W)
    assert sim.last_action == parse_action("SFFF")
    assert outcome.duration == Fraction(2)
    assert set(outcome.swept) == {(2, 3), (2, 2), (1, 3), (1, 2)}
    assert outcome.blocking == frozenset()
    assert sim.bumps == 0


def test_a_motion_that_sweeps_a_wall_stops_at_the_start_pose() -> None:
    start = Pose(2, 3, Heading.N)
    sim = Simulator(FOUR_WHEEL, CORRIDOR, start, _hidden("FL:F"))
    outcome = sim.execute(parse_action("FFFF"))  # the arc to the left sweeps the wall (1, 3)
    assert outcome.status is Outcome.BUMPED
    assert outcome.end == start and sim.pose == start
    assert outcome.duration == Fraction(1) and sim.ticks == Fraction(1)
    assert sim.bumps == 1 and sim.steps == 1
    healthy = sim.execute(parse_action("SSFF"))  # a straight move up the corridor still works
    assert healthy.status is Outcome.MOVED and healthy.end == Pose(2, 2, Heading.N)
    assert sim.execute(parse_action("SSFF")).end == Pose(2, 1, Heading.N)
    assert sim.execute(parse_action("SSFF")).status is Outcome.BUMPED  # the wall ahead
    assert sim.pose == Pose(2, 1, Heading.N) and sim.bumps == 2


def test_other_detections_keep_failed_attempts() -> None:
    sim = Simulator(
        FOUR_WHEEL, OPEN, Pose(2, 3, Heading.N), _hidden("FL:F", Detection.ON_USE)
    )
    outcome = sim.execute(parse_action("FFFF"))
    assert outcome.status is Outcome.FAILED_ATTEMPT
    assert outcome.blocking == FOUR_WHEEL.parse_faults("FL:F")


def test_a_domain_without_a_model_fails_without_naming_the_fault() -> None:
    fault = THREE_ACTION.faults[0]
    action = next(a for a in THREE_ACTION.actions if not THREE_ACTION.available(a, {fault}))
    schedule = FaultSchedule.permanent([fault], detection=Detection.HIDDEN)
    sim = Simulator(THREE_ACTION, OPEN, Pose(2, 2, Heading.N), schedule)
    outcome = sim.execute(action)
    assert outcome.status is Outcome.FAILED_ATTEMPT
    assert outcome.blocking == frozenset() and outcome.end == Pose(2, 2, Heading.N)


def test_an_unknown_behaviour_fails_before_the_first_step() -> None:
    with pytest.raises(ProblemError, match="unknown fault behaviour"):
        Simulator(FOUR_WHEEL, OPEN, Pose(2, 3, Heading.N), _hidden("FL:F"), behaviour="melt")


def test_a_mission_with_hidden_faults_records_its_bumps() -> None:
    maze = parse_maze("#######\n#.....#\n#######\n", name="slot")
    spec = MissionSpec(
        maze, Pose(1, 1, Heading.E), (5, 1), schedule=_hidden("FL:F"), max_steps=12
    )
    result = run_mission(spec)
    # the plan's straight moves arc into the walls of the one-cell corridor: the robot, which is
    # not told its fault and does not diagnose, bumps at every step and never moves
    assert not result.reached
    assert [s.source for s in result.steps] == [StepSource.BUMPED] * 12
    assert all(s.start == s.end == Pose(1, 1, Heading.E) for s in result.steps)
    assert run_mission(spec).steps == result.steps
