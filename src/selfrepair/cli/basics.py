"""Basic commands: ``selfrepair actions`` and the maze group (``maze show``, ``maze list``,
``maze generate``, ``maze routes``)."""


import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from selfrepair.cli._app import (
    MaxCells,
    MaxFileBytes,
    app,
    echo,
    echo_json,
    flag,
    maze_app,
    option,
    text_table,
)
from selfrepair.cli._inputs import (
    Braid,
    Corridor,
    Json,
    MazeArg,
    domain_named,
    find_input,
)
from selfrepair.errors import InputError
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES

if TYPE_CHECKING:
    from selfrepair.world.maze import Maze
    from selfrepair.world.routes import Route

__all__ = ["actions", "maze_generate", "maze_list", "maze_routes", "maze_show", "route_picture"]


@app.command()
def actions(
    as_json: Json = False,
    as_markdown: Annotated[
        bool, flag("--markdown", "Print the Markdown table of docs/robot.md (four-wheel only).")
    ] = False,
    domain_name: Annotated[
        str | None,
        option(
            "--domain",
            "NAME",
            "The robot: a registered domain name ({domains}); default four-wheel.",
            show_default=False,
        ),
    ] = None,  # not "four-wheel": a value given is coerced by pydantic, which is slow to import
) -> int:
    """Print a robot's actions (default: the four-wheel robot's 81).

    For the four-wheel robot each row gives the wheel code, the side drives l and r, the motion
    and the duration in ticks; for any other robot the action, its motion class, level and
    duration, and where it goes from 0,0 facing N (end pose and every cell it sweeps).
    """
    if domain_name not in (None, "four-wheel"):
        return _domain_actions(domain_name, as_json, as_markdown)
    from selfrepair.robots.four_wheel_docs import (
        ACTION_COLUMNS,
        action_rows,
        markdown_action_table,
    )

    rows = action_rows()
    if as_json:
        echo_json(rows)
        return 0
    if as_markdown:
        sys.stdout.write(markdown_action_table())
        return 0
    echo("The 81 actions of the four-wheel robot")
    cells = [[str(row[c]) for c in ACTION_COLUMNS] for row in rows]
    sys.stdout.write(text_table(ACTION_COLUMNS, cells, right={1, 2, 4}))
    return 0


def _domain_actions(name: str, as_json: bool, as_markdown: bool) -> int:
    """``actions --domain NAME`` for a robot other than the four-wheel one."""
    from selfrepair.geometry import Heading, Pose

    domain = domain_named(name)
    if as_markdown:
        raise InputError("the Markdown table is the four-wheel robot's only", source="--markdown")
    origin = Pose(0, 0, Heading.N)
    rows: list[dict[str, object]] = []
    for action in domain.actions:
        end = domain.apply(origin, action)
        rows.append(
            {
                "action": domain.format_action(action),
                "motion": str(domain.motion_class(action)),
                "level": domain.level(action),
                "duration": str(domain.duration(action)),
                "end": f"{end.x},{end.y},{end.heading.name}",
                "cells": " ".join(f"{x},{y}" for x, y in domain.footprint(origin, action)),
            }
        )
    if as_json:
        echo_json(rows)
        return 0
    echo(f"The {len(rows)} actions of the {domain.name} robot (from 0,0 facing N)")
    columns = ("action", "motion", "level", "duration", "end", "cells")
    cells = [[str(row[c]) for c in columns] for row in rows]
    sys.stdout.write(text_table(columns, cells, right={2, 3}))
    return 0


# --- mazes ------------------------------------------------------------------------------------


