"""Pictures of an episode for ``render()``: an RGB frame (numpy only) and the ASCII picture.

The RGB frame draws every cell as a ``cell_pixels`` square: walls dark, free cells light, the goal
green and the robot blue, with a white bar on the side it faces. The maze part of the frame is
made once per episode (:func:`maze_frame`) and copied for every call (:func:`rgb_frame`).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.world.maze import Maze
from selfrepair.world.render import GOAL_CHAR, pose_layer, render_ascii

__all__ = ["MAX_CELL_PIXELS", "ansi_frame", "maze_frame", "rgb_frame"]

MAX_CELL_PIXELS = 64
"""The largest ``cell_pixels`` accepted (a frame is ``cell_pixels**2 * cells * 3`` bytes)."""

WALL_RGB = (40, 40, 48)
FREE_RGB = (235, 235, 228)
GOAL_RGB = (60, 170, 80)
ROBOT_RGB = (40, 90, 210)
FRONT_RGB = (255, 255, 255)

Frame = npt.NDArray[np.uint8]


def check_cell_pixels(cell_pixels: int) -> int:
    """``cell_pixels`` when it is from 2 to :data:`MAX_CELL_PIXELS`; else a ProblemError naming the
    keyword to change."""
    if not 2 <= cell_pixels <= MAX_CELL_PIXELS:
        raise ProblemError(f"cell_pixels must be from 2 to {MAX_CELL_PIXELS}, got {cell_pixels}")
    return cell_pixels


def maze_frame(maze: Maze, goal: Cell, cell_pixels: int) -> Frame:
    """The maze and its goal as an ``(height * px, width * px, 3)`` uint8 image (read-only)."""
    wall, free = np.array(WALL_RGB, dtype=np.uint8), np.array(FREE_RGB, dtype=np.uint8)
    colours = np.where(maze.walls[..., None], wall, free).astype(np.uint8)
    colours[goal[1], goal[0]] = GOAL_RGB
    frame = np.repeat(np.repeat(colours, cell_pixels, axis=0), cell_pixels, axis=1)
    frame.setflags(write=False)
    return frame


def rgb_frame(base: Frame, pose: Pose, cell_pixels: int) -> Frame:
    """A new frame: ``base`` (from :func:`maze_frame`) with the robot drawn at ``pose``."""
    frame = base.copy()
    px = cell_pixels
    top, left = pose.y * px, pose.x * px
    frame[top : top + px, left : left + px] = ROBOT_RGB
    bar = max(1, px // 4)
    rows, cols = _front(pose.heading, top, left, px, bar)
    frame[rows, cols] = FRONT_RGB
    return frame


def _front(heading: Heading, top: int, left: int, px: int, bar: int) -> tuple[slice, slice]:
    """The pixel block of the cell side the robot faces."""
    full_rows, full_cols = slice(top, top + px), slice(left, left + px)
    if heading is Heading.N:
        return slice(top, top + bar), full_cols
    if heading is Heading.S:
        return slice(top + px - bar, top + px), full_cols
    if heading is Heading.E:
        return full_rows, slice(left + px - bar, left + px)
    return full_rows, slice(left, left + bar)


def ansi_frame(maze: Maze, pose: Pose, goal: Cell, status: Iterable[str]) -> str:
    """The ASCII picture (goal ``G``, robot as its heading character) and status lines."""
    picture = render_ascii(maze, [{goal: GOAL_CHAR}, pose_layer([pose])])
    return picture + "".join(f"{line}\n" for line in status)
