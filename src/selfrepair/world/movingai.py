"""MovingAI grid benchmarks: ``.map`` files and ``.map.scen`` scenario files.

Format (Sturtevant 2012): a map starts with ``type octile``, ``height H``, ``width W`` and ``map``,
then H rows of W characters; ``.``, ``G`` and ``S`` are passable, ``@``, ``O``, ``T`` and ``W``
blocked. A scenario file starts with ``version 1``; every other line has nine tab-separated fields
``bucket map width height start_x start_y goal_x goal_y optimal_length``; the optimal length is a
finite non-negative decimal number. Both generations of
scenario files are accepted: the hog2 snapshot (map column with a path, 5 decimals) and the newer
one (bare map name, 8 decimals). Lines end at ``\\n`` or ``\\r\\n`` only, a header key may appear
once, a leading UTF-8 byte-order mark is ignored, and a map whose header declares more than
``max_cells`` cells (default :data:`selfrepair.limits.MAX_CELLS`) is refused before its rows are
read.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from selfrepair.errors import InputError
from selfrepair.geometry import Cell
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES, check_limit, maze_file_bytes
from selfrepair.textio import read_text, strip_bom, text_lines
from selfrepair.world.maze import Maze

__all__ = ["ScenarioQuery", "load_map", "load_scenario", "parse_map", "parse_scenario"]

_PASSABLE = frozenset(".GS")
_BLOCKED = frozenset("@OTW")
_HEADER_KEYS = ("type", "height", "width")
_MAX_DIGITS = 18
"""Longest integer field accepted (any real map or scenario needs at most 5 digits)."""
_DECIMAL = re.compile(r"([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?")


@dataclass(frozen=True, slots=True)
class ScenarioQuery:
    """One line of a scenario file; ``line`` is its 1-based line number in the file."""

    bucket: int
    map_name: str
    width: int
    height: int
    start: Cell
    goal: Cell
    optimal_length: float
    line: int


def parse_map(
    text: str, *, source: str = "<string>", name: str = "", max_cells: int | None = MAX_CELLS
) -> Maze:
    """Parse a MovingAI ``.map`` text into a :class:`Maze`.

    A map whose header declares more than ``max_cells`` cells raises
    :class:`~selfrepair.errors.LimitError` before its rows are read (``None``: no limit).
    """
    lines = text_lines(strip_bom(text))
    if not lines:
        raise InputError(
            "expected a MovingAI map starting with 'type octile', got an empty file", source=source
        )
    header, where, index = _parse_header(lines, source)
    height = _header_int(header, where, "height", source)
    width = _header_int(header, where, "width", source)
    check_limit(
        height * width,
        max_cells,
        name="max_cells",
        what="cells",
        detail=f"height {height} x width {width}",
        source=source,
        line=max(where["height"], where["width"]),
    )
    rows = lines[index + 1 : index + 1 + height]
    if len(rows) < height:
        raise InputError(
            f"expected {height} map rows (from the header), got {len(rows)}",
            source=source,
            line=len(lines) + 1,
        )
    for extra, text in enumerate(lines[index + 1 + height :], start=index + 2 + height):
        if text.strip():
            raise InputError(
                f"expected {height} map rows (from the header), found more",
                source=source,
                line=extra,
            )
    for y, row in enumerate(rows):  # all row lengths first: the header may claim any size
        if len(row) != width:
            raise InputError(
                f"expected {width} cells in the row (from the header), got {len(row)}",
                source=source,
                line=index + 2 + y,
                column=min(len(row), width) + 1,
            )
    walls = np.zeros((height, width), dtype=bool)
    for y, row in enumerate(rows):
        for x, char in enumerate(row):
            if char in _BLOCKED:
                walls[y, x] = True
            elif char not in _PASSABLE:
                raise InputError(
                    f"expected a map character from '.GS' (passable) or '@OTW' (blocked), "
                    f"got {char!r}",
                    source=source,
                    line=index + 2 + y,
                    column=x + 1,
                )
    return Maze(walls, name=name)


def _parse_header(lines: list[str], source: str) -> tuple[dict[str, str], dict[str, int], int]:
    """The header fields, the 1-based line of each, and the index of the ``map`` line."""
    header: dict[str, str] = {}
    where: dict[str, int] = {}
    index = 0
    while index < len(lines) and lines[index].strip() != "map":
        key, _, value = lines[index].strip().partition(" ")
        if key not in _HEADER_KEYS:
            raise InputError(
                f"expected a header line 'type', 'height', 'width' or 'map', got {lines[index]!r}",
                source=source,
                line=index + 1,
            )
        if key in header:
            raise InputError(
                f"expected one '{key}' header line, got a second one (the first is line "
                f"{where[key]})",
                source=source,
                line=index + 1,
            )
        header[key] = value.strip()
        where[key] = index + 1
        index += 1
    if index == len(lines):
        raise InputError(
            "expected a 'map' line after the header, got the end of the file",
            source=source,
            line=len(lines),
        )
    for key in _HEADER_KEYS:
        if key not in header:
            raise InputError(f"expected a '{key}' header field", source=source, line=index + 1)
    if header["type"] != "octile":
        raise InputError(
            f"expected 'type octile', got 'type {header['type']}'",
            source=source,
            line=where["type"],
        )
    return header, where, index


def _header_int(header: dict[str, str], where: dict[str, int], key: str, source: str) -> int:
    value = header[key]
    number = _small_int(value)
    if number is None or number < 1:
        raise InputError(
            f"expected a positive integer {key} of at most {_MAX_DIGITS} digits, got {value!r}",
            source=source,
            line=where[key],
        )
    return number


def _small_int(text: str) -> int | None:
    """``text`` as an integer when it is an optional ``-`` and 1 to 18 ASCII digits, else None.

    The digit bound keeps ``int()`` far from Python's 4300-digit conversion limit."""
    digits = text.removeprefix("-")
    if not (digits.isascii() and digits.isdigit() and len(digits) <= _MAX_DIGITS):
        return None
    return int(text)


