"""Grid mazes: the :class:`Maze` value, its plain-text format and its clearance map.

Plain-text format: one line per row, ``#`` for a wall, ``.`` for a free cell; ``S`` and ``G`` marks
are accepted as free cells (they are not kept). Row ``y`` is the ``y``-th line, column ``x`` the
character index, as in MovingAI maps. Only ``\\n`` and ``\\r\\n`` end a row (a form feed or U+2028
is a bad character of its row); blank lines may only come at the end; a leading UTF-8 byte-order
mark is ignored. A maze of more than ``max_cells`` cells (default
:data:`selfrepair.limits.MAX_CELLS`) is refused before its cells are read.

MovingAI ``.map`` files are read by :mod:`selfrepair.world.movingai`; :func:`load_maze` picks the
reader by file suffix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import InputError
from selfrepair.geometry import Cell, FreeGrid
from selfrepair.limits import MAX_CELLS, check_limit
from selfrepair.textio import strip_bom, text_lines

__all__ = [
    "Maze",
    "believed_maze",
    "clearance_map",
    "clearance_penalties",
    "format_maze",
    "parse_maze",
    "save_maze",
]

WALL_CHAR = "#"
FREE_CHAR = "."
_FREE_MARKS = frozenset(".SG")


@dataclass(frozen=True, slots=True, eq=False)
class Maze:
    """A rectangular grid of free cells and walls; outside the grid counts as wall.

    ``walls`` is a read-only boolean array of shape ``(height, width)`` indexed ``[y, x]``.
    Equality and hashing look at the walls only, not at the name.
    """

    walls: npt.NDArray[np.bool_]
    name: str = ""
    _key: bytes = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        walls = np.array(self.walls, dtype=bool, copy=True)
        if walls.ndim != 2 or walls.shape[0] < 1 or walls.shape[1] < 1:
            raise ValueError(f"maze walls must be a non-empty 2-D array, got shape {walls.shape}")
        walls.setflags(write=False)
        object.__setattr__(self, "walls", walls)
        key = walls.shape[0].to_bytes(4, "little") + np.packbits(walls).tobytes()
        object.__setattr__(self, "_key", key)

    @property
    def width(self) -> int:
        """Number of columns."""
        return int(self.walls.shape[1])

    @property
    def height(self) -> int:
        """Number of rows."""
        return int(self.walls.shape[0])

    def in_bounds(self, x: int, y: int) -> bool:
        """Whether ``(x, y)`` lies on the grid."""
        return 0 <= x < self.width and 0 <= y < self.height

    def is_free(self, x: int, y: int) -> bool:
        """Whether ``(x, y)`` lies on the grid and is not a wall."""
        return self.in_bounds(x, y) and not bool(self.walls[y, x])

    def all_free(self, cells: tuple[Cell, ...] | list[Cell]) -> bool:
        """Whether every cell in ``cells`` is free: the executability test for swept cells."""
        return all(self.is_free(x, y) for x, y in cells)

    def free_grid(self, margin: int = 2) -> FreeGrid:
        """The free cells as a :class:`~selfrepair.geometry.FreeGrid` with ``margin`` wall cells
        around the grid (built once per maze and margin; a few are kept)."""
        return _FREE_GRIDS.get((self, margin), lambda: _free_grid(self, margin))

    def free_cells(self) -> list[Cell]:
        """Every free cell, row by row."""
        ys, xs = np.nonzero(~self.walls)
        return [(int(x), int(y)) for y, x in zip(ys, xs, strict=True)]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Maze):
            return NotImplemented
        return self._key == other._key and self.walls.shape == other.walls.shape

    def __hash__(self) -> int:
        return hash(self._key)

    def __str__(self) -> str:
        return format_maze(self)


_FREE_GRIDS: BoundedCache[tuple[Maze, int], FreeGrid] = BoundedCache(
    "maze free grids", 8, kind=CacheKind.PLAN, per_map=True
)


def _free_grid(maze: Maze, margin: int) -> FreeGrid:
    padded = np.zeros((maze.height + 2 * margin, maze.width + 2 * margin), dtype=np.uint8)
    padded[margin : margin + maze.height, margin : margin + maze.width] = ~maze.walls
    return FreeGrid(maze.width, maze.height, margin, padded.tobytes())


def parse_maze(
    text: str, *, source: str = "<string>", name: str = "", max_cells: int | None = MAX_CELLS
) -> Maze:
    """Parse the plain-text format; errors name ``source``, the line and the column.

    A maze of more than ``max_cells`` cells raises :class:`~selfrepair.errors.LimitError` before
    any cell is read (``None``: no limit).
    """
    rows = text_lines(strip_bom(text))
    while rows and not rows[-1].strip():
        rows.pop()
    if not rows:
        raise InputError(
            "expected at least one row of '#' and '.', got an empty maze", source=source
        )
    width = len(rows[0])
    check_limit(
        len(rows) * width,
        max_cells,
        name="max_cells",
        what="cells",
        detail=f"{width} columns x {len(rows)} rows",
        source=source,
    )
    for y, row in enumerate(rows):
        if not row.strip():
            raise InputError(
                "expected a row of '#' and '.', got an empty line", source=source, line=y + 1
            )
        if len(row) != width:
            raise InputError(
                f"expected {width} cells in every row (as in row 1), got {len(row)}",
                source=source,
                line=y + 1,
                column=min(len(row), width) + 1,
            )
    walls = np.zeros((len(rows), width), dtype=bool)
    for y, row in enumerate(rows):
        for x, char in enumerate(row):
            if char == WALL_CHAR:
                walls[y, x] = True
            elif char not in _FREE_MARKS:
                raise InputError(
                    f"expected '#' (wall), '.', 'S' or 'G' (free), got {char!r}",
                    source=source,
                    line=y + 1,
                    column=x + 1,
                )
    return Maze(walls, name=name)


def format_maze(maze: Maze) -> str:
    """The plain-text form of ``maze``, one line per row with a final newline."""
    lut = np.array([FREE_CHAR, WALL_CHAR])
    return "".join("".join(lut[row.astype(np.intp)]) + "\n" for row in maze.walls)


def save_maze(maze: Maze, path: str | Path) -> None:
    """Write ``maze`` in the plain-text format."""
    Path(path).write_text(format_maze(maze), encoding="utf-8")


def clearance_map(maze: Maze) -> npt.NDArray[np.int32]:
    """Chebyshev distance from every cell to the nearest wall, computed once per maze.

    Walls get 0, a free cell touching a wall (also diagonally) gets 1, and so on. The area outside
    the grid counts as wall, so a free cell on the border has clearance 1. The array is read-only,
    shaped ``(height, width)`` and indexed ``[y, x]``.
    """
    return _CLEARANCE.get(maze, lambda: _clearance(maze))


_CLEARANCE: BoundedCache[Maze, npt.NDArray[np.int32]] = BoundedCache(
    "maze clearance maps", 8, kind=CacheKind.PLAN, per_map=True
)


def _clearance(maze: Maze) -> npt.NDArray[np.int32]:
    h, w = maze.walls.shape
    blocked = np.ones((h + 2, w + 2), dtype=bool)
    blocked[1:-1, 1:-1] = maze.walls
    dist = np.zeros((h + 2, w + 2), dtype=np.int32)
    reached = blocked.copy()
    level = 0
    while not reached.all():
        level += 1
        grown = reached.copy()
        # A 3x3 dilation is the Chebyshev ball of radius 1: two separable 1-D passes.
        grown[1:, :] |= reached[:-1, :]
        grown[:-1, :] |= reached[1:, :]
        rows = grown.copy()
        grown[:, 1:] |= rows[:, :-1]
        grown[:, :-1] |= rows[:, 1:]
        dist[grown & ~reached] = level
        reached = grown
    result = dist[1:-1, 1:-1].copy()
    result.setflags(write=False)
    return result


def clearance_penalties(maze: Maze, radius: int) -> npt.NDArray[np.int64]:
    """``max(0, radius - clearance)`` per cell, as an ``int64`` array ``[y, x]``."""
    return np.maximum(0, radius - clearance_map(maze).astype(np.int64))


def believed_maze(maze: Maze, blocked: frozenset[Cell]) -> Maze:
    """``maze`` with the cells ``blocked`` (world events the robot believes in) as walls: the map
    the robot plans on in a changing world (the last few are kept)."""
    return _BELIEVED.get((maze, blocked), lambda: _with_walls(maze, blocked))


def _with_walls(maze: Maze, blocked: frozenset[Cell]) -> Maze:
    walls = maze.walls.copy()
    for x, y in blocked:
        if maze.in_bounds(x, y):
            walls[y, x] = True
    return Maze(walls, name=maze.name)


_BELIEVED: BoundedCache[tuple[Maze, frozenset[Cell]], Maze] = BoundedCache(
    "mazes with believed-blocked cells", 4, kind=CacheKind.PLAN, per_map=True
)
