"""The table generator: motion classes, enumeration, both shapes, determinism, the Table 1 robot."""

from __future__ import annotations

import json
import pathlib
from importlib import resources

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.errors import ProblemError, TableError
from selfrepair.robots import four_wheel
from selfrepair.robots.domain import run_open
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.tables.fileformat import dump_table, load_table, parse_table
from selfrepair.tables.generate import (
    Path,
    class_costs,
    enumerate_paths,
    generate_table,
    motion_classes,
    scope_fault_sets,
    select_diverse,
    verify_entry,
)
from selfrepair.tables.model import GenerateOptions


def _shipped(name: str) -> str:
    return resources.files("selfrepair").joinpath("data", "tables", f"{name}.json").read_text()


# --- motion classes and class costs ----------------------------------------------------------


def test_four_wheel_classes_are_the_nine_motions() -> None:
    classes = motion_classes(FOUR_WHEEL)
    assert len(classes) == len(four_wheel.MOTIONS) == 9
    for motion in classes:
        assert {a.motion for a in motion.members} == {motion.members[0].motion}
    assert sum(len(c.members) for c in classes) == 81


def test_three_action_classes() -> None:
    assert [c.members for c in motion_classes(THREE_ACTION)] == [("F",), ("L",), ("R",)]


@pytest.mark.parametrize("faults", [frozenset(), *FOUR_WHEEL.fault_sets])
def test_class_costs_pick_what_fastest_by_motion_picks(faults: frozenset[four_wheel.Fault]) -> None:
    costs = class_costs(FOUR_WHEEL, lambda a: four_wheel.available(a, faults))
    picked = {action.motion: action for _, _, action in costs.values()}
    assert picked == four_wheel.fastest_by_motion(faults)
    for obj, duration, action in costs.values():
        assert obj == duration == action.duration * 3  # durations scaled to thirds of a tick


def test_length_objective_counts_steps_but_keeps_the_fastest_member() -> None:
    costs = class_costs(FOUR_WHEEL, lambda a: True, "length")
    assert {obj for obj, _, _ in costs.values()} == {1}
    assert {a for _, _, a in costs.values()} == set(four_wheel.fastest_by_motion().values())


def test_scopes() -> None:
    assert len(scope_fault_sets(FOUR_WHEEL, "singles")) == 12
    assert len(scope_fault_sets(FOUR_WHEEL, "doubles")) == 66
    assert len(scope_fault_sets(FOUR_WHEEL, "all")) == 78
    assert scope_fault_sets(FOUR_WHEEL, "none") == ()
    with pytest.raises(ProblemError):
        scope_fault_sets(FOUR_WHEEL, "triples")


# --- enumeration ---------------------------------------------------------------------------


@pytest.mark.parametrize("faults", [frozenset(), *FOUR_WHEEL.fault_sets[:12:5]])
def test_enumerated_paths_resimulate(faults: frozenset[four_wheel.Fault]) -> None:
    costs = class_costs(FOUR_WHEEL, lambda a: four_wheel.available(a, faults))
    targets = [c.end for c in motion_classes(FOUR_WHEEL)]
    found = enumerate_paths(FOUR_WHEEL, costs, targets, 3)
    start = FOUR_WHEEL.canonical
    for target, paths in found.items():
        assert paths, f"no path to {target}"
        assert paths == sorted(paths, key=Path.rank)
        keys = set()
        for path in paths:
            actions = [costs[ci][2] for ci in path.motions]
            assert 1 <= len(actions) <= 3
            state, cells = start, set()
            for a in actions:
                cells.update(four_wheel.swept_cells(state, a))
                state = four_wheel.step(state, a)[0]
            assert state == target
            assert frozenset(cells) == path.footprint
            assert path.duration == sum(a.duration for a in actions) * 3
            keys.add((path.end, path.footprint))
        assert len(keys) == len(paths), "duplicate (end pose, swept cells) kept"


