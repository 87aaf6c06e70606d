"""Replacement tables: the shipped tables, the file format, validation and look-ups."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.errors import LimitError, TableError
from selfrepair.robots import four_wheel
from selfrepair.robots.domain import run_open
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.tables.fileformat import (
    bundled_table,
    bundled_table_names,
    dump_table,
    load_table,
    parse_table,
)
from selfrepair.tables.model import ReplacementTable, TableEntry, check_table

A = four_wheel.parse_action
F = four_wheel.parse_faults


def _seq(text: str) -> tuple[four_wheel.Action, ...]:
    return tuple(A(t) for t in text.split())


def test_bundled_tables_are_listed() -> None:
    assert {"handwritten", "three-action"} <= set(bundled_table_names())


def test_handwritten_table_covers_all_81_actions_by_motion_class() -> None:
    table = bundled_table()
    assert (table.domain, table.shape, table.made_by, table.version) == (
        FOUR_WHEEL,
        "fault-agnostic",
        "hand",
        1,
    )
    assert len(table.entries) == 81
    assert table.actions_with_entries() == frozenset(four_wheel.ACTIONS)
    by_class: dict[str, set[tuple[four_wheel.Action, ...]]] = {}
    for entry in table.entries:
        assert 4 <= len(entry.candidates) <= 5
        assert all(entry.action not in c for c in entry.candidates)
        target = four_wheel.step(FOUR_WHEEL.canonical, entry.action)[0]
        for candidate in entry.candidates:
            assert run_open(FOUR_WHEEL, FOUR_WHEEL.canonical, candidate) == target
        by_class.setdefault(entry.action.motion.name, set()).update(entry.candidates)
    # Five hand-written candidates per motion class, nine classes.
    assert len(by_class) == 9
    assert all(len(c) == 5 for c in by_class.values())
    assert check_table(table) == []


def test_handwritten_table_has_the_obvious_human_ideas() -> None:
    table = bundled_table()
    assert _seq("FBFB FBFB FBFB") in table.candidates(A("BFBF"))  # left = three rights
    assert _seq("FBFB FBFB BBBB FBFB FBFB") in table.candidates(A("FFFF"))  # turn round, back
    assert _seq("FFSS") == table.candidates(A("FFFF"))[0]  # a slower forward first


def test_dump_is_deterministic_and_round_trips(tmp_path: Path) -> None:
    table = bundled_table()
    text = dump_table(table)
    assert text.endswith("\n") and text == dump_table(parse_table(text))
    path = tmp_path / "t.json"
    path.write_text(text)
    assert load_table(path) == table
    data = json.loads(text)
    assert data["format"] == "selfrepair-table" and list(data) == sorted(data)
    shipped = Path(__file__).parents[1] / "src/selfrepair/data/tables/handwritten.json"
    assert shipped.read_text() == text


def _table_text(entries: list[dict[str, object]], shape: str = "fault-agnostic") -> str:
    return json.dumps(
        {
            "format": "selfrepair-table",
            "version": 1,
            "domain": "four-wheel",
            "shape": shape,
            "made_by": "hand",
            "parameters": {},
            "entries": entries,
        },
        indent=1,
    )


def test_wrong_end_state_is_rejected_naming_file_entry_and_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.json"
    path.write_text(
        _table_text(
            [
                {"action": "FFFF", "candidates": [["SSFF"]]},
                {"action": "BFBF", "candidates": [["FBFB"]]},
            ]
        )
    )
    with pytest.raises(TableError) as err:
        load_table(path)
    message = str(err.value)
    assert str(path) in message and "entry 1 (action BFBF" in message
    assert "expected 0,0,W" in message and "ends at 0,0,E" in message
    lines = path.read_text().splitlines()
    assert err.value.line == 1 + next(i for i, t in enumerate(lines) if '"BFBF"' in t)


def test_candidate_containing_the_replaced_action_is_rejected() -> None:
    text = _table_text([{"action": "BFBF", "candidates": [["BFBF", "FBFB", "BFBF"]]}])
    with pytest.raises(TableError, match="contains the replaced action BFBF"):
        parse_table(text, source="mine.json")


@pytest.mark.parametrize(
    ("mutation", "expected"),
    [
        ({"format": "other"}, "selfrepair-table"),
        ({"version": 2}, "expected version 1"),
        ({"domain": "hexapod"}, "expected a domain"),
        ({"shape": "round"}, "expected shape"),
        ({"made_by": "elves"}, "expected made_by"),
        ({"entries": [{"action": "QQQQ", "candidates": []}]}, "entry 0"),
        ({"entries": [{"action": "FFFF", "candidates": [[]]}]}, "empty"),
        ({"entries": [{"action": "FFFF", "faults": "FL:F", "candidates": []}]}, 'no "faults"'),
        ({"version": True}, '"version" to be an integer, got true'),
        ({"version": 1.0}, '"version" to be an integer, got 1.0'),
        ({"version": "1"}, '"version" to be an integer'),
        ({"domain": ["four-wheel"]}, "'domain' to be a string"),
        ({"shape": 1}, "'shape' to be a string"),
        ({"made_by": None}, "'made_by' to be a string"),
        ({"parameters": []}, '"parameters" to be an object'),
        ({"parameters": {"k": {"deep": 1}}}, '"parameters" values'),
        ({"parameters": {"k": [[1]]}}, '"parameters" values'),
    ],
)
def test_malformed_tables_are_rejected(mutation: dict[str, object], expected: str) -> None:
    data = json.loads(_table_text([]))
    data.update(mutation)
    with pytest.raises(TableError, match=expected):
        parse_table(json.dumps(data), source="x.json")


@pytest.mark.parametrize(
    ("text", "message", "line", "column"),
    [
        ("[" * 100_000, "nested at most 8 deep", 1, 9),  # was a RecursionError
        ('{"a": "[[[[[[[[[[\\"[[[[[[[[[", "b":\n [[[[[[[[]]]]]]]]}', "nested", 2, 9),
        ('{"format": "selfrepair-table", "version": 1' + "0" * 5000 + "}", "18 digits", 1, 43),
        ('{"format": "selfrepair-table",\n "version": NaN}', "got NaN", 2, 13),
        ('{"format": "selfrepair-table", "version": -Infinity}', "got -Infinity", 1, 43),
        ('{"format": "selfrepair-table", "version": 1e400}', "finite number", 1, 43),
    ],
)
def test_hostile_json_is_a_table_error_with_its_place(
    text: str, message: str, line: int, column: int
) -> None:
    with pytest.raises(TableError, match=message) as err:
        parse_table(text, source="x.json")
    assert (err.value.source, err.value.line, err.value.column) == ("x.json", line, column)


def test_nesting_the_format_needs_and_escaped_quotes_are_accepted() -> None:
    entry = {"action": "FFFF", "candidates": [["SFFS"]]}
    data = json.loads(_table_text([entry]))
    data["parameters"] = {"note": 'a "quoted" [[[[[[[[[[ \\', "list": [1, 2.5, None, True]}
    table = parse_table(json.dumps(data))
    assert table.parameters["note"].endswith("\\")
    assert parse_table("\ufeff" + json.dumps(data)) == table  # a byte-order mark is ignored


def test_candidate_count_over_the_limit_is_refused_before_re_simulation() -> None:
    entry = {"action": "FFFF", "candidates": [["QQQQ"], ["SFFS"]]}  # QQQQ would fail re-simulation
    with pytest.raises(LimitError, match="at most 1 candidates, got 2") as err:
        parse_table(_table_text([entry]), source="x.json", max_table_candidates=1)
    assert err.value.limit == "max_table_candidates" and "--max-table-candidates" in str(err.value)
    with pytest.raises(TableError, match="QQQQ"):
        parse_table(_table_text([entry]), source="x.json", max_table_candidates=2)


def test_table_file_over_the_byte_limit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "big.json"
    path.write_text(_table_text([]) + " " * 1000, encoding="utf-8")
    size = path.stat().st_size
    with pytest.raises(LimitError, match=f"table file of at most 1,000 bytes, got {size:,}"):
        load_table(path, max_table_bytes=1000)
    assert load_table(path, max_table_bytes=size).entries == ()
    with pytest.raises(LimitError, match="max-table-bytes"):
        parse_table(_table_text([]), max_table_bytes=10)


def test_table_file_that_is_not_utf8_names_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "latin1.json"
    path.write_bytes(_table_text([]).encode() + b"\n\xe9")
    with pytest.raises(TableError, match="UTF-8") as err:
        load_table(path)
    assert err.value.column == 1 and err.value.line == _table_text([]).count("\n") + 2


def test_bad_json_names_line() -> None:
    with pytest.raises(TableError) as err:
        parse_table('{\n "format": \n}', source="x.json")
    assert err.value.line == 3


def _indexed() -> ReplacementTable:
    fwd = A("FFFF")
    return ReplacementTable(
        FOUR_WHEEL,
        "fault-indexed",
        "generator",
        (
            TableEntry(fwd, (_seq("SSFF"),), F("FL:F")),
            TableEntry(fwd, (_seq("FFSS"), _seq("FSSF")), F("RL:F")),
            TableEntry(fwd, (_seq("SFFS"), _seq("SSFF")), F("")),
            TableEntry(fwd, (_seq("FBFB FBFB BBBB FBFB FBFB"),), F("FL:F,RL:F")),
        ),
        {"max_length": 5},
    )


def test_fault_indexed_lookup_exact_then_subsets_largest_first() -> None:
    table = _indexed()
    fwd = A("FFFF")
    assert table.candidates(fwd, F("FL:F,RL:F")) == (_seq("FBFB FBFB BBBB FBFB FBFB"),)
    assert table.candidates(fwd, F("FL:F")) == (_seq("SSFF"),)
    # No entry for {FL:F, RR:B}: subsets {FL:F} then {} (size 1 before size 0), deduplicated.
    assert table.candidates(fwd, F("FL:F,RR:B")) == (_seq("SSFF"), _seq("SFFS"))
    assert table.candidates(fwd, F("FL:F,RL:F,RR:B")) == (
        _seq("FBFB FBFB BBBB FBFB FBFB"),
        _seq("SSFF"),
        _seq("FFSS"),
        _seq("FSSF"),
        _seq("SFFS"),
    )
    assert table.candidates(A("BBBB"), F("FL:F")) == ()
    assert dump_table(parse_table(dump_table(table))) == dump_table(table)


def test_check_table_flags_dead_candidates_in_indexed_tables() -> None:
    table = ReplacementTable(
        FOUR_WHEEL,
        "fault-indexed",
        "generator",
        (TableEntry(A("FFFF"), (_seq("FFSS"),), F("FL:F")),),
    )
    problems = check_table(table)
    errors = [p for p in problems if p.severity == "error"]
    assert len(errors) == 1 and "FFSS" in errors[0].message
    assert sum(1 for p in problems if "has no candidates" in p.message) == 80


def test_duplicate_keys_are_rejected() -> None:
    entry = TableEntry(A("FFFF"), (_seq("FFSS"),))
    with pytest.raises(TableError, match="second one"):
        ReplacementTable(FOUR_WHEEL, "fault-agnostic", "hand", (entry, entry))


def test_docs_list_the_hand_written_candidates_of_each_class() -> None:
    doc = (Path(__file__).parents[1] / "docs/replacement.md").read_text()
    table = bundled_table()
    by_class: dict[str, set[str]] = {}
    for entry in table.entries:
        for candidate in entry.candidates:
            by_class.setdefault(entry.action.motion.name, set()).add(
                " ".join(a.code for a in candidate)
            )
    for name, candidates in by_class.items():
        line = next(t for t in doc.splitlines() if t.startswith(f"| {name} |"))
        listed = {c.strip().strip("`") for c in line.split("|")[2].split(";")}
        assert listed == candidates, name


def test_tables_are_hashable_values() -> None:
    table = bundled_table()
    again = parse_table(dump_table(table))
    assert table == again and hash(table) == hash(again)
    assert len({table, again, bundled_table("three-action")}) == 2


_FORWARDS = ["FFSS", "SSFF", "FSSF", "SFFS", "FBFB FBFB BBBB FBFB FBFB", "BFBF BFBF BBBB BFBF BFBF"]
_FAULTS = [frozenset(), *FOUR_WHEEL.fault_sets[:12], *FOUR_WHEEL.fault_sets[12:30]]


@settings(max_examples=150, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(_FAULTS),
        st.lists(st.sampled_from(_FORWARDS), max_size=3, unique=True),
        max_size=8,
    ),
    st.sets(st.sampled_from(four_wheel.SINGLE_FAULTS), max_size=3),
)
def test_fault_indexed_lookup_properties(index, known_set) -> None:  # type: ignore[no-untyped-def]
    fwd = A("FFFF")
    known = frozenset(known_set)
    entries = tuple(
        TableEntry(fwd, tuple(_seq(c) for c in cands), faults) for faults, cands in index.items()
    )
    table = ReplacementTable(FOUR_WHEEL, "fault-indexed", "generator", entries)
    got = table.candidates(fwd, known)
    if known in index:
        assert got == tuple(_seq(c) for c in index[known])
    else:
        subsets = sorted((f for f in index if f <= known), key=len, reverse=True)
        expected = {_seq(c) for f in subsets for c in index[f]}
        assert len(got) == len(set(got)) and set(got) == expected
        # A candidate of a larger indexed subset comes before one only found in smaller ones.
        rank = {}
        for f in subsets:
            for c in index[f]:
                rank.setdefault(_seq(c), len(f))
        sizes = [rank[c] for c in got]
        assert sizes == sorted(sizes, reverse=True)
    again = parse_table(dump_table(table))
    assert again.candidates(fwd, known) == got
