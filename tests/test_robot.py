"""The robot model: every row of the motion table, the issue's examples, faults, and properties."""

from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.errors import InputError
from selfrepair.geometry import Heading, Pose, parse_cell, parse_pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import (
    ACTIONS,
    DOUBLE_FAULTS,
    MOTIONS,
    SINGLE_FAULTS,
    Fault,
    Mode,
    MotionKind,
    Wheel,
    available,
    fastest_by_motion,
    format_faults,
    parse_action,
    parse_fault,
    parse_faults,
    step,
)

N, E, S, W = Heading.N, Heading.E, Heading.S, Heading.W
ORIGIN = Pose(2, 2, N)


def act(code: str) -> four_wheel.Action:
    return parse_action(code)


# --- the five examples of the issue --------------------------------------------------------------


def test_example_ffff_drives_one_cell_forward_in_one_tick() -> None:
    assert step(ORIGIN, act("FFFF")) == (Pose(2, 1, N), ((2, 2), (2, 1)), Fraction(1))


def test_example_sfff_arcs_forward_left_in_two_ticks() -> None:
    end, swept, ticks = step(ORIGIN, act("SFFF"))
    assert (act("SFFF").left, act("SFFF").right) == (1, 2)
    assert end == Pose(1, 1, W)
    assert ticks == 2
    assert set(swept) == {(2, 2), (2, 1), (1, 2), (1, 1)}


def test_example_bsbb_arcs_backward_to_the_right() -> None:
    end, swept, ticks = step(ORIGIN, act("BSBB"))
    assert end == Pose(3, 3, W)
    assert set(swept) == {(2, 2), (2, 3), (3, 2), (3, 3)}
    assert ticks == 2


def test_example_fbfb_spins_clockwise_in_one_tick() -> None:
    assert step(ORIGIN, act("FBFB")) == (Pose(2, 2, E), ((2, 2),), Fraction(1))


def test_example_fsss_pivots_clockwise_in_four_ticks() -> None:
    assert step(ORIGIN, act("FSSS")) == (Pose(2, 2, E), ((2, 2),), Fraction(4))


# --- every row of the motion table ----------------------------------------------------------------


def test_wait_row() -> None:
    waits = [a for a in ACTIONS if a.motion.kind is MotionKind.WAIT]
    assert {a.code for a in waits} == {
        "SSSS",
        "FSBS",
        "BSFS",
        "SFSB",
        "SBSF",
        "FFBB",
        "BBFF",
        "FBBF",
        "BFFB",
    }
    for a in waits:
        assert (a.left, a.right) == (0, 0)
        assert step(ORIGIN, a) == (ORIGIN, ((2, 2),), Fraction(1))


@pytest.mark.parametrize(
    ("code", "end", "ticks"),
    [
        ("FFFF", (2, 1), Fraction(1)),  # l = r = 2
        ("FFSS", (2, 1), Fraction(2)),  # l = r = 1
        ("SSFF", (2, 1), Fraction(2)),
        ("FSSF", (2, 1), Fraction(2)),
        ("SFFS", (2, 1), Fraction(2)),
        ("BBBB", (2, 3), Fraction(1)),  # l = r = -2
        ("BBSS", (2, 3), Fraction(2)),
    ],
)
def test_straight_row(code: str, end: tuple[int, int], ticks: Fraction) -> None:
    a = act(code)
    assert a.left == a.right != 0
    assert a.motion.kind is MotionKind.STRAIGHT
    assert step(ORIGIN, a) == (Pose(*end, N), ((2, 2), end), ticks)


def test_five_actions_go_straight_forward() -> None:
    forward = [a.code for a in ACTIONS if a.motion.name == "forward"]
    assert sorted(forward) == sorted(["FFFF", "FFSS", "SSFF", "FSSF", "SFFS"])


@pytest.mark.parametrize(
    ("code", "end"),
    [
        ("SFFF", Pose(1, 1, W)),  # l=1, r=2: forward, slower left side, counter-clockwise
        ("FSFF", Pose(3, 1, E)),  # l=2, r=1: forward, slower right side, clockwise
        ("SBBB", Pose(1, 3, E)),  # l=-1, r=-2: backward, slower left, clockwise (r < l)
        ("BSBB", Pose(3, 3, W)),  # l=-2, r=-1: backward, slower right, counter-clockwise
    ],
)
def test_arc_row(code: str, end: Pose) -> None:
    a = act(code)
    assert a.left * a.right > 0 and a.left != a.right
    assert a.motion.kind is MotionKind.ARC
    got, swept, ticks = step(ORIGIN, a)
    assert got == end
    assert ticks == 2
    d = 1 if a.left > 0 else -1
    lateral = end.x - ORIGIN.x
    assert set(swept) == {(2, 2), (2, 2 - d), (2 + lateral, 2), (2 + lateral, 2 - d)}


