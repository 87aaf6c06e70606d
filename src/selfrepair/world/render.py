"""ASCII pictures of mazes with overlays (robot poses, goals, paths).

Plain text so that the CLI, the docs and test failure messages can all show the same picture.
A picture is the maze in its plain-text format (``#`` wall, ``.`` free) with zero or more *layers*
drawn on top: each layer maps cells to one character, and later layers overwrite earlier ones.
Cells of a layer that lie outside the grid are ignored, so callers need not clip.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.world.maze import FREE_CHAR, WALL_CHAR, Maze
from selfrepair.world.routes import Route

__all__ = [
    "GOAL_CHAR",
    "HEADING_CHARS",
    "PATH_CHAR",
    "legend",
    "path_layer",
    "pose_layer",
    "render_ascii",
    "route_index_char",
    "route_layers",
]

HEADING_CHARS: dict[Heading, str] = {
    Heading.N: "^",
    Heading.E: ">",
    Heading.S: "v",
    Heading.W: "<",
}
"""The character that shows a robot facing each heading."""

GOAL_CHAR = "G"
"""The character that marks a goal cell."""

PATH_CHAR = "o"
"""The character that marks a cell a path passes through."""

_LEGEND: tuple[tuple[str, str], ...] = (
    (WALL_CHAR, "wall"),
    (FREE_CHAR, "free"),
    ("^ > v <", "robot pose facing N, E, S, W"),
    (GOAL_CHAR, "goal"),
    (PATH_CHAR, "swept by the path"),
)


def render_ascii(maze: Maze, layers: Sequence[Mapping[Cell, str]] = ()) -> str:
    """The maze as text, one line per row with a final newline, with ``layers`` drawn on top.

    Each layer maps ``(x, y)`` cells to a single character; later layers overwrite earlier ones.
    Off-grid cells are skipped. A layer value that is not exactly one character raises
    :class:`ValueError` because it would shift the rest of the row.
    """
    grid = [
        [WALL_CHAR if wall else FREE_CHAR for wall in row] for row in maze.walls.tolist()
    ]
    for layer in layers:
        for (x, y), char in layer.items():
            if len(char) != 1:
                raise ValueError(f"overlay characters must be one character long, got {char!r}")
            if maze.in_bounds(x, y):
                grid[y][x] = char
    return "".join("".join(row) + "\n" for row in grid)


def pose_layer(poses: Iterable[Pose]) -> dict[Cell, str]:
    """A layer showing each pose as its heading character."""
    return {pose.cell: HEADING_CHARS[pose.heading] for pose in poses}


def path_layer(cells: Iterable[Cell], char: str = PATH_CHAR) -> dict[Cell, str]:
    """A layer marking every cell in ``cells`` with ``char``."""
    return dict.fromkeys(cells, char)


_INDEX_CHARS = "123456789"


def route_index_char(index: int) -> str:
    """The character that marks the goal of route number ``index`` (1-based) in a multi-route
    picture: ``1`` to ``9``, then ``*``."""
    return _INDEX_CHARS[index - 1] if 1 <= index <= len(_INDEX_CHARS) else "*"


def route_layers(routes: Sequence[Route]) -> list[dict[Cell, str]]:
    """Layers that show each route's start pose as its heading character and its goal.

    With one route the goal is ``G``; with several, each goal is its route's number (see
    :func:`route_index_char`) so the picture says which goal belongs to which start. Start
    poses are drawn last, so a start is never hidden by another route's goal.
    """
    if len(routes) == 1:
        goals = {routes[0].goal: GOAL_CHAR}
    else:
        goals = {r.goal: route_index_char(i) for i, r in enumerate(routes, start=1)}
    return [goals, pose_layer(r.start for r in routes)]


def legend(extra: Iterable[tuple[str, str]] = ()) -> str:
    """A short key to the characters, one ``char  meaning`` per line, with a final newline.

    ``extra`` adds caller-specific entries such as ``("1-4", "route start / goal index")``.
    """
    entries = (*_LEGEND, *extra)
    width = max(len(char) for char, _ in entries)
    return "".join(f"{char:<{width}}  {meaning}\n" for char, meaning in entries)
