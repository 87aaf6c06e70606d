"""MovingAI maps and both generations of scenario files (data in tests/data/movingai/)."""

from __future__ import annotations

from pathlib import Path

import pytest

from selfrepair.errors import InputError, LimitError
from selfrepair.world.loading import load_maze
from selfrepair.world.movingai import load_map, load_scenario, parse_map, parse_scenario

DATA = Path(__file__).parent / "data" / "movingai"

SMALL_MAP = "type octile\nheight 3\nwidth 4\nmap\n@@@@\n@.G@\n@TS@\n"


def test_parse_small_map_with_all_passable_and_blocked_characters() -> None:
    maze = parse_map(SMALL_MAP, name="small")
    assert (maze.width, maze.height, maze.name) == (4, 3, "small")
    assert maze.free_cells() == [(1, 1), (2, 1), (2, 2)]
    blocked = parse_map("type octile\nheight 1\nwidth 4\nmap\n@OTW\n")
    assert blocked.free_cells() == []


@pytest.mark.parametrize("name", ["maze512-1-0", "maze512-4-0", "maze512-32-9"])
def test_full_maps_load(name: str) -> None:
    maze = load_map(DATA / f"{name}.map")
    assert (maze.width, maze.height, maze.name) == (512, 512, name)
    assert load_maze(DATA / f"{name}.map") == maze  # load_maze picks the reader by suffix
    free_share = len(maze.free_cells()) / (512 * 512)
    expected = {"maze512-1-0": 0.50, "maze512-4-0": 0.80, "maze512-32-9": 0.97}[name]
    assert abs(free_share - expected) < 0.03


def test_map_coordinates_are_column_and_row() -> None:
    maze = load_map(DATA / "maze512-1-0.map")
    # Row 1 of the file starts "@.........@.@": x is the character index, y the row.
    assert not maze.is_free(0, 1)
    assert maze.is_free(1, 1) and maze.is_free(9, 1)
    assert not maze.is_free(10, 1)
    assert maze.is_free(1, 2) and not maze.is_free(2, 2)


def test_hog2_scenario_generation() -> None:
    maze = load_map(DATA / "maze512-1-0.map")
    queries = load_scenario(DATA / "maze512-1-0.map.scen", maze=maze)
    assert len(queries) == 11960
    first = queries[0]
    assert (first.bucket, first.map_name) == (1, "maps/mazes/maze512-1-0.map")
    assert (first.start, first.goal, first.optimal_length, first.line) == (
        (407, 136), (405, 134), 4.0, 2
    )
    assert all(maze.is_free(*q.start) and maze.is_free(*q.goal) for q in queries)


def test_newer_scenario_generation() -> None:
    maze = load_map(DATA / "maze512-32-9.map")
    queries = load_scenario(DATA / "maze512-32-9.map.scen", maze=maze)
    assert len(queries) == 8010
    first, last = queries[0], queries[-1]
    assert (first.bucket, first.map_name) == (0, "maze512-32-9.map")
    assert first.optimal_length == pytest.approx(3.41421356, abs=1e-9)
    assert (last.bucket, last.line) == (800, 8011)


SCEN_HEADER = "version 1\n"


def scen_line(sx: int, sy: int, gx: int, gy: int, width: int = 4, height: int = 3) -> str:
    return f"0\tsmall.map\t{width}\t{height}\t{sx}\t{sy}\t{gx}\t{gy}\t1.00000000\n"