@pytest.mark.parametrize(
    ("code", "heading", "ticks"),
    [
        ("FBFB", E, Fraction(1)),  # l=2, r=-2
        ("BFBF", W, Fraction(1)),  # l=-2, r=2
        ("FBSS", E, Fraction(2)),  # l=1, r=-1
        ("FSFB", E, Fraction(4, 3)),  # l=2, r=-1
        ("FSFS", E, Fraction(2)),  # l=2, r=0
        ("FSSS", E, Fraction(4)),  # l=1, r=0
        ("SFSS", W, Fraction(4)),  # l=0, r=1
        ("BSSS", W, Fraction(4)),  # l=-1, r=0: r > l, counter-clockwise
        ("SBSB", E, Fraction(2)),  # l=0, r=-2: r < l, clockwise
    ],
)
def test_turn_row(code: str, heading: Heading, ticks: Fraction) -> None:
    a = act(code)
    assert a.left * a.right <= 0 and (a.left, a.right) != (0, 0)
    assert a.motion.kind is MotionKind.TURN
    assert step(ORIGIN, a) == (Pose(2, 2, heading), ((2, 2),), ticks)


def test_there_are_81_actions_and_nine_motions() -> None:
    assert len(ACTIONS) == 81 == len({a.code for a in ACTIONS})
    assert len(MOTIONS) == 9
    assert {m.name for m in MOTIONS} == {
        "wait",
        "forward",
        "backward",
        "turn-left",
        "turn-right",
        "arc-forward-left",
        "arc-forward-right",
        "arc-backward-left",
        "arc-backward-right",
    }


def test_durations_are_exact_thirds() -> None:
    for a in ACTIONS:
        assert isinstance(a.duration, Fraction)
        assert (a.duration * four_wheel.TICKS_DENOMINATOR).denominator == 1


# --- properties -----------------------------------------------------------------------------------

actions = st.sampled_from(ACTIONS)
headings = st.sampled_from(list(Heading))
coords = st.integers(-50, 50)


def expected_kind(left: int, right: int) -> MotionKind:
    """The table's condition column, written independently of robot.py."""
    if left == right == 0:
        return MotionKind.WAIT
    if left == right:
        return MotionKind.STRAIGHT
    if left * right > 0:
        return MotionKind.ARC
    return MotionKind.TURN


@given(actions)
def test_each_action_falls_in_exactly_the_class_its_drives_say(a: four_wheel.Action) -> None:
    assert a.left == a.wheels[0] + a.wheels[2] and a.right == a.wheels[1] + a.wheels[3]
    assert a.motion.kind is expected_kind(a.left, a.right)


def test_actions_partition_into_motion_classes() -> None:
    classes: dict[MotionKind, set[str]] = {}
    for a in ACTIONS:
        classes.setdefault(a.motion.kind, set()).add(a.code)
    assert sum(len(c) for c in classes.values()) == 81
    assert {k: len(c) for k, c in classes.items()} == {
        MotionKind.WAIT: 9,
        MotionKind.STRAIGHT: 10,
        MotionKind.ARC: 8,
        MotionKind.TURN: 54,
    }


def rotate(cell: tuple[int, int], about: tuple[int, int], quarter_turns: int) -> tuple[int, int]:
    """Rotate ``cell`` clockwise (y down) about ``about`` by ``quarter_turns``."""
    dx, dy = cell[0] - about[0], cell[1] - about[1]
    for _ in range(quarter_turns % 4):
        dx, dy = -dy, dx
    return (about[0] + dx, about[1] + dy)


@given(actions, coords, coords, headings, st.integers(0, 3))
def test_step_is_a_rigid_motion(a: four_wheel.Action, x: int, y: int, h: Heading, k: int) -> None:
    start = Pose(x, y, h)
    end, swept, ticks = step(start, a)
    end_r, swept_r, ticks_r = step(Pose(x, y, h.rotated(k)), a)
    assert ticks_r == ticks
    assert end_r == Pose(*rotate(end.cell, start.cell, k), end.heading.rotated(k))
    assert swept_r == tuple(rotate(c, start.cell, k) for c in swept)


@given(actions, coords, coords, headings, coords, coords)
def test_step_commutes_with_translation(
    a: four_wheel.Action, x: int, y: int, h: Heading, dx: int, dy: int
) -> None:
    end, swept, _ = step(Pose(x, y, h), a)
    end_t, swept_t, _ = step(Pose(x + dx, y + dy, h), a)
    assert end_t == Pose(end.x + dx, end.y + dy, end.heading)
    assert swept_t == tuple((cx + dx, cy + dy) for cx, cy in swept)


