"""The Maze value, its plain-text format and the clearance map."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from selfrepair.errors import InputError, LimitError
from selfrepair.world.loading import load_maze
from selfrepair.world.maze import Maze, clearance_map, format_maze, parse_maze, save_maze

wall_grids = hnp.arrays(
    dtype=bool,
    shape=st.tuples(st.integers(1, 12), st.integers(1, 12)),
    elements=st.booleans(),
)


@given(wall_grids)
def test_format_parse_round_trip(walls: np.ndarray) -> None:
    maze = Maze(walls)
    text = format_maze(maze)
    assert text.endswith("\n") and len(text.splitlines()) == maze.height
    again = parse_maze(text)
    assert again == maze
    assert np.array_equal(again.walls, walls)
    assert format_maze(again) == text


def test_parse_geometry_and_marks() -> None:
    maze = parse_maze("####\n#S.#\n#.G#\n####\n")
    assert (maze.width, maze.height) == (4, 4)
    assert maze.is_free(1, 1) and maze.is_free(2, 2) and maze.is_free(2, 1)
    assert not maze.is_free(0, 0) and not maze.is_free(4, 1) and not maze.is_free(-1, 1)
    assert maze.all_free(((1, 1), (2, 1))) and not maze.all_free(((1, 1), (3, 1)))
    assert maze.free_cells() == [(1, 1), (2, 1), (1, 2), (2, 2)]
    assert format_maze(maze) == "####\n#..#\n#..#\n####\n"


def test_walls_are_read_only_and_equality_ignores_name() -> None:
    maze = parse_maze("#.\n..\n", name="a")
    with pytest.raises(ValueError):
        maze.walls[0, 0] = False
    assert maze == parse_maze("#.\n..\n", name="b")
    assert hash(maze) == hash(parse_maze("#.\n..\n"))
    assert maze != parse_maze("#..\n...\n")


def test_ragged_row_names_line_and_column() -> None:
    with pytest.raises(InputError) as info:
        parse_maze("####\n#..#\n#.#\n####\n", source="m.maze")
    err = info.value
    assert (err.source, err.line, err.column) == ("m.maze", 3, 4)
    assert "expected 4 cells" in str(err) and str(err).startswith("m.maze:3:4:")


def test_unknown_character_names_line_and_column() -> None:
    with pytest.raises(InputError) as info:
        parse_maze("####\n#.x#\n####\n", source="m.maze")
    assert (info.value.line, info.value.column) == (2, 3)
    assert "'x'" in str(info.value)


def test_empty_maze_is_an_error() -> None:
    with pytest.raises(InputError, match="empty"):
        parse_maze("\n\n")


@pytest.mark.parametrize(("text", "line"), [("\n....\n", 1), ("....\n\n....\n", 2)])
def test_blank_line_inside_a_maze_is_named(text: str, line: int) -> None:
    with pytest.raises(InputError, match="empty line") as info:
        parse_maze(text, source="m.maze")
    assert info.value.line == line


@pytest.mark.parametrize("separator", ["\u2028", "\x0c", "\r", "\x85", "\x1e"])
def test_only_line_feeds_end_a_row(separator: str) -> None:
    # str.splitlines also splits at U+2028, form feeds, lone CRs and more: "#...#<sep>#...#" was
    # read as two good rows. It is one row of 11 characters, too long from column 6 on.
    text = "#####\n#...#" + separator + "#...#\n#####\n"
    with pytest.raises(InputError, match=r"expected 5 cells.*got 11") as info:
        parse_maze(text, source="m.maze")
    assert (info.value.line, info.value.column) == (2, 6)
    with pytest.raises(InputError, match=re.escape(repr(separator))):
        parse_maze("#....#" + separator + "#\n", source="m.maze")


def test_crlf_line_ends_and_a_byte_order_mark_are_accepted() -> None:
    plain = parse_maze("#####\n#...#\n#####\n")
    assert parse_maze("\ufeff#####\r\n#...#\r\n#####\r\n") == plain


def test_byte_order_mark_in_a_file_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "bom.maze"
    path.write_bytes(b"\xef\xbb\xbf#####\n#...#\n#####\n")
    assert load_maze(path) == parse_maze("#####\n#...#\n#####\n")


def test_a_file_that_is_not_utf8_names_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "latin1.maze"
    path.write_bytes(b"#####\n#.\xe9.#\n#####\n")
    with pytest.raises(InputError, match=r"UTF-8.*0xe9") as info:
        load_maze(path)
    assert (info.value.line, info.value.column) == (2, 3)


def test_maze_over_the_cell_limit_is_refused_before_its_cells_are_read() -> None:
    text = "#####\n#...#\n#####\n"
    message = r"at most 14 cells, got 15 \(5 columns x 3 rows\)"
    with pytest.raises(LimitError, match=message) as info:
        parse_maze(text, source="m.maze", max_cells=14)
    assert "--max-cells" in str(info.value) and info.value.limit == "max_cells"
    assert parse_maze(text, max_cells=15).width == 5
    assert parse_maze(text, max_cells=None).width == 5
    with pytest.raises(LimitError):  # the limit comes before the bad character
        parse_maze(text.replace(".", "x"), max_cells=14)


def test_maze_file_too_big_for_the_cell_limit_is_refused_unread(tmp_path: Path) -> None:
    path = tmp_path / "big.maze"
    path.write_text("#" * 70_000 + "\n", encoding="utf-8")
    with pytest.raises(LimitError, match="maze file of at most 65,539 bytes, got 70,001"):
        load_maze(path, max_cells=1)
    assert load_maze(path).width == 70_000


def test_save_and_load(tmp_path: Path) -> None:
    maze = parse_maze("###\n#.#\n###\n")
    path = tmp_path / "tiny.maze"
    save_maze(maze, path)
    loaded = load_maze(path)
    assert loaded == maze and loaded.name == "tiny"
    with pytest.raises(InputError, match="cannot read"):
        load_maze(tmp_path / "missing.maze")


def brute_force_clearance(walls: np.ndarray) -> np.ndarray:
    """Chebyshev distance to the nearest wall cell or off-grid cell, by enumeration."""
    h, w = walls.shape
    blocked = [(x, y) for y in range(-1, h + 1) for x in range(-1, w + 1)
               if not (0 <= x < w and 0 <= y < h) or walls[y, x]]
    out = np.zeros((h, w), dtype=np.int64)
    for y in range(h):
        for x in range(w):
            out[y, x] = min(max(abs(x - bx), abs(y - by)) for bx, by in blocked)
    return out


@given(wall_grids)
def test_clearance_matches_brute_force(walls: np.ndarray) -> None:
    got = clearance_map(Maze(walls))
    assert got.shape == walls.shape
    assert np.array_equal(got, brute_force_clearance(walls))


def test_clearance_of_an_open_room() -> None:
    maze = parse_maze("#######\n#.....#\n#.....#\n#.....#\n#######\n")
    c = clearance_map(maze)
    assert c[2, 3] == 2 and c[1, 1] == 1 and c[0, 0] == 0
    assert not c.flags.writeable