def test_small_scenario_parses() -> None:
    maze = parse_map(SMALL_MAP)
    (query,) = parse_scenario(SCEN_HEADER + scen_line(1, 1, 2, 2), maze=maze)
    assert (query.start, query.goal, query.width, query.height) == ((1, 1), (2, 2), 4, 3)


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("height 3\nwidth 4\nmap\n....\n", 3, "'type' header field"),
        ("type octile\nwidth 4\nmap\n....\n", 3, "'height' header field"),
        ("type octile\nheight 1\nmap\n....\n", 3, "'width' header field"),
        ("type octile\nheight 1\nwidth 4\n", 3, "'map' line"),
        ("type octile\nheight x\nwidth 4\nmap\n....\n", 2, "positive integer height"),
        ("type octile\nheight 1\nwidth ²\nmap\n....\n", 3, "positive integer width"),
        ("type octile\nsize 4\nmap\n", 2, "header line"),
        ("type octile\nheight 2\nwidth 4\nmap\n....\n", 6, "expected 2 map rows"),
        ("type octile\nheight 1\nwidth 4\nmap\n...\n", 5, "expected 4 cells"),
        ("type octile\nheight 1\nwidth 4\nmap\n..x.\n", 5, "'x'"),
        ("type hex\nheight 1\nwidth 4\nmap\n....\n", 1, "type octile"),
        ("type octile\nheight 1\nwidth 4\nmap\n....\n....\n", 6, "found more"),
        ("type octile\nheight 1\nwidth 99999999999999\nmap\n....\n", 3, "at most 4,194,304 cells"),
        ("type octile\nheight 3\nheight 4\nwidth 3\nmap\n...\n...\n...\n", 3, "second one"),
        ("type octile\nwidth 3\nheight 1\nwidth 4\nmap\n....\n", 4, "first is line 2"),
        ("type octile\ntype octile\nheight 1\nwidth 1\nmap\n.\n", 2, "one 'type' header"),
        ("type octile\nheight 1" + "0" * 5000 + "\nwidth 4\nmap\n", 2, "at most 18 digits"),
        ("type octile\nheight 1\nwidth 4\nmap\n..\x0c.\n", 5, r"got '\\x0c'"),
        ("type octile\nheight 2\nwidth 2\nmap\n..\u2028..\n", 6, "expected 2 map rows"),
    ],
)
def test_map_errors(text: str, line: int, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        parse_map(text, source="bad.map")
    assert info.value.source == "bad.map"
    assert info.value.line == line
    assert str(info.value).startswith(f"bad.map:{line}")


def test_empty_map_is_reported_without_a_line_number() -> None:
    with pytest.raises(InputError, match="empty file") as info:
        parse_map("", source="empty.map")
    assert info.value.line is None
    assert str(info.value) == (
        "empty.map: expected a MovingAI map starting with 'type octile', got an empty file"
    )


def test_map_with_byte_order_mark_and_crlf_line_ends_parses() -> None:
    assert parse_map("\ufeff" + SMALL_MAP.replace("\n", "\r\n")) == parse_map(SMALL_MAP)


def test_map_declaring_more_cells_than_the_limit_is_refused_before_its_rows() -> None:
    text = "type octile\nheight 3\nwidth 4\nmap\n"  # no rows at all: the limit comes first
    with pytest.raises(LimitError, match=r"got 12 \(height 3 x width 4\)") as info:
        parse_map(text, source="big.map", max_cells=11)
    assert info.value.limit == "max_cells" and info.value.line == 3
    assert "--max-cells" in str(info.value)
    assert parse_map(SMALL_MAP, max_cells=12).width == 4


def test_map_file_too_big_for_the_cell_limit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "big.map"
    path.write_text(SMALL_MAP + "\n" * 70_000, encoding="utf-8")
    with pytest.raises(LimitError, match="bytes"):
        load_map(path, max_cells=1)
    assert load_map(path).width == 4  # blank lines after the rows are fine within the limit


def test_map_error_names_column_of_bad_character() -> None:
    with pytest.raises(InputError) as info:
        parse_map("type octile\nheight 1\nwidth 4\nmap\n..x.\n", source="bad.map")
    assert info.value.column == 3


@pytest.mark.parametrize(("row", "column"), [("...", 4), (".....", 5)])
def test_map_error_names_column_where_a_ragged_row_goes_wrong(row: str, column: int) -> None:
    with pytest.raises(InputError) as info:
        parse_map(f"type octile\nheight 1\nwidth 4\nmap\n{row}\n", source="bad.map")
    assert (info.value.line, info.value.column) == (5, column)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (scen_line(4, 1, 2, 2), "start \\(4,1\\) inside the 4x3 map"),
        (scen_line(1, 1, 2, -1), "goal \\(2,-1\\) inside"),
        (scen_line(0, 0, 2, 2), "start \\(0,0\\) on a free cell"),
        (scen_line(1, 1, 1, 2), "goal \\(1,2\\) on a free cell"),
        (scen_line(1, 1, 2, 2, width=5), "map size 4x3"),
        (scen_line(5, 1, 2, 2, width=6), "map size 4x3"),  # size first, not "a wall"
        ("0\tsmall.map\t4\t3\t1\t1\n", "expected 9 fields"),
        ("0\tsmall.map\t4\t3\ta\t1\t2\t2\t1.0\n", "integer start_x"),
        ("0\tsmall.map\t4\t3\t1\t--1\t2\t2\t1.0\n", "integer start_y"),
        ("0\tsmall.map\t4\t3\t1\t1\t²\t2\t1.0\n", "integer goal_x"),
        ("0\tsmall.map\t4\t3\t1\t1\t2\t2\tfar\n", "number optimal_length"),
        ("0\tsmall.map\t4\t3\t1\t1\t2\t2\tnan\n", "finite non-negative number"),
        ("0\tsmall.map\t4\t3\t1\t1\t2\t2\tinf\n", "finite non-negative number"),
        ("0\tsmall.map\t4\t3\t1\t1\t2\t2\t-1.5\n", "finite non-negative number"),
        ("0\tsmall.map\t4\t3\t1\t1\t2\t2\t1e400\n", "finite non-negative number"),
        ("0\tsmall.map\t4\t3\t1\t1\t2\t2\t1_0\n", "finite non-negative number"),
        ("0\tsmall.map\t4\t3\t1" + "0" * 5000 + "\t1\t2\t2\t1\n", "at most 18 digits"),
    ],
)
def test_scenario_errors(body: str, message: str) -> None:
    maze = parse_map(SMALL_MAP)
    text = SCEN_HEADER + scen_line(1, 1, 2, 2) + body
    with pytest.raises(InputError, match=message) as info:
        parse_scenario(text, source="bad.scen", maze=maze)
    assert (info.value.source, info.value.line) == ("bad.scen", 3)
    if "9 fields" not in message:
        assert info.value.column is not None and info.value.column > 1