def _routes_for(
    spec: str, maze: "Maze", routes_file: Path | None, max_file_bytes: int
) -> "tuple[Route, ...]":
    """The routes to overlay: an explicit file, a bundled maze's own routes, or ``FILE.routes``."""
    from selfrepair.world import bundled
    from selfrepair.world.routes import load_routes

    if routes_file is not None:
        return load_routes(routes_file, maze=maze, max_file_bytes=max_file_bytes)
    if spec in bundled.maze_names():
        return bundled.bundled_routes(spec)
    sibling = Path(find_input(spec)).with_suffix(".routes")
    if not sibling.is_file():
        raise InputError(
            f"expected a route file {sibling} next to the maze (give --routes-file, or make one "
            f"with: selfrepair maze routes {spec} -n 4 --seed 0 -o {sibling})",
            source=spec,
        )
    return load_routes(sibling, maze=maze, max_file_bytes=max_file_bytes)


def route_picture(maze: "Maze", routes: "Sequence[Route]") -> str:
    """The maze with ``routes`` drawn on it, followed by one line per route."""
    from selfrepair.world.render import (
        GOAL_CHAR,
        HEADING_CHARS,
        render_ascii,
        route_index_char,
        route_layers,
    )

    lines = [render_ascii(maze, route_layers(routes)).rstrip("\n")]
    several = len(routes) > 1
    for index, route in enumerate(routes, start=1):
        mark = route_index_char(index) if several else GOAL_CHAR
        lines.append(
            f"  {index}  {route.name:<8} start {route.start!s:<10} "
            f"{HEADING_CHARS[route.start.heading]}  goal {route.goal[0]},{route.goal[1]} {mark}"
        )
    return "\n".join(lines) + "\n"


@maze_app.command("show")
def maze_show(
    spec: MazeArg,
    routes: Annotated[
        bool, flag("--routes", "Overlay the routes (bundled ones, or FILE.routes).")
    ] = False,
    routes_file: Annotated[
        Path | None, option("--routes-file", "FILE", "Overlay the routes of this file.")
    ] = None,
    route: Annotated[
        str | None, option("--route", "NAME", "Overlay only the route with this name.")
    ] = None,
    max_cells: MaxCells = MAX_CELLS,
    max_file_bytes: MaxFileBytes = MAX_FILE_BYTES,
) -> int:
    """Print a maze as text, optionally with its routes.

    '#' is wall and '.' free.
    """
    from selfrepair.world.bundled import resolve_maze
    from selfrepair.world.render import render_ascii

    maze = resolve_maze(find_input(spec), max_cells=max_cells)
    if not (routes or routes_file is not None or route is not None):
        sys.stdout.write(render_ascii(maze))
        return 0
    chosen = _routes_for(spec, maze, routes_file, max_file_bytes)
    if route is not None:
        chosen = tuple(r for r in chosen if r.name == route)
        if not chosen:
            raise InputError(f"unknown route {route!r} for maze {spec}", source="--route")
    sys.stdout.write(route_picture(maze, chosen))
    return 0


@maze_app.command("list")
def maze_list() -> int:
    """Print every bundled maze with its routes."""
    from selfrepair.world import bundled

    echo("Bundled mazes of the reference experiment. On each picture '#' is wall, '.' free,")
    echo("^ > v < a route's start pose (facing N, E, S, W) and 1-4 the goal of that route.")
    for name in bundled.maze_names():
        info = bundled.describe(name)
        maze = bundled.load_bundled(name)
        echo()
        echo(f"== {name}: {info.summary}")
        sys.stdout.write(route_picture(maze, bundled.bundled_routes(name)))
    return 0


_Seed = Annotated[int, option("--seed", "S", "Random seed (non-negative integer).")]
_Output = Annotated[
    Path | None,
    typer.Option("-o", "--output", metavar="FILE", help="Write the file here (default: print it)."),
]


def _check_seed(seed: int) -> None:
    if seed < 0:
        raise InputError(f"expected a non-negative integer seed, got {seed}", source="--seed")


