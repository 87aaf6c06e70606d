"""Grid geometry shared by every layer: cells, headings, poses, and their text forms.

Coordinates follow MovingAI maps: ``x`` is the column, ``y`` the row, origin top-left. Headings
are N, E, S, W with N = (0, -1) and E = (+1, 0). A robot's state in a maze is a :class:`Pose`:
the cell it stands on and the way it faces. Mazes, robots, planners and tables all speak in these
values, so they live here, below all of them (this module imports nothing of selfrepair but
:mod:`selfrepair.errors`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields
from enum import IntEnum

from selfrepair.errors import InputError

__all__ = [
    "Cell",
    "FreeGrid",
    "Heading",
    "Pose",
    "make_pose",
    "parse_cell",
    "parse_pose",
    "relative_cell",
    "turn_corner",
]

Cell = tuple[int, int]
"""A grid cell ``(x, y)``."""


class Heading(IntEnum):
    """Compass heading; the integer value counts quarter turns clockwise from north."""

    N = 0
    E = 1
    S = 2
    W = 3

    @property
    def vector(self) -> Cell:
        """Unit step ``(dx, dy)`` in the direction the robot faces."""
        return _HEADING_VECTORS[self]

    @property
    def right(self) -> Cell:
        """Unit step ``(dx, dy)`` to the robot's right."""
        return _HEADING_VECTORS[(self + 1) % 4]

    def rotated(self, quarter_turns: int) -> Heading:
        """The heading after ``quarter_turns`` clockwise quarter turns (negative: anticlockwise)."""
        return _HEADINGS[(self + quarter_turns) % 4]  # the member by index: no enum call


_HEADING_VECTORS: tuple[Cell, ...] = ((0, -1), (1, 0), (0, 1), (-1, 0))
_HEADINGS: tuple[Heading, ...] = tuple(Heading)


@dataclass(frozen=True, slots=True, order=True)
class Pose:
    """Where the robot is and which way it faces."""

    x: int
    y: int
    heading: Heading

    @property
    def cell(self) -> Cell:
        """The cell the robot occupies."""
        return (self.x, self.y)

    def __str__(self) -> str:
        return f"{self.x},{self.y},{self.heading.name}"


def _pose_maker() -> Callable[[int, int, Heading], Pose]:
    """A :class:`~selfrepair.geometry.Pose` constructor for the hot paths (plan paths, simulator
    steps) that fills the three slots directly: the same value as ``Pose(x, y, heading)`` at a
    third of the cost of the frozen dataclass's ``__init__``. Falls back to the class itself should
    ``Pose`` ever validate its fields (a ``__post_init__``) or change its fields."""
    names = tuple(f.name for f in fields(Pose))
    if hasattr(Pose, "__post_init__") or names != ("x", "y", "heading"):
        return Pose
    new = object.__new__
    set_x, set_y, set_heading = (getattr(Pose, name).__set__ for name in names)

    def make(x: int, y: int, heading: Heading) -> Pose:
        pose = new(Pose)
        set_x(pose, x)
        set_y(pose, y)
        set_heading(pose, heading)
        return pose

    return make


make_pose: Callable[[int, int, Heading], Pose] = _pose_maker()
"""``make_pose(x, y, heading) == Pose(x, y, heading)``, built faster (see :func:`_pose_maker`;
:mod:`selfrepair.search.problem` re-exports it)."""


def relative_cell(pose: Pose, forward: int, lateral: int) -> Cell:
    """The world cell ``forward`` cells ahead of and ``lateral`` cells right of ``pose``."""
    fx, fy = _HEADING_VECTORS[pose.heading]
    rx, ry = _HEADING_VECTORS[(pose.heading + 1) % 4]
    return (pose.x + forward * fx + lateral * rx, pose.y + forward * fy + lateral * ry)


def turn_corner(start: Pose, end: Pose) -> Cell | None:
    """The corner of a move from ``start`` to ``end`` that turns a quarter and leaves both the
    line through ``start`` along its heading and the line through ``end`` along its heading: the
    cell where those two lines cross (for the four-wheel robot's arcs, the cell it sweeps between
    its start and end cells). ``None`` for every other move (in place, straight, sideways, a half
    turn): those are drawn as straight segments, an arc as a quarter ellipse tangent to both
    headings."""
    if (end.heading - start.heading) % 2 == 0:
        return None
    corner = (end.x, start.y) if start.heading.vector[0] else (start.x, end.y)
    return None if corner in (start.cell, end.cell) else corner


# --- pose and cell text ------------------------------------------------------------------------


def parse_cell(text: str, *, source: str = "<cell>") -> Cell:
    """Parse ``"X,Y"`` into a cell."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2 or not all(_is_int(p) for p in parts):
        raise InputError(f"expected a cell X,Y with integer X and Y, got {text!r}", source=source)
    return (int(parts[0]), int(parts[1]))


def parse_pose(text: str, *, source: str = "<pose>") -> Pose:
    """Parse ``"X,Y,H"`` (H one of N, E, S, W) into a pose."""
    parts = [p.strip() for p in text.split(",")]
    if (
        len(parts) != 3
        or not all(_is_int(p) for p in parts[:2])
        or parts[2].upper() not in Heading.__members__
    ):
        raise InputError(
            f"expected a pose X,Y,H with integer X, Y and H in N, E, S, W, got {text!r}",
            source=source,
        )
    return Pose(int(parts[0]), int(parts[1]), Heading[parts[2].upper()])


_MAX_DIGITS = 18
"""Longest coordinate accepted; keeps ``int()`` far from Python's 4300-digit conversion limit."""


def _is_int(text: str) -> bool:
    body = text[1:] if text[:1] in ("+", "-") else text
    return body.isascii() and body.isdigit() and len(body) <= _MAX_DIGITS


@dataclass(frozen=True, slots=True, eq=False)
class FreeGrid:
    """Which cells of a ``width`` x ``height`` grid are free: one byte per cell (1 free, 0 wall) in
    a flat row-major buffer, padded with ``margin`` never-free cells on every side.

    This is what the layers that must not know mazes (tables, repair) test footprints against:
    ``all_free`` is the executability test for an action's cells, and a cell at most ``margin``
    cells outside the grid can be looked up with no bounds check (:meth:`index`). Build one with
    :meth:`selfrepair.world.maze.Maze.free_grid`.
    """

    width: int
    height: int
    margin: int
    data: bytes

    @property
    def stride(self) -> int:
        """Bytes per padded row."""
        return self.width + 2 * self.margin

    def index(self, x: int, y: int) -> int:
        """The buffer index of cell ``(x, y)``; valid for cells at most ``margin`` outside."""
        return (y + self.margin) * self.stride + x + self.margin

    def is_free(self, x: int, y: int) -> bool:
        """Whether ``(x, y)`` lies on the grid and is free."""
        return 0 <= x < self.width and 0 <= y < self.height and self.data[self.index(x, y)] == 1

    def all_free(self, cells: Iterable[Cell]) -> bool:
        """Whether every cell of ``cells`` lies on the grid and is free (:meth:`is_free`, inlined:
        this is the executability test of every simulated step)."""
        width, height, margin, data = self.width, self.height, self.margin, self.data
        stride = width + 2 * margin
        for x, y in cells:
            if (
                not (0 <= x < width and 0 <= y < height)
                or data[(y + margin) * stride + x + margin] != 1
            ):
                return False
        return True
