"""The mazes and routes of an experiment: identities for the mission key, and loading.

A maze is identified in a mission key by its bundled name, its file (path and content hash) or
its generator options (:func:`maze_identity`); :func:`maze_of` loads the maze of an identity once
per process. Limits (:mod:`selfrepair.limits`) are checked before the work they guard: a maze
file against ``max_cells`` before it is hashed and read.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ConfigError
from selfrepair.experiment.keys import canonical_json, derive_seed, portable
from selfrepair.experiment.schema import MazeConfig, MazeSource
from selfrepair.geometry import parse_cell, parse_pose
from selfrepair.limits import MAX_CELLS, check_limit, maze_file_bytes
from selfrepair.textio import JSONObject
from selfrepair.world.maze import Maze
from selfrepair.world.routes import Route, random_routes

__all__ = ["entry_label", "maze_identity", "maze_label", "maze_of", "route_count", "routes_of"]


def maze_identity(
    entry: MazeSource, base_dir: Path, source: str, index: int, max_cells: int | None = MAX_CELLS
) -> JSONObject:
    """What identifies a maze in a mission key (a file is identified by path and content hash).

    A maze file too big to hold ``max_cells`` cells is refused before it is hashed."""
    if entry.bundled is not None:
        from selfrepair.world.bundled import maze_names

        if entry.bundled not in maze_names():
            raise ConfigError(
                f"key 'mazes[{index}].bundled': expected one of {', '.join(maze_names())}, "
                f"got {entry.bundled!r}",
                source=source,
            )
        return {"bundled": entry.bundled}
    if entry.file is not None:
        path = (base_dir / entry.file).resolve()
        try:
            size = path.stat().st_size
            check_limit(
                size,
                maze_file_bytes(max_cells),
                name="max_cells",
                what="bytes in a maze file",
                source=str(path),
            )
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError as exc:
            raise ConfigError(
                f"key 'mazes[{index}].file': cannot read maze file {str(path)!r}: {exc.strerror}",
                source=source,
            ) from None
        return {"file": str(path), "sha256": digest}
    assert entry.generate is not None
    return {"generate": entry.generate.model_dump()}


def maze_label(identity: dict[str, Any]) -> str:
    """A short readable name for a maze identity (bundled name, file stem or generator spec)."""
    if "bundled" in identity:
        return str(identity["bundled"])
    if "file" in identity:
        return Path(identity["file"]).stem
    g = identity["generate"]
    braid = f"-b{g['braid']:g}" if g["braid"] else ""
    return f"gen{g['width']}x{g['height']}-c{g['corridor']}{braid}-s{g['seed']}"


def entry_label(entry: MazeSource) -> str:
    """The label :func:`maze_label` gives a maze entry, without reading its file."""
    if entry.bundled is not None:
        return entry.bundled
    if entry.file is not None:
        return Path(entry.file).stem
    assert entry.generate is not None
    return maze_label({"generate": entry.generate.model_dump()})


_MAZES: BoundedCache[tuple[str, int | None], Maze] = BoundedCache(
    "experiment mazes", 64, kind=CacheKind.INPUT
)


def maze_of(identity_json: str, *, max_cells: int | None = None) -> Maze:
    """The maze of an identity (as canonical JSON, so results can be cached per process).

    ``max_cells`` is checked by :func:`~selfrepair.experiment.missions.expand`; it is off by
    default because the missions that workers load mazes for come from ``expand``, which has
    checked their mazes already.
    """
    return _MAZES.get((identity_json, max_cells), lambda: _load(identity_json, max_cells))


def _load(identity_json: str, max_cells: int | None) -> Maze:
    identity = json.loads(identity_json)
    if "bundled" in identity:
        from selfrepair.world.bundled import load_bundled

        return load_bundled(identity["bundled"])
    if "file" in identity:
        from selfrepair.world.loading import load_maze

        return load_maze(identity["file"], max_cells=max_cells)
    from selfrepair.world.mazegen import generate_maze

    g = identity["generate"]
    return generate_maze(
        g["width"],
        g["height"],
        corridor=g["corridor"],
        braid=g["braid"],
        seed=g["seed"],
        name=maze_label(identity),
        max_cells=max_cells,
    )


def routes_of(
    entry: MazeConfig,
    identity: dict[str, Any],
    base_seed: int,
    source: str,
    index: int,
    max_cells: int | None = MAX_CELLS,
) -> tuple[Route, ...]:
    """The routes of one maze entry: bundled, random (seeded) or explicit (checked free)."""
    if entry.routes == "bundled":
        from selfrepair.world.bundled import bundled_routes

        assert entry.bundled is not None
        return bundled_routes(entry.bundled)
    maze = maze_of(canonical_json(identity), max_cells=max_cells)
    if isinstance(entry.routes, int):
        where = portable({"maze": identity})["maze"]  # seeded by content, not location
        return random_routes(maze, entry.routes, derive_seed(base_seed, {"routes": where}))
    routes = []
    for n, r in enumerate(entry.routes):
        route = Route(r.name or f"r{n + 1}", parse_pose(r.start), parse_cell(r.goal))
        for what, cell in (("start", route.start.cell), ("goal", route.goal)):
            if not maze.is_free(*cell):
                raise ConfigError(
                    f"key 'mazes[{index}].routes[{n}].{what}': expected a free cell of maze "
                    f"{maze_label(identity)!r}, got {cell[0]},{cell[1]}",
                    source=source,
                )
        routes.append(route)
    return tuple(routes)


def route_count(entry: MazeConfig) -> int:
    """How many routes a maze entry asks for, without loading its maze."""
    if entry.routes == "bundled":
        from selfrepair.world.bundled import bundled_routes

        assert entry.bundled is not None
        return len(bundled_routes(entry.bundled))
    return entry.routes if isinstance(entry.routes, int) else len(entry.routes)
