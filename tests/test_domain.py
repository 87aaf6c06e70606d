"""The domain-independent interface and its two domains."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.errors import InputError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.domain import run_open
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.registry import domain_names, get_domain
from selfrepair.robots.three_action import THREE_ACTION

poses = st.builds(Pose, st.integers(-20, 20), st.integers(-20, 20), st.sampled_from(list(Heading)))


def test_registry_names_both_domains() -> None:
    assert set(domain_names()) >= {"four-wheel", "three-action"}
    assert get_domain("three-action") is THREE_ACTION
    with pytest.raises(InputError, match="four-wheel, three-action"):
        get_domain("hexapod")


@given(poses, st.sampled_from(four_wheel.ACTIONS))
def test_four_wheel_is_the_robot_model(pose: Pose, action: four_wheel.Action) -> None:
    end, swept, duration = four_wheel.step(pose, action)
    assert FOUR_WHEEL.apply(pose, action) == end
    assert FOUR_WHEEL.footprint(pose, action) == swept
    assert FOUR_WHEEL.duration(action) == duration


def test_four_wheel_fault_sets_are_singles_then_doubles() -> None:
    sets = FOUR_WHEEL.fault_sets
    assert len(sets) == 12 + 66
    assert all(len(s) == 1 for s in sets[:12]) and all(len(s) == 2 for s in sets[12:])
    fault = four_wheel.parse_fault("FL:F")
    assert not FOUR_WHEEL.available(four_wheel.parse_action("FFFF"), frozenset({fault}))
    assert FOUR_WHEEL.available(four_wheel.parse_action("SSFF"), frozenset({fault}))


def test_four_wheel_levels_put_arcs_above_primitives() -> None:
    for action in four_wheel.ACTIONS:
        expected = 1 if action.motion.kind is four_wheel.MotionKind.ARC else 0
        assert FOUR_WHEEL.level(action) == expected


def test_three_action_moves_like_table_one() -> None:
    start = THREE_ACTION.canonical
    assert THREE_ACTION.apply(start, "F") == Pose(0, -1, Heading.N)
    assert THREE_ACTION.apply(start, "L") == Pose(0, 0, Heading.W)
    assert THREE_ACTION.apply(start, "R") == Pose(0, 0, Heading.E)
    assert run_open(THREE_ACTION, start, "LLL") == THREE_ACTION.apply(start, "R")
    assert run_open(THREE_ACTION, start, "RRR") == THREE_ACTION.apply(start, "L")
    assert all(THREE_ACTION.duration(a) == Fraction(1) for a in "FLR")
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


@pytest.mark.parametrize("domain", [FOUR_WHEEL, THREE_ACTION], ids=["four-wheel", "three-action"])
def test_action_text_round_trips(domain) -> None:  # type: ignore[no-untyped-def]
    for action in domain.actions:
        assert domain.parse_action(domain.format_action(action)) == action
    for faults in domain.fault_sets:
        assert domain.parse_faults(domain.format_faults(faults)) == faults
