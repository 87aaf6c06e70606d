"""The domain-independent interface and its two domains."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.errors import InputError, ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.domain import Domain, check_domain, run_open
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.registry import domain_names, get_domain, register_domain
from selfrepair.robots.three_action import THREE_ACTION

poses = st.builds(Pose, st.integers(-20, 20), st.integers(-20, 20), st.sampled_from(list(Heading)))


def test_registry_names_both_domains() -> None:
    assert set(domain_names()) >= {"four-wheel", "three-action"}
    assert get_domain("three-action") is THREE_ACTION
    with pytest.raises(InputError, match=r"four-wheel, .*three-action"):
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


def _hopper(footprint_connected: bool, footprint: str = "ends") -> Domain[str, str]:
    """A hand-made robot with one straight step and one diagonal hop "D" (one cell right and one
    ahead, heading kept); its footprint is only the two end cells (``"ends"``), or the end cells
    and the cell ahead (``"swept"``), or the end cells and a 6-step detour round the
    cells between them (``"detour"``)."""
    moves = {"F": (0, -1), "D": (1, -1)}

    def apply(pose: Pose, action: str) -> Pose:
        dx, dy = moves[action]
        return Pose(pose.x + dx, pose.y + dy, pose.heading)

    def cells(pose: Pose, action: str) -> tuple[Cell, ...]:
        end = apply(pose, action).cell
        if action == "F" or footprint == "ends":
            return (pose.cell, end)
        if footprint == "swept":
            return (pose.cell, (pose.x, pose.y - 1), end)
        x, y = pose.cell
        return ((x, y), (x - 1, y), (x - 1, y - 1), (x - 1, y - 2), (x, y - 2), (x + 1, y - 2), end)

    return Domain(
        name="hopper",
        actions=("F", "D"),
        apply=apply,
        footprint=cells,
        duration=lambda action: Fraction(1),
        available=lambda action, faults: action not in faults,
        parse_action=lambda text: text,
        format_action=lambda action: action,
        faults=("F", "D"),
        parse_faults=lambda text: frozenset(t for t in text.split(",") if t),
        format_faults=lambda faults: ",".join(sorted(faults)),
        motion_class=lambda action: action,
        footprint_connected=footprint_connected,
    )


def test_a_diagonal_hop_that_claims_a_connected_footprint_is_refused() -> None:
    with pytest.raises(ProblemError, match=r"'hopper'.*footprint_connected=True.*action D from N"):
        check_domain(_hopper(True))
    with pytest.raises(ProblemError, match="action D"):
        register_domain(_hopper(True))
    check_domain(_hopper(False))  # the same hop without the claim is a valid domain


def test_a_connected_footprint_must_hold_a_shortest_path() -> None:
    check_domain(_hopper(True, "swept"))  # start, the cell ahead, end: 2 steps for distance 2
    with pytest.raises(ProblemError, match="no 4-connected path of 2 steps"):
        check_domain(_hopper(True, "detour"))  # connected, but 6 steps: h would overestimate


@pytest.mark.parametrize("domain", [FOUR_WHEEL, THREE_ACTION], ids=lambda d: d.name)
def test_shipped_robots_keep_their_connected_footprints(domain: Domain[Any, Any]) -> None:
    assert domain.footprint_connected
    check_domain(domain)
