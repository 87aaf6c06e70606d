"""Routes and the route-file format."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.errors import InputError
from selfrepair.geometry import Heading, Pose
from selfrepair.world.maze import parse_maze
from selfrepair.world.routes import (
    Route,
    check_route,
    format_routes,
    load_routes,
    parse_routes,
    save_routes,
)

MAZE = parse_maze("#####\n#...#\n#.#.#\n#...#\n#####\n")


def test_parse_with_comments_and_blank_lines() -> None:
    text = "# header\n\nr1 1,1,E 3,3   # trailing comment\n  r2\t3,3,n  1,3\n"
    routes = parse_routes(text, maze=MAZE)
    assert routes == (
        Route("r1", Pose(1, 1, Heading.E), (3, 3)),
        Route("r2", Pose(3, 3, Heading.N), (1, 3)),
    )


names = st.text(alphabet="abcxyz_-0123456789", min_size=1, max_size=8)
routes_strategy = st.lists(
    st.builds(
        Route,
        names,
        st.builds(Pose, st.integers(-5, 99), st.integers(-5, 99), st.sampled_from(list(Heading))),
        st.tuples(st.integers(-5, 99), st.integers(-5, 99)),
    ),
    max_size=6,
    unique_by=lambda r: r.name,
)


@given(routes_strategy)
def test_format_parse_round_trip(routes: list[Route]) -> None:
    text = format_routes(routes, comments=["made by a test"])
    assert text.startswith("# made by a test\n")
    assert parse_routes(text) == tuple(routes)


def test_save_and_load(tmp_path: Path) -> None:
    routes = (Route("a", Pose(1, 1, Heading.S), (3, 1)),)
    path = tmp_path / "x.routes"
    save_routes(routes, path)
    assert load_routes(path, maze=MAZE) == routes
    with pytest.raises(InputError, match="cannot read route file"):
        load_routes(tmp_path / "missing.routes")


@pytest.mark.parametrize(
    ("line", "column", "message"),
    [
        ("r1 1,1,E", 9, "expected 3 fields"),
        ("r1 1,1,E 3,3 extra", 14, "expected 3 fields"),
        ("r1 1,1 3,3", 4, "expected a pose X,Y,H"),
        ("r1 1,1,Q 3,3", 4, "expected a pose X,Y,H"),
        ("r1 1,1,E 3;3", 10, "expected a cell X,Y"),
        ("r1   1,1,E x,3", 12, "expected a cell X,Y"),
    ],
)
def test_syntax_errors_name_file_line_column(line: str, column: int, message: str) -> None:
    text = "# ok\nr0 1,1,E 3,3\n" + line + "\n"
    with pytest.raises(InputError, match=message) as info:
        parse_routes(text, source="x.routes")
    err = info.value
    assert (err.source, err.line, err.column) == ("x.routes", 3, column)
    assert str(err).startswith(f"x.routes:3:{column}: ")


def test_lines_end_only_at_line_feeds_and_a_byte_order_mark_is_ignored(tmp_path: Path) -> None:
    # A form feed or U+2028 used to split a line, so later errors named the wrong line.
    text = "\ufeffr0 1,1,E 3,3\r\nr1 1,1,E\x0c3,3\nr2 1,1,E\u20283,3\nbad\n"
    with pytest.raises(InputError, match="expected 3 fields") as info:
        parse_routes(text, source="x.routes")
    assert info.value.line == 4
    path = tmp_path / "bom.routes"
    path.write_bytes(b"\xef\xbb\xbfr0 1,1,E 3,3\n\xe9\n")
    with pytest.raises(InputError, match="UTF-8") as info:
        load_routes(path)
    assert (info.value.line, info.value.column) == (2, 1)


def test_duplicate_name_is_an_error() -> None:
    with pytest.raises(InputError, match=r"unique route name.*line 1") as info:
        parse_routes("a 1,1,E 3,3\na 1,1,E 3,1\n", source="x.routes")
    assert (info.value.line, info.value.column) == (2, 1)


@pytest.mark.parametrize(
    ("line", "column", "message"),
    [
        ("r 0,0,E 3,3", 3, "start of route 'r' on a free cell"),
        ("r 1,1,E 2,2", 9, "goal of route 'r' on a free cell"),
        ("r 9,1,E 3,3", 3, "start of route 'r' inside the 5x5 maze"),
        ("r 1,1,E 3,-1", 9, "goal of route 'r' inside"),
    ],
)
def test_validation_against_the_maze(line: str, column: int, message: str) -> None:
    with pytest.raises(InputError, match=message) as info:
        parse_routes(line + "\n", source="x.routes", maze=MAZE)
    assert (info.value.line, info.value.column) == (1, column)
    parse_routes(line + "\n")  # without a maze only the syntax is checked


def test_check_route() -> None:
    check_route(Route("ok", Pose(1, 1, Heading.E), (3, 3)), MAZE)
    with pytest.raises(InputError, match="wall"):
        check_route(Route("bad", Pose(2, 2, Heading.E), (3, 3)), MAZE)


def test_format_rejects_names_that_would_not_parse() -> None:
    for bad in ("", "two words", "a#b"):
        with pytest.raises(InputError, match="route name"):
            format_routes([Route(bad, Pose(1, 1, Heading.E), (3, 3))])
