"""Reading a maze file in whichever format it is: the one place that knows both readers.

:mod:`selfrepair.world.maze` (plain text) and :mod:`selfrepair.world.movingai` (``.map``) each read
one format; this module sits above both and picks by file suffix.
"""

from __future__ import annotations

from pathlib import Path

from selfrepair.limits import MAX_CELLS, maze_file_bytes
from selfrepair.textio import read_text
from selfrepair.world.maze import Maze, parse_maze
from selfrepair.world.movingai import load_map

__all__ = ["load_maze"]


def load_maze(
    path: str | Path, *, name: str | None = None, max_cells: int | None = MAX_CELLS
) -> Maze:
    """Read a maze file: MovingAI ``.map`` by suffix, else the plain-text format.

    A file too big to hold ``max_cells`` cells is refused before it is read
    (:func:`selfrepair.limits.maze_file_bytes`), a maze of more cells before its cells are read.
    """
    path = Path(path)
    if path.suffix == ".map":
        return load_map(path, name=name, max_cells=max_cells)
    text = read_text(
        path, what="maze file", max_bytes=maze_file_bytes(max_cells), limit="max_cells"
    )
    name = name if name is not None else path.stem
    return parse_maze(text, source=str(path), name=name, max_cells=max_cells)