@maze_app.command("generate")
def maze_generate(
    width: Annotated[int, option("--width", "N", "Columns, border included.")],
    height: Annotated[int, option("--height", "N", "Rows, border included.")],
    seed: _Seed,
    corridor: Corridor = 1,
    braid: Braid = 0.0,
    routes: Annotated[
        int | None,
        option(
            "--routes",
            "N",
            "Also draw N seeded routes and write them next to the maze (FILE.routes).",
        ),
    ] = None,
    output: _Output = None,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Generate a seeded maze in the plain-text format.

    The same options give the same maze.
    Sizes of the form k * (corridor + 1) + 1 use the whole grid; otherwise the spare columns and
    rows at the right and bottom stay wall.
    """
    from selfrepair.world.maze import format_maze, save_maze
    from selfrepair.world.mazegen import generate_maze
    from selfrepair.world.routes import random_routes

    _check_seed(seed)
    if output is not None and output.suffix == ".map":
        raise InputError(
            "expected a plain-text maze file name (e.g. maze.maze): .map would be read back as "
            "a MovingAI map",
            source=str(output),
        )
    if routes is not None and output is None:
        raise InputError(
            "expected -o FILE with --routes (the routes are written next to the maze, in "
            "FILE.routes)",
            source="--routes",
        )
    maze = generate_maze(
        width, height, corridor=corridor, braid=braid, seed=seed, max_cells=max_cells
    )
    if output is None:
        sys.stdout.write(format_maze(maze))
        return 0
    drawn: tuple[Route, ...] = ()
    if routes is not None:
        _check_count(routes, "--routes")
        drawn = random_routes(maze, routes, seed)
    try:
        save_maze(maze, output)
    except OSError as exc:
        raise InputError(f"cannot write maze file: {exc.strerror}", source=str(output)) from exc
    echo(
        f"wrote {output}: {width}x{height}, corridor {corridor}, braid {braid}, seed {seed}, "
        f"{len(maze.free_cells())} free cells"
    )
    if routes is not None:
        route_file = output.with_suffix(".routes")
        command = (
            f"selfrepair maze generate --width {width} --height {height} --corridor {corridor} "
            f"--braid {braid} --seed {seed} --routes {routes} -o {output.name}"
        )
        _write_routes(drawn, route_file, [f"maze: {output.name}", f"made by: {command}"])
    return 0


def _check_count(count: int, option: str) -> None:
    from selfrepair.world.routes import MAX_ROUTES

    if not 1 <= count <= MAX_ROUTES:
        raise InputError(
            f"expected a route count from 1 to {MAX_ROUTES}, got {count}", source=option
        )


def _write_routes(drawn: "Sequence[Route]", path: Path, comments: list[str]) -> None:
    from selfrepair.world.routes import save_routes

    try:
        save_routes(drawn, path, comments=comments)
    except OSError as exc:
        raise InputError(f"cannot write route file: {exc.strerror}", source=str(path)) from exc
    echo(f"wrote {path}: {len(drawn)} routes")


@maze_app.command("routes")
def maze_routes(
    spec: MazeArg,
    count: Annotated[int, typer.Option("-n", "--count", metavar="N", help="How many routes.")] = 4,
    seed: _Seed = 0,
    output: _Output = None,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Draw seeded routes for a maze.

    Each route has a random free start pose and a far reachable goal.
    The same maze, count and seed give the same routes. Write them next to a maze file as
    FILE.routes to use `maze show FILE --routes`, or list them in an experiment.
    """
    from selfrepair.world.bundled import resolve_maze
    from selfrepair.world.routes import format_routes, random_routes

    _check_seed(seed)
    _check_count(count, "--count")
    maze = resolve_maze(find_input(spec), max_cells=max_cells)
    drawn = random_routes(maze, count, seed)
    comments = [f"maze: {spec}", f"made by: selfrepair maze routes {spec} -n {count} --seed {seed}"]
    if output is None:
        sys.stdout.write(format_routes(drawn, comments=comments))
        return 0
    _write_routes(drawn, output, comments)
    return 0