def test_select_diverse_drops_supersets_of_kept_extras() -> None:
    base = frozenset({(0, 0)})
    p1 = Path(1, 1, (0,), None, frozenset({(0, 0), (1, 0)}))
    p2 = Path(2, 2, (1,), None, frozenset({(0, 0), (1, 0), (2, 0)}))  # extra covers p1's
    p3 = Path(3, 3, (2,), None, frozenset({(0, 0), (0, 1)}))
    p4 = Path(4, 4, (3,), None, frozenset({(0, 0)}))
    assert select_diverse([p1, p2, p3, p4], base, 5) == [p1, p3, p4]
    assert select_diverse([p1, p2, p3, p4], base, 2) == [p1, p3]
    assert select_diverse([p4, p1], base, 5) == [p4]


# --- generated entries ---------------------------------------------------------------------


def _check_entries(table_text: str) -> None:
    table = parse_table(table_text)
    dom = table.domain
    for entry in table.entries:
        target = dom.apply(dom.canonical, entry.action)
        for candidate in entry.candidates:
            assert candidate and entry.action not in candidate
            assert run_open(dom, dom.canonical, candidate) == target
            if entry.faults is not None:
                assert all(dom.available(a, entry.faults) for a in candidate)
                assert not dom.available(entry.action, entry.faults)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    shape=st.sampled_from(["fault-agnostic", "fault-indexed"]),
    max_length=st.integers(1, 4),
    per_action=st.integers(1, 4),
    faults=st.sampled_from(["singles", "doubles", "none"]),
    objective=st.sampled_from(["duration", "length"]),
)
def test_every_generated_entry_resimulates(
    shape: str, max_length: int, per_action: int, faults: str, objective: str
) -> None:
    options = GenerateOptions(
        shape=shape,
        max_length=max_length,
        per_action=per_action,
        faults=faults,
        objective=objective,
    )
    table = generate_table(FOUR_WHEEL, options)
    assert table.made_by == "generator"
    assert dict(table.parameters) == options.parameters()
    for entry in table.entries:
        assert 1 <= len(entry.candidates) <= per_action or (
            shape == "fault-indexed" and not entry.candidates
        )
        assert all(len(c) <= max_length for c in entry.candidates)
    _check_entries(dump_table(table))


def test_fault_indexed_has_one_entry_per_disabled_action() -> None:
    table = generate_table(FOUR_WHEEL, GenerateOptions(shape="fault-indexed", faults="singles"))
    keys = {(e.action, e.faults) for e in table.entries}
    expected = {
        (a, f)
        for f in scope_fault_sets(FOUR_WHEEL, "singles")
        for a in four_wheel.ACTIONS
        if not four_wheel.available(a, f)
    }
    assert keys == expected
    assert len(keys) == 12 * 27


def test_fault_agnostic_candidates_are_cheapest_first() -> None:
    table = generate_table(FOUR_WHEEL, GenerateOptions(faults="singles", per_action=3))
    for entry in table.entries:
        costs = [sum(a.duration for a in c) for c in entry.candidates]
        assert costs == sorted(costs)


def test_shipped_tables_are_valid_and_small() -> None:
    for name in ("generated-agnostic", "generated-indexed"):
        text = _shipped(name)
        assert len(text.encode()) < 400_000
        _check_entries(text)
        header = json.loads(text)
        assert header["made_by"] == "generator"
        assert header["parameters"]["per_action"] == 5


def test_generation_is_deterministic_and_reproduces_the_shipped_indexed_table() -> None:
    shipped = _shipped("generated-indexed")
    params = json.loads(shipped)["parameters"]
    options = GenerateOptions(shape="fault-indexed", **params)
    assert dump_table(generate_table(FOUR_WHEEL, options)) == shipped
    again = GenerateOptions(shape="fault-agnostic", faults="singles", per_action=3)
    assert dump_table(generate_table(FOUR_WHEEL, again)) == dump_table(
        generate_table(FOUR_WHEEL, again)
    )