def _read_text(path: Path, what: str, max_cells: int | None = None) -> str:
    max_bytes = maze_file_bytes(max_cells)
    return read_text(path, what=what, max_bytes=max_bytes, limit="max_cells")


def load_map(
    path: str | Path, *, name: str | None = None, max_cells: int | None = MAX_CELLS
) -> Maze:
    """Read a MovingAI ``.map`` file; the maze is named after the file unless ``name`` is given.

    A file too big to hold ``max_cells`` cells is refused before it is read."""
    path = Path(path)
    return parse_map(
        _read_text(path, "MovingAI map file", max_cells),
        source=str(path),
        name=name if name is not None else path.stem,
        max_cells=max_cells,
    )


def parse_scenario(
    text: str, *, source: str = "<string>", maze: Maze | None = None
) -> tuple[ScenarioQuery, ...]:
    """Parse a ``.map.scen`` text. With ``maze``, also check that starts and goals are free."""
    lines = text_lines(strip_bom(text))
    if not lines or lines[0].split() not in (["version", "1"], ["version", "1.0"]):
        raise InputError("expected the first line 'version 1'", source=source, line=1)
    queries = []
    for number, raw in enumerate(lines[1:], start=2):
        if raw.strip():
            queries.append(_parse_scenario_line(raw, number, source, maze))
    return tuple(queries)


def _parse_scenario_line(raw: str, number: int, source: str, maze: Maze | None) -> ScenarioQuery:
    fields = raw.split("\t") if "\t" in raw else raw.split()
    if len(fields) != 9:
        raise InputError(
            "expected 9 fields: bucket map width height start_x start_y goal_x goal_y "
            f"optimal_length, got {len(fields)}",
            source=source,
            line=number,
        )
    columns = _field_columns(raw, fields)
    names = ("bucket", "width", "height", "start_x", "start_y", "goal_x", "goal_y")
    ints: dict[str, int] = {}
    for key, value, column in zip(
        names, [fields[0], *fields[2:8]], [columns[0], *columns[2:8]], strict=True
    ):
        parsed = _small_int(value.strip())
        if parsed is None:
            raise InputError(
                f"expected an integer {key} of at most {_MAX_DIGITS} digits, got {value!r}",
                source=source,
                line=number,
                column=column,
            )
        ints[key] = parsed
    optimal = _optimal_length(fields[8])
    if optimal is None:
        raise InputError(
            f"expected a finite non-negative number optimal_length, got {fields[8]!r}",
            source=source,
            line=number,
            column=columns[8],
        )
    query = ScenarioQuery(
        bucket=ints["bucket"],
        map_name=fields[1],
        width=ints["width"],
        height=ints["height"],
        start=(ints["start_x"], ints["start_y"]),
        goal=(ints["goal_x"], ints["goal_y"]),
        optimal_length=optimal,
        line=number,
    )
    _check_query(query, source, maze, columns)
    return query


def _optimal_length(text: str) -> float | None:
    """A decimal number such as ``1.41421`` or ``2e3`` as a finite float, else None (no sign, no
    ``nan`` or ``inf``: a length is never negative, and a non-number is bad input, not a
    mismatch)."""
    number = text.strip()
    if _DECIMAL.fullmatch(number) is None:
        return None
    value = float(number)
    return value if math.isfinite(value) else None


def _field_columns(raw: str, fields: list[str]) -> list[int]:
    """The 1-based column where each field of a scenario line starts."""
    columns, at = [], 0
    for field in fields:
        at = raw.index(field, at)
        columns.append(at + 1)
        at += len(field)
    return columns


def _check_query(query: ScenarioQuery, source: str, maze: Maze | None, columns: list[int]) -> None:
    if maze is not None and (query.width, query.height) != (maze.width, maze.height):
        raise InputError(
            f"expected the map size {maze.width}x{maze.height}, got {query.width}x{query.height}",
            source=source,
            line=query.line,
            column=columns[2],
        )
    for label, (x, y), column in (
        ("start", query.start, columns[4]),
        ("goal", query.goal, columns[6]),
    ):
        if not (0 <= x < query.width and 0 <= y < query.height):
            raise InputError(
                f"expected the {label} ({x},{y}) inside the {query.width}x{query.height} map",
                source=source,
                line=query.line,
                column=column,
            )
        if maze is not None and not maze.is_free(x, y):
            raise InputError(
                f"expected the {label} ({x},{y}) on a free cell, but it is a wall",
                source=source,
                line=query.line,
                column=column,
            )


def load_scenario(
    path: str | Path, *, maze: Maze | None = None, max_file_bytes: int | None = MAX_FILE_BYTES
) -> tuple[ScenarioQuery, ...]:
    """Read a ``.map.scen`` file (see :func:`parse_scenario`); a file over ``max_file_bytes``
    (:data:`selfrepair.limits.MAX_FILE_BYTES`; ``None``: no limit) is refused unread."""
    path = Path(path)
    text = read_text(
        path, what="MovingAI scenario file", max_bytes=max_file_bytes, limit="max_file_bytes"
    )
    return parse_scenario(text, source=str(path), maze=maze)
