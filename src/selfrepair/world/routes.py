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

:func:`random_routes` draws seeded routes for any maze (``selfrepair maze routes``, ``maze generate
--routes`` and the experiments' ``routes = N`` use it).
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Heading, Pose, parse_cell, parse_pose
from selfrepair.limits import MAX_FILE_BYTES
from selfrepair.textio import read_text, strip_bom, text_lines
from selfrepair.world.maze import Maze

__all__ = [
    "MAX_ROUTES",
    "Route",
    "check_route",
    "format_routes",
    "load_routes",
    "parse_routes",
    "random_routes",
    "save_routes",
]

MAX_ROUTES = 10_000
"""Most routes :func:`random_routes` draws in one call (each costs a search over the maze)."""

_T = TypeVar("_T")
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
    start = _parse_field(parse_pose, pose_field, source, number)
    goal = _parse_field(parse_cell, goal_field, source, number)
    return Route(name.group(), start, goal)


def _parse_field(
    parse: Callable[[str], _T], field: re.Match[str], source: str, number: int
) -> _T:
    """``parse`` of one field of a route line; its error names the field's line and column."""
    try:
        return parse(field.group())
    except InputError as exc:
        raise InputError(exc.reason, source=source, line=number, column=field.start() + 1) from exc


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


def load_routes(
    path: str | Path, *, maze: Maze | None = None, max_file_bytes: int | None = MAX_FILE_BYTES
) -> tuple[Route, ...]:
    """Read a route file (see the module docstring); with ``maze``, check starts and goals. A
    file over ``max_file_bytes`` (:data:`selfrepair.limits.MAX_FILE_BYTES`; ``None``: no
    limit) is refused unread."""
    path = Path(path)
    text = read_text(path, what="route file", max_bytes=max_file_bytes, limit="max_file_bytes")
    return parse_routes(text, source=str(path), maze=maze)


def save_routes(
    routes: Iterable[Route], path: str | Path, *, comments: Sequence[str] = ()
) -> None:
    """Write ``routes`` to ``path`` in the route-file format."""
    Path(path).write_text(format_routes(routes, comments=comments), encoding="utf-8")


def random_routes(maze: Maze, count: int, seed: int) -> tuple[Route, ...]:
    """``count`` seeded routes named ``q1``, ``q2``, ...: a random free start cell and heading,
    and a goal drawn among the reachable cells at least half the largest 4-connected distance away
    (so routes are long). The same maze, count and seed give the same routes."""
    if not 1 <= count <= MAX_ROUTES:
        raise InputError(
            f"expected a route count from 1 to {MAX_ROUTES}, got {count}", source="<routes>"
        )
    if seed < 0:
        raise InputError(f"expected a non-negative seed, got {seed}", source="<routes>")
    rng = np.random.default_rng(seed)
    free = maze.free_cells()
    if len(free) < 2:
        raise InputError("expected a maze with at least two free cells for random routes")
    routes = []
    for n in range(count):
        start = free[int(rng.integers(len(free)))]
        distances = _bfs(maze, start)
        far = max(distances.values())
        candidates = sorted(c for c, d in distances.items() if d * 2 >= far and d > 0)
        if not candidates:
            candidates = sorted(c for c in distances if c != start) or [start]
        goal = candidates[int(rng.integers(len(candidates)))]
        heading = Heading(int(rng.integers(4)))
        routes.append(Route(f"q{n + 1}", Pose(start[0], start[1], heading), goal))
    return tuple(routes)


def _bfs(maze: Maze, start: Cell) -> dict[Cell, int]:
    """4-connected distances from ``start`` (a turn in place needs only the robot's own cell, so
    4-connectivity is exactly what the robot can reach)."""
    distances = {start: 0}
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
            if (nx, ny) not in distances and maze.is_free(nx, ny):
                distances[(nx, ny)] = distances[(x, y)] + 1
                queue.append((nx, ny))
    return distances
