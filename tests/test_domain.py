"""The domain-independent interface and its two domains."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair import robot
from selfrepair.domain import DOMAINS, FOUR_WHEEL, THREE_ACTION, get_domain, run_open
from selfrepair.errors import InputError
from selfrepair.robot import Heading, Pose

poses = st.builds(Pose, st.integers(-20, 20), st.integers(-20, 20), st.sampled_from(list(Heading)))


def test_registry_names_both_domains() -> None:
    assert set(DOMAINS) == {"four-wheel", "three-action"}
    assert get_domain("three-action") is THREE_ACTION
    with pytest.raises(InputError, match="four-wheel, three-action"):
        get_domain("hexapod")


@given(poses, st.sampled_from(robot.ACTIONS))
def test_four_wheel_is_the_robot_model(pose: Pose, action: robot.Action) -> None:
    end, swept, duration = robot.step(pose, action)
    assert FOUR_WHEEL.apply(pose, action) == end
    assert FOUR_WHEEL.footprint(pose, action) == swept
    assert FOUR_WHEEL.cost(action) == duration


def test_four_wheel_fault_sets_are_singles_then_doubles() -> None:
    sets = FOUR_WHEEL.fault_sets
    assert len(sets) == 12 + 66
    assert all(len(s) == 1 for s in sets[:12]) and all(len(s) == 2 for s in sets[12:])
    fault = robot.parse_fault("FL:F")
    assert not FOUR_WHEEL.available(robot.parse_action("FFFF"), frozenset({fault}))
    assert FOUR_WHEEL.available(robot.parse_action("SSFF"), frozenset({fault}))


def test_four_wheel_levels_put_arcs_above_primitives() -> None:
    for action in robot.ACTIONS:
        expected = 1 if action.motion.kind is robot.MotionKind.ARC else 0
        assert FOUR_WHEEL.level(action) == expected


def test_three_action_moves_like_table_one() -> None:
    start = THREE_ACTION.canonical
    assert THREE_ACTION.apply(start, "F") == Pose(0, -1, Heading.N)
    assert THREE_ACTION.apply(start, "L") == Pose(0, 0, Heading.W)
    assert THREE_ACTION.apply(start, "R") == Pose(0, 0, Heading.E)
    assert run_open(THREE_ACTION, start, "LLL") == THREE_ACTION.apply(start, "R")
    assert run_open(THREE_ACTION, start, "RRR") == THREE_ACTION.apply(start, "L")
    assert all(THREE_ACTION.cost(a) == Fraction(1) for a in "FLR")
    assert THREE_ACTION.footprint(start, "F") == ((0, 0), (0, -1))
    assert THREE_ACTION.footprint(start, "L") == ((0, 0),)


def test_three_action_faults_disable_one_action_by_name() -> None:
    faults = THREE_ACTION.parse_faults("r, L")
    assert faults == frozenset({"R", "L"})
    assert THREE_ACTION.format_faults(faults) == "L,R"
    assert THREE_ACTION.available("F", faults) and not THREE_ACTION.available("R", faults)
    assert [THREE_ACTION.format_faults(s) for s in THREE_ACTION.fault_sets] == [
        "F",
        "L",
        "R",
        "F,L",
        "F,R",
        "L,R",
    ]
    with pytest.raises(InputError, match="F, L or R"):
        THREE_ACTION.parse_action("X")


@pytest.mark.parametrize("domain", list(DOMAINS.values()), ids=list(DOMAINS))
def test_action_text_round_trips(domain) -> None:  # type: ignore[no-untyped-def]
    for action in domain.actions:
        assert domain.parse_action(domain.format_action(action)) == action
    for faults in domain.fault_sets:
        assert domain.parse_faults(domain.format_faults(faults)) == faults
