"""The four bundled mazes and their routes: the reference experiment's data.

They ship as package data (``selfrepair/data/mazes/<name>.maze`` and ``<name>.routes``) and were
made with :func:`selfrepair.world.mazegen.generate_maze`; each route file's header records the exact
command and how its routes were chosen. Together they cover short and long, simple (perfect) and
complex (braided, with loops), narrow (1-cell) and wide (2- and 3-cell) corridors. In a 1-cell
corridor no ARC motion fits (an arc sweeps a 2x2 block), so there a robot that lost its turns in
place has no substitute; in wide corridors arcs can stand in. See ``docs/mazes.md``.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import InputError
from selfrepair.limits import MAX_CELLS
from selfrepair.world.loading import load_maze
from selfrepair.world.maze import Maze, parse_maze
from selfrepair.world.routes import Route, parse_routes

__all__ = [
    "BundledMaze",
    "bundled_routes",
    "describe",
    "load_bundled",
    "maze_names",
    "resolve_maze",
]


@dataclass(frozen=True, slots=True)
class BundledMaze:
    """What a bundled maze is for: corridor width and a one-line character sketch."""

    name: str
    corridor: int
    summary: str


_CATALOGUE: dict[str, BundledMaze] = {
    m.name: m
    for m in (
        BundledMaze(
            "narrow-short", 1, "15x15, 1-cell corridors, perfect (no loops): short and simple"
        ),
        BundledMaze(
            "wide-short", 2, "25x25, 2-cell corridors, perfect (no loops): short and simple"
        ),
        BundledMaze(
            "narrow-long",
            1,
            "49x49, 1-cell corridors, braided (30% of dead ends opened): long and complex",
        ),
        BundledMaze(
            "wide-long",
            3,
            "61x61, 3-cell corridors, braided (40% of dead ends opened): long and complex",
        ),
    )
}


def maze_names() -> tuple[str, ...]:
    """The bundled maze names, short ones first."""
    return tuple(_CATALOGUE)


def describe(name: str) -> BundledMaze:
    """The catalogue entry of a bundled maze."""
    return _CATALOGUE[_check_name(name)]


def _check_name(name: str) -> str:
    if name not in _CATALOGUE:
        raise InputError(
            f"unknown maze {name!r}: expected one of {', '.join(maze_names())} "
            "or a path to a maze file (.maze text or MovingAI .map)",
            source="<maze>",
        )
    return name


def _data_text(filename: str) -> str:
    return resources.files("selfrepair").joinpath("data", "mazes", filename).read_text("utf-8")


_MAZES: BoundedCache[str, Maze] = BoundedCache("bundled mazes", 32, kind=CacheKind.INPUT)
_ROUTES: BoundedCache[str, tuple[Route, ...]] = BoundedCache(
    "bundled routes", 32, kind=CacheKind.INPUT
)


def load_bundled(name: str) -> Maze:
    """The bundled maze ``name`` (see :func:`maze_names`), parsed once per process."""
    _check_name(name)
    return _MAZES.get(
        name,
        lambda: parse_maze(_data_text(f"{name}.maze"), source=f"<bundled {name}.maze>", name=name),
    )


def bundled_routes(name: str) -> tuple[Route, ...]:
    """The four routes of bundled maze ``name``, checked against the maze."""

    def parse() -> tuple[Route, ...]:
        maze = load_bundled(name)
        text = _data_text(f"{name}.routes")
        return parse_routes(text, source=f"<bundled {name}.routes>", maze=maze)

    return _ROUTES.get(name, parse)


def resolve_maze(spec: str, *, max_cells: int | None = MAX_CELLS) -> Maze:
    """A maze from a bundled name, a plain-text maze file or a MovingAI ``.map`` file.

    A bundled name wins over a file of the same name in the working directory. An unknown name
    that is not an existing file raises :class:`~selfrepair.errors.InputError` listing the
    bundled names. A file is checked against ``max_cells`` (see :func:`load_maze`).
    """
    if spec in _CATALOGUE:
        return load_bundled(spec)
    path = Path(spec)
    if path.is_file():
        return load_maze(path, max_cells=max_cells)
    _check_name(spec)
    raise AssertionError("unreachable")  # pragma: no cover