@pytest.mark.slow
def test_generation_reproduces_the_shipped_agnostic_table() -> None:
    shipped = _shipped("generated-agnostic")
    params = json.loads(shipped)["parameters"]
    assert (
        dump_table(generate_table(FOUR_WHEEL, GenerateOptions(shape="fault-agnostic", **params)))
        == shipped
    )


# --- the Table 1 robot ----------------------------------------------------------------------


def test_three_action_table_is_the_papers() -> None:
    table = generate_table(THREE_ACTION, GenerateOptions())
    assert table.candidates("R") == (("L", "L", "L"),)
    assert table.candidates("L") == (("R", "R", "R"),)
    assert "F" not in table.actions_with_entries()


def test_three_action_fault_indexed() -> None:
    table = generate_table(THREE_ACTION, GenerateOptions(shape="fault-indexed"))
    assert table.candidates("R", frozenset({"R"})) == (("L", "L", "L"),)
    assert table.candidates("R", frozenset({"R", "F"})) == (("L", "L", "L"),)
    assert table.candidates("R", frozenset({"R", "L"})) == ()
    assert table.candidates("F", frozenset({"F"})) == ()


# --- verification and errors ----------------------------------------------------------------


def test_verify_entry_rejects_wrong_candidates() -> None:
    ffff, ffss = four_wheel.parse_action("FFFF"), four_wheel.parse_action("FFSS")
    verify_entry(FOUR_WHEEL, ffff, [(ffss,)])
    with pytest.raises(TableError, match="does not end"):
        verify_entry(FOUR_WHEEL, ffff, [(four_wheel.parse_action("FBFB"),)])
    with pytest.raises(TableError, match="empty or uses"):
        verify_entry(FOUR_WHEEL, ffff, [(ffff,)])
    with pytest.raises(TableError, match="forbidden"):
        verify_entry(FOUR_WHEEL, ffff, [(ffss,)], frozenset({four_wheel.parse_fault("FR:F")}))


@pytest.mark.parametrize(
    "bad",
    [
        {"shape": "round"},
        {"faults": "triples"},
        {"objective": "speed"},
        {"max_length": 0},
        {"per_action": 0},
        {"priority": "beauty"},
    ],
)
def test_bad_options(bad: dict[str, object]) -> None:
    with pytest.raises(ProblemError):
        GenerateOptions(**bad)  # type: ignore[arg-type]


# --- CLI ------------------------------------------------------------------------------------


def test_cli_generate(tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "t.json"
    code = main(
        [
            "table",
            "generate",
            "--domain",
            "three-action",
            "--shape",
            "fault-indexed",
            "--per-action",
            "2",
            "-o",
            str(out),
        ]
    )
    assert code == 0
    assert "9 entries" in capsys.readouterr().out
    table = load_table(out)
    assert table.shape == "fault-indexed"
    assert table.parameters["per_action"] == 2


def test_cli_generate_rejects_bad_choices(
    tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = str(tmp_path / "t.json")
    assert main(["table", "generate", "--faults", "triples", "-o", out]) == 2
    assert "--faults" in capsys.readouterr().err
    assert main(["table", "generate", "--domain", "six-legs", "-o", out]) == 2


def test_cli_generate_priority_is_recorded(tmp_path: pathlib.Path) -> None:
    out = tmp_path / "walls.json"
    args = ["table", "generate", "--faults", "singles", "--priority", "walls", "-o", str(out)]
    assert main(args) == 0
    assert load_table(out).parameters["priority"] == "walls"


def test_no_fault_scope_gives_the_cheapest_other_way_first() -> None:
    table = generate_table(FOUR_WHEEL, GenerateOptions(faults="none", per_action=2))
    ffff = four_wheel.parse_action("FFFF")
    first = table.candidates(ffff)[0]
    assert len(first) == 1 and first[0].motion == ffff.motion and first[0].duration == 2