def test_fields_may_carry_surrounding_whitespace_of_any_kind() -> None:
    # Found by the fuzz tests: "\x1c1.0" passed the number check after strip() but float() does
    # not strip \x1c, so it raised a ValueError.
    text = SCEN_HEADER + "0\tsmall.map\t4\t3\t1\t1\t2\t2\t\x1c1.5 \n"
    assert parse_scenario(text)[0].optimal_length == 1.5


def test_scenario_lines_end_only_at_line_feeds() -> None:
    # A form feed inside a line used to split it in two, and later errors named the wrong line.
    text = SCEN_HEADER + scen_line(1, 1, 2, 2).replace("\t2\t2", "\t2\x0c\t2") + "bad\n"
    with pytest.raises(InputError, match="9 fields") as info:
        parse_scenario(text, source="bad.scen")
    assert info.value.line == 3
    crlf = "\ufeff" + (SCEN_HEADER + scen_line(1, 1, 2, 2)).replace("\n", "\r\n")
    assert parse_scenario(crlf)[0].goal == (2, 2)


def test_scenario_error_column_points_at_the_field() -> None:
    line = "0\tsmall.map\t4\t3\t1\t1\t9\t2\t1.0\n"
    with pytest.raises(InputError, match="goal") as info:
        parse_scenario(SCEN_HEADER + line, source="bad.scen", maze=parse_map(SMALL_MAP))
    assert info.value.column == line.index("\t9\t") + 2


def test_scenario_needs_version_line() -> None:
    with pytest.raises(InputError, match="version 1") as info:
        parse_scenario(scen_line(1, 1, 2, 2), source="bad.scen")
    assert info.value.line == 1


def test_missing_files_are_input_errors(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot read"):
        load_map(tmp_path / "none.map")
    with pytest.raises(InputError, match="cannot read"):
        load_scenario(tmp_path / "none.map.scen")
