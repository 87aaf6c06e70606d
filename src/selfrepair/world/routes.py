"""Routes (a start pose and a goal cell) and the small text format of route files.

Route-file format, one route per line::

    # comments start with '#', anywhere on a line; blank lines are ignored
    NAME X,Y,H X,Y

``NAME`` is a word without whitespace or ``#`` (unique within the file), ``X,Y,H`` the start pose
(column, row, heading N/E/S/W) and ``X,Y`` the goal cell, separated by whitespace. Coordinates
follow the maze: ``x`` is the column, ``y`` the row, origin top-left. Example::

    # maze: narrow-short
    r1 1,1,E 13,13
    r2 13,1,S 1,13

A route only asks for the robot's cell to reach the goal; the heading at the goal is free.
Parse errors name the file, the line and the column of the offending field, and what was expected.
Lines end at ``\\n`` or ``\\r\\n`` only, and a leading UTF-8 byte-order mark is ignored.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Pose, parse_cell, parse_pose
from selfrepair.textio import read_text, strip_bom, text_lines
from selfrepair.world.maze import Maze

__all__ = [
    "Route",
    "check_route",
    "format_routes",
    "load_routes",
    "parse_routes",
    "save_routes",
]

_FIELD = re.compile(r"\S+")


@dataclass(frozen=True, slots=True)
class Route:
    """A mission: drive from ``start`` (a pose) until the robot stands on ``goal`` (a cell)."""

    name: str
    start: Pose
    goal: Cell

    def __str__(self) -> str:
        return f"{self.name} {self.start} {self.goal[0]},{self.goal[1]}"


def parse_routes(
    text: str, *, source: str = "<string>", maze: Maze | None = None
) -> tuple[Route, ...]:
    """Parse a route file's text; with ``maze``, also check every start and goal is free."""
    routes: list[Route] = []
    seen: dict[str, int] = {}
    for number, raw in enumerate(text_lines(strip_bom(text)), start=1):
        content = raw.split("#", 1)[0]
        fields = list(_FIELD.finditer(content))
        if not fields:
            continue
        route = _parse_line(fields, number, source)
        if route.name in seen:
            raise InputError(
                f"expected a unique route name, but {route.name!r} is already used on line "
                f"{seen[route.name]}",
                source=source,
                line=number,
                column=fields[0].start() + 1,
            )
        seen[route.name] = number
        if maze is not None:
            _check(route, maze, source, number, fields)
        routes.append(route)
    return tuple(routes)


def _parse_line(fields: Sequence[re.Match[str]], number: int, source: str) -> Route:
    if len(fields) != 3:
        column = fields[3].start() + 1 if len(fields) > 3 else fields[-1].end() + 1
        raise InputError(
            f"expected 3 fields 'NAME X,Y,H X,Y', got {len(fields)}",
            source=source,
            line=number,
            column=column,
        )
    name, pose_field, goal_field = fields
    try:
        start = parse_pose(pose_field.group())
    except InputError as exc:
        raise InputError(
            exc.reason, source=source, line=number, column=pose_field.start() + 1
        ) from exc
    try:
        goal = parse_cell(goal_field.group())
    except InputError as exc:
        raise InputError(
            exc.reason, source=source, line=number, column=goal_field.start() + 1
        ) from exc
    return Route(name.group(), start, goal)


def _check(
    route: Route, maze: Maze, source: str, number: int | None, fields: Sequence[re.Match[str]] = ()
) -> None:
    for index, label, (x, y) in ((1, "start", route.start.cell), (2, "goal", route.goal)):
        column = fields[index].start() + 1 if fields else None
        if not maze.in_bounds(x, y):
            raise InputError(
                f"expected the {label} of route {route.name!r} inside the "
                f"{maze.width}x{maze.height} maze, got ({x},{y})",
                source=source,
                line=number,
                column=column,
            )
        if not maze.is_free(x, y):
            raise InputError(
                f"expected the {label} of route {route.name!r} on a free cell, but ({x},{y}) is a "
                "wall",
                source=source,
                line=number,
                column=column,
            )


def check_route(route: Route, maze: Maze, *, source: str = "<route>") -> None:
    """Raise :class:`~selfrepair.errors.InputError` unless start and goal are inside and free."""
    _check(route, maze, source, None)


def format_routes(routes: Iterable[Route], *, comments: Sequence[str] = ()) -> str:
    """The route-file text for ``routes``, preceded by ``comments`` as ``# ...`` lines."""
    lines = [f"# {c}".rstrip() for c in comments]
    for route in routes:
        if not route.name or _FIELD.fullmatch(route.name) is None or "#" in route.name:
            raise InputError(
                f"expected a route name without whitespace or '#', got {route.name!r}",
                source="<routes>",
            )
        lines.append(str(route))
    return "".join(line + "\n" for line in lines)


def load_routes(path: str | Path, *, maze: Maze | None = None) -> tuple[Route, ...]:
    """Read a route file (see the module docstring); with ``maze``, check starts and goals."""
    path = Path(path)
    return parse_routes(read_text(path, what="route file"), source=str(path), maze=maze)


def save_routes(
    routes: Iterable[Route], path: str | Path, *, comments: Sequence[str] = ()
) -> None:
    """Write ``routes`` to ``path`` in the route-file format."""
    Path(path).write_text(format_routes(routes, comments=comments), encoding="utf-8")
