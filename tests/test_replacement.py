"""Run-time replacement: validity, the three recursion modes, and the paper's Table 1."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.replacement import (
    RecursionMode,
    find_replacement,
    flat_replacement,
    is_valid_replacement,
    table_reach,
)
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.tables.fileformat import bundled_table
from selfrepair.tables.model import ReplacementTable, TableEntry
from selfrepair.world.maze import Maze, parse_maze

A = four_wheel.parse_action
F = four_wheel.parse_faults
OPEN = parse_maze("\n".join(["." * 9] * 9))
ORIGIN = Pose(4, 4, Heading.N)


def _seq(text: str) -> tuple[four_wheel.Action, ...]:
    return tuple(A(t) for t in text.split())


# --- the original paper's Table 1 --------------------------------------------------------------


def test_table_one_rows() -> None:
    table = bundled_table("three-action")
    rows = {e.action: [" ".join(c) for c in e.candidates] for e in table.entries}
    assert rows == {"F": [], "L": ["R R R"], "R": ["L L L"]}


@pytest.mark.parametrize("mode", list(RecursionMode))
def test_table_one_replacements_and_the_no_replacement_row(mode: str) -> None:
    table = bundled_table("three-action")
    found = {}
    for action in "FLR":
        hit = find_replacement(table, action, ORIGIN, {action}, OPEN.all_free, mode=mode)
        found[action] = None if hit is None else "".join(hit.actions)
    assert found == {"F": None, "L": "RRR", "R": "LLL"}


@pytest.mark.parametrize("mode", list(RecursionMode))
def test_guard_stops_mutual_recursion(mode: str) -> None:
    # With L and R both faulty, R -> L L L needs L -> R R R, which uses R (being replaced).
    table = bundled_table("three-action")
    assert (
        find_replacement(table, "R", ORIGIN, {"L", "R"}, OPEN.all_free, mode=mode, max_depth=10)
        is None
    )


# --- four-wheel recursion modes -------------------------------------------------------------


def test_forward_without_left_forward_needs_recursion_into_a_turn_round() -> None:
    table = bundled_table()
    faults = F("FL:F,RL:F")
    args = (table, A("FFFF"), ORIGIN, faults, OPEN.all_free)
    assert find_replacement(*args, mode="flat") is None
    assert find_replacement(*args, mode="layered") is None  # straight moves are primitive
    assert find_replacement(*args, mode="guarded", max_depth=0) is None
    hit = find_replacement(*args, mode="guarded")
    assert hit is not None and hit.depth >= 1
    assert is_valid_replacement(FOUR_WHEEL, A("FFFF"), ORIGIN, hit.actions, faults, OPEN.all_free)


def test_layered_replaces_an_arc_by_recursively_replaced_primitives() -> None:
    table = bundled_table()
    faults = F("FR:F")
    args = (table, A("SFFF"), ORIGIN, faults, OPEN.all_free)
    assert find_replacement(*args, mode="flat") is None
    layered = find_replacement(*args, mode="layered")
    assert layered is not None and layered.depth == 1
    assert layered.candidate == _seq("FFFF BFBF FFFF")
    assert layered.actions == _seq("SSFF BSBS SSFF")
    guarded = find_replacement(*args, mode="guarded")
    assert guarded is not None and guarded.actions == layered.actions


def test_walls_make_a_candidate_invalid() -> None:
    # A corridor one cell wide: turning round in place is fine, arcs are not.
    corridor = parse_maze("###\n#.#\n#.#\n#.#\n###")
    pose = Pose(1, 3, Heading.N)
    table = bundled_table()
    faults = F("FL:F,RL:F")
    hit = find_replacement(table, A("FFFF"), pose, faults, corridor.all_free, mode="guarded")
    assert hit is not None
    walled = parse_maze("###\n#.#\n###")
    assert (
        find_replacement(
            table,
            A("FFFF"),
            Pose(1, 1, Heading.N),
            faults,
            walled.all_free,
            mode="guarded",
        )
        is None
    )


def test_candidate_using_an_action_being_replaced_is_skipped() -> None:
    fwd, back = A("FFFF"), A("BBBB")
    table = ReplacementTable(
        FOUR_WHEEL,
        "fault-agnostic",
        "hand",
        (
            TableEntry(fwd, (_seq("FBFB FBFB BBBB FBFB FBFB"),)),
            TableEntry(back, (_seq("FBFB FBFB FFFF FBFB FBFB"),)),
        ),
    )
    # BBBB is faulty too: replacing it would need FFFF, which is being replaced.
    faults = F("FL:F,RR:B")
    assert (
        find_replacement(table, fwd, ORIGIN, faults, OPEN.all_free, mode="guarded", max_depth=5)
        is None
    )


def test_bad_arguments_raise() -> None:
    table = bundled_table()
    with pytest.raises(ProblemError, match="recursion mode"):
        find_replacement(table, A("FFFF"), ORIGIN, (), OPEN.all_free, mode="deep")
    with pytest.raises(ProblemError, match="domain"):
        find_replacement(table, "F", ORIGIN, (), OPEN.all_free)


@st.composite
def situations(
    draw: st.DrawFn,
) -> tuple[Maze, Pose, four_wheel.Action, frozenset[four_wheel.Fault]]:
    seed = draw(st.integers(0, 2**31))
    rng = np.random.default_rng(seed)
    walls = rng.random((7, 7)) < draw(st.sampled_from([0.0, 0.2, 0.4]))
    walls[3, 3] = False
    maze = Maze(walls)
    pose = Pose(3, 3, draw(st.sampled_from(list(Heading))))
    action = draw(st.sampled_from(four_wheel.ACTIONS))
    faults = draw(st.sampled_from(FOUR_WHEEL.fault_sets))
    return maze, pose, action, faults


@settings(max_examples=150, deadline=None)
@given(situations(), st.sampled_from(list(RecursionMode)))
def test_every_replacement_found_is_valid(situation, mode: str) -> None:  # type: ignore[no-untyped-def]
    maze, pose, action, faults = situation
    hit = find_replacement(bundled_table(), action, pose, faults, maze.all_free, mode=mode)
    if hit is None:
        return
    assert is_valid_replacement(
        FOUR_WHEEL, action, pose, hit.actions, faults, maze.all_free, deferred=hit.deferred
    )
    if mode == "flat":
        assert hit.depth == 0 and hit.actions == hit.candidate


@settings(max_examples=100, deadline=None)
@given(situations())
def test_modes_are_nested(situation) -> None:  # type: ignore[no-untyped-def]
    """Whatever flat finds, layered and guarded find too (they only add recursion)."""
    maze, pose, action, faults = situation
    table = bundled_table()
    found = {
        m: find_replacement(table, action, pose, faults, maze.all_free, mode=m)
        for m in RecursionMode
    }
    if found["flat"] is not None:
        assert found["layered"] is not None and found["guarded"] is not None
    if found["layered"] is not None:
        assert found["guarded"] is not None


@settings(max_examples=150, deadline=None)
@given(situations())
def test_grid_fast_path_equals_the_general_flat_search(situation) -> None:  # type: ignore[no-untyped-def]
    maze, pose, action, faults = situation
    table = bundled_table()
    general = find_replacement(table, action, pose, faults, maze.all_free, mode="flat")
    fast = flat_replacement(table, action, pose, faults, maze.free_grid(table_reach(table)))
    assert fast == general


def test_grid_fast_path_on_table_one() -> None:
    table = bundled_table("three-action")
    free = OPEN.free_grid(table_reach(table))
    hit = flat_replacement(table, "R", ORIGIN, frozenset({"R"}), free)
    assert hit is not None and hit.actions == ("L", "L", "L") and hit.end == Pose(4, 4, Heading.E)
    assert flat_replacement(table, "F", ORIGIN, frozenset({"F"}), free) is None


def test_docs_show_table_one_as_bundled() -> None:
    from pathlib import Path

    doc = (Path(__file__).parents[1] / "docs/replacement.md").read_text()
    table = bundled_table("three-action")
    for entry in table.entries:
        shown = " ".join(entry.candidates[0]) if entry.candidates else "(no replacement)"
        assert f"| {entry.action} (" in doc and f") | {shown} |" in doc


def test_guard_skips_a_candidate_that_reuses_an_action_being_replaced() -> None:
    """FL:F disables FFFF and FBFB. FFFF's candidate turns around with FBFB, which is replaced
    in turn; FBFB's first candidate uses FFFF, the action being replaced, so the guard must skip
    it for the second. Without the guard the search would recurse into FFFF again and return a
    different, deeper replacement."""
    ffff, fbfb = A("FFFF"), A("FBFB")
    table = ReplacementTable(
        FOUR_WHEEL,
        "fault-agnostic",
        "hand",
        (
            TableEntry(ffff, (_seq("FBFB FBFB BBBB FBFB FBFB"),)),
            TableEntry(fbfb, (_seq("FFFF BBBB SBSB"), _seq("SBSB"))),
        ),
    )
    hit = find_replacement(
        table, ffff, ORIGIN, F("FL:F"), OPEN.all_free, mode="guarded", max_depth=5
    )
    assert hit is not None
    assert hit.actions == _seq("SBSB SBSB BBBB SBSB SBSB") and hit.depth == 1