@given(actions, headings)
def test_swept_cells_start_with_the_start_and_contain_the_end(
    a: four_wheel.Action, h: Heading
) -> None:
    start = Pose(0, 0, h)
    end, swept, _ = step(start, a)
    assert swept[0] == start.cell
    assert end.cell in swept
    assert len(set(swept)) == len(swept)


# --- faults ---------------------------------------------------------------------------------------


def test_fault_counts() -> None:
    assert len(SINGLE_FAULTS) == 12 == len(set(SINGLE_FAULTS))
    assert len(DOUBLE_FAULTS) == 66 == len(set(DOUBLE_FAULTS))
    assert all(len(pair) == 2 for pair in DOUBLE_FAULTS)


def test_parse_fault_syntax() -> None:
    assert parse_fault("FL:F") == Fault(Wheel.FL, Mode.F)
    assert parse_fault(" rr:b ") == Fault(Wheel.RR, Mode.B)
    both = frozenset({Fault(Wheel.FL, Mode.F), Fault(Wheel.RR, Mode.S)})
    assert parse_faults("FL:F, RR:S") == both
    assert parse_faults("") == frozenset()
    assert format_faults([Fault(Wheel.RR, Mode.S), Fault(Wheel.FL, Mode.F)]) == "FL:F,RR:S"
    assert format_faults(parse_faults("FL:F,FL:S,FL:B,RR:F")) == "FL:B,FL:S,FL:F,RR:F"


@pytest.mark.parametrize("text", [",", ",,,", "FL:F,,RR:B", "FL:F,"])
def test_parse_faults_rejects_empty_items(text: str) -> None:
    with pytest.raises(InputError, match="got ''"):
        parse_faults(text)


@pytest.mark.parametrize("text", ["FL", "FL:X", "XX:F", "FL:F:S", ":F", "FLF"])
def test_parse_fault_rejects_bad_text(text: str) -> None:
    with pytest.raises(InputError, match="expected a fault WHEEL:MODE"):
        parse_fault(text)


@given(st.sets(st.sampled_from(SINGLE_FAULTS), max_size=4))
def test_fault_format_parse_round_trip(faults: set[Fault]) -> None:
    text = format_faults(faults)
    assert parse_faults(text) == frozenset(faults)
    assert format_faults(parse_faults(text)) == text


@given(actions, st.sets(st.sampled_from(SINGLE_FAULTS), max_size=3))
def test_available_means_no_faulty_wheel_command(a: four_wheel.Action, faults: set[Fault]) -> None:
    forbidden = any(a.wheels[f.wheel] is f.mode for f in faults)
    assert available(a, faults) is not forbidden


def test_available_semantics_on_examples() -> None:
    fl_f = {parse_fault("FL:F")}
    assert not available(act("FFFF"), fl_f)
    assert available(act("SFFF"), fl_f)
    assert available(act("FFFF"), set())
    # A single fault removes exactly the 27 actions that give that wheel that command.
    for fault in SINGLE_FAULTS:
        assert sum(available(a, {fault}) for a in ACTIONS) == 54


def test_fastest_by_motion_without_faults() -> None:
    best = fastest_by_motion()
    assert len(best) == 9
    by_name = {m.name: a.code for m, a in best.items()}
    assert by_name["forward"] == "FFFF"
    assert by_name["turn-right"] == "FBFB"
    for m, a in best.items():
        assert a.motion == m
        assert all(b.duration >= a.duration for b in ACTIONS if b.motion == m)


def test_fastest_by_motion_respects_faults() -> None:
    faults = parse_faults("FL:F,RL:F")  # the left side can no longer drive forward
    best = fastest_by_motion(faults)
    assert all(available(a, faults) for a in best.values())
    assert "forward" not in {m.name for m in best}


# --- text forms -----------------------------------------------------------------------------------


def test_parse_action_pose_cell() -> None:
    assert parse_action("sfff").code == "SFFF"
    assert parse_pose("3, 4, w") == Pose(3, 4, W)
    assert str(Pose(3, 4, W)) == "3,4,W"
    assert parse_cell("-1,7") == (-1, 7)
    for bad, parser in (
        ("FFF", parse_action),
        ("1,2", parse_pose),
        ("1,2,X", parse_pose),
        ("1", parse_cell),
        ("a,b", parse_cell),
        ("1,--2,N", parse_pose),
        ("²,1", parse_cell),
        ("+-1,1", parse_cell),
        ("1" * 5000 + ",1", parse_cell),
        ("1," + "2" * 19 + ",N", parse_pose),
    ):
        with pytest.raises(InputError, match="expected"):
            parser(bad)


@given(coords, coords, headings)
def test_pose_text_round_trip(x: int, y: int, h: Heading) -> None:
    assert parse_pose(str(Pose(x, y, h))) == Pose(x, y, h)
