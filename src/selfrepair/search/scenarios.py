"""Checking the grid planner against MovingAI scenario files.

A scenario file (``.map.scen``) lists queries on a map with their optimal length under MovingAI's
rules (8-connected, diagonal sqrt(2), no corner cutting). :func:`check_scenarios` runs
:func:`selfrepair.search.grid.grid_astar` on every line (or on an evenly spread, seeded sample)
and compares; :func:`sample_indices` is that sample, also used by the planner benchmark. The map
of each line is the file next to the scenario file named by the basename of the map column (both
file generations give either a bare name or a ``maps/mazes/...`` path there).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from selfrepair.errors import InputError
from selfrepair.geometry import Cell
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES
from selfrepair.search.grid import grid_astar
from selfrepair.textio import JSONObject
from selfrepair.world.maze import Maze
from selfrepair.world.movingai import ScenarioQuery, load_map, load_scenario

__all__ = [
    "SCEN_TOLERANCE",
    "ScenarioCheck",
    "ScenarioReport",
    "check_scenarios",
    "sample_indices",
    "scenario_map_path",
]

SCEN_TOLERANCE = 0.01
"""Absolute tolerance against MovingAI ``optimal_length`` (hog2-era files round sqrt(2))."""


@dataclass(frozen=True, slots=True)
class ScenarioCheck:
    """One checked scenario line: the listed optimum, the planner's cost (``None``: no path) and
    whether they agree within :data:`SCEN_TOLERANCE`."""

    line: int
    start: Cell
    goal: Cell
    expected: float
    got: float | None
    ok: bool

    def to_json(self) -> JSONObject:
        """A JSON object with the same fields (cells as ``[x, y]``)."""
        return {
            "line": self.line,
            "start": list(self.start),
            "goal": list(self.goal),
            "expected": self.expected,
            "got": self.got,
            "ok": self.ok,
        }


@dataclass(frozen=True, slots=True)
class ScenarioReport:
    """The outcome of :func:`check_scenarios`: how many lines the file has and each check."""

    source: str
    lines: int
    checks: tuple[ScenarioCheck, ...]

    @property
    def mismatches(self) -> tuple[ScenarioCheck, ...]:
        """The checks whose cost disagrees with the listed optimum."""
        return tuple(c for c in self.checks if not c.ok)


def sample_indices(total: int, sample: int | None, seed: int) -> list[int]:
    """``sample`` indices spread evenly over ``range(total)`` (all when ``sample`` is None or
    not smaller), one per equal stretch at the same seeded offset within each stretch."""
    if sample is None or sample >= total:
        return list(range(total))
    offset = float(np.random.default_rng(seed).random())
    return [int((i + offset) * total / sample) for i in range(sample)]


def check_scenarios(
    scen_path: str | Path,
    *,
    sample: int | None = None,
    seed: int = 0,
    backend: str = "auto",
    max_cells: int | None = MAX_CELLS,
    max_file_bytes: int | None = MAX_FILE_BYTES,
) -> ScenarioReport:
    """Run the scenario lines (all, or ``sample`` spread evenly) with 8-connected grid A*.

    Bad input (an unreadable file, a scenario file over ``max_file_bytes``, a missing map, a map
    over ``max_cells``, a size that disagrees
    with the map, a start or goal on a wall) raises :class:`~selfrepair.errors.InputError` naming
    the scenario line. Every number in a check is finite: the reader refuses a non-finite
    ``optimal_length`` and a path cost is a sum of finite steps.
    """
    path = Path(scen_path)
    queries = load_scenario(path, max_file_bytes=max_file_bytes)
    chosen = [queries[i] for i in sample_indices(len(queries), sample, seed)]
    maps: dict[str, Maze] = {}  # the maps of this one file, dropped on return
    checks = []
    for query in chosen:
        maze = _scenario_map(path, query, maps, max_cells)
        result = grid_astar(maze, query.start, query.goal, connectivity=8, backend=backend)
        got = None if result.cost is None else result.cost.value
        ok = got is not None and abs(got - query.optimal_length) <= SCEN_TOLERANCE
        checks.append(
            ScenarioCheck(query.line, query.start, query.goal, query.optimal_length, got, ok)
        )
    return ScenarioReport(str(path), len(queries), tuple(checks))


def scenario_map_path(scen_path: Path, query: ScenarioQuery) -> Path:
    """The map file a scenario line refers to: the basename of its map column, next to the
    scenario file."""
    return scen_path.parent / query.map_name.replace("\\", "/").rsplit("/", 1)[-1]


def _scenario_map(
    scen_path: Path, query: ScenarioQuery, maps: dict[str, Maze], max_cells: int | None
) -> Maze:
    map_path = scenario_map_path(scen_path, query)
    name = map_path.name
    if name not in maps:
        if not map_path.is_file():
            raise InputError(
                f"expected the map {name!r} next to the scenario file (at {map_path})",
                source=str(scen_path),
                line=query.line,
            )
        maze = load_map(map_path, max_cells=max_cells)
        if (maze.width, maze.height) != (query.width, query.height):
            raise InputError(
                f"expected the map size {maze.width}x{maze.height}, "
                f"got {query.width}x{query.height}",
                source=str(scen_path),
                line=query.line,
            )
        maps[name] = maze
    maze = maps[name]
    for label, (x, y) in (("start", query.start), ("goal", query.goal)):
        if not maze.is_free(x, y):
            raise InputError(
                f"expected the {label} ({x},{y}) on a free cell of {name}",
                source=str(scen_path),
                line=query.line,
            )
    return maze
