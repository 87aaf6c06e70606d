"""Reading a maze file in whichever format it is: the one place that knows both readers.

:mod:`selfrepair.world.maze` (plain text) and :mod:`selfrepair.world.movingai` (``.map``) each read
one format; this module sits above both and picks by file suffix.
"""

from __future__ import annotations

from pathlib import Path

from selfrepair.errors import InputError
from selfrepair.world.maze import Maze, parse_maze
from selfrepair.world.movingai import load_map

__all__ = ["load_maze"]


def load_maze(path: str | Path, *, name: str | None = None) -> Maze:
    """Read a maze file: MovingAI ``.map`` by suffix, else the plain-text format."""
    path = Path(path)
    if path.suffix == ".map":
        return load_map(path, name=name)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(f"cannot read maze file: {exc.strerror}", source=str(path)) from exc
    except UnicodeDecodeError as exc:
        raise InputError("expected a UTF-8 text maze file", source=str(path)) from exc
    return parse_maze(text, source=str(path), name=name if name is not None else path.stem)
