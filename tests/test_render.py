"""ASCII rendering of mazes and overlays."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from selfrepair.geometry import Heading, Pose
from selfrepair.world.maze import Maze, format_maze, parse_maze
from selfrepair.world.render import (
    HEADING_CHARS,
    legend,
    path_layer,
    pose_layer,
    render_ascii,
    route_index_char,
    route_layers,
)
from selfrepair.world.routes import Route

MAZE = parse_maze("#####\n#...#\n#.#.#\n#####\n")


@given(hnp.arrays(bool, st.tuples(st.integers(1, 9), st.integers(1, 9))))
def test_without_layers_the_picture_is_the_plain_text_format(walls: np.ndarray) -> None:
    maze = Maze(walls)
    assert render_ascii(maze) == format_maze(maze)


def test_heading_chars() -> None:
    assert HEADING_CHARS == {Heading.N: "^", Heading.E: ">", Heading.S: "v", Heading.W: "<"}


def test_later_layers_overwrite_and_off_grid_cells_are_ignored() -> None:
    picture = render_ascii(MAZE, [{(1, 1): "a", (3, 2): "b"}, {(1, 1): "c", (9, 9): "z"}])
    assert picture == "#####\n#c..#\n#.#b#\n#####\n"


def test_pose_and_path_layers() -> None:
    layers = [path_layer([(1, 1), (2, 1), (3, 1)]), pose_layer([Pose(1, 1, Heading.S)])]
    assert render_ascii(MAZE, layers) == "#####\n#voo#\n#.#.#\n#####\n"


def test_layer_values_must_be_single_characters() -> None:
    with pytest.raises(ValueError, match="one character"):
        render_ascii(MAZE, [{(1, 1): "ab"}])


def test_route_layers_mark_goal_g_for_one_route_and_numbers_for_several() -> None:
    one = [Route("a", Pose(1, 1, Heading.E), (3, 2))]
    assert render_ascii(MAZE, route_layers(one)) == "#####\n#>..#\n#.#G#\n#####\n"
    two = [*one, Route("b", Pose(3, 1, Heading.W), (1, 2))]
    assert render_ascii(MAZE, route_layers(two)) == "#####\n#>.<#\n#2#1#\n#####\n"


def test_route_index_chars() -> None:
    assert [route_index_char(i) for i in (1, 4, 9, 10)] == ["1", "4", "9", "*"]


def test_legend_lists_every_character() -> None:
    text = legend([("1-4", "route goals")])
    for char in ("#", ".", "^ > v <", "G", "o", "1-4"):
        assert any(line.startswith(char) for line in text.splitlines())
    assert text.endswith("\n")
