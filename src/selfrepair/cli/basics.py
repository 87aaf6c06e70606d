"""Basic commands: ``selfrepair actions``, ``maze show``, ``maze generate`` and ``demo``."""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from selfrepair.cli._app import MaxCells, app, console, echo, echo_json, maze_app
from selfrepair.errors import InputError
from selfrepair.limits import MAX_CELLS
from selfrepair.robots import four_wheel
from selfrepair.world import bundled
from selfrepair.world.maze import Maze, format_maze, save_maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.render import (
    GOAL_CHAR,
    HEADING_CHARS,
    render_ascii,
    route_index_char,
    route_layers,
)
from selfrepair.world.routes import Route, load_routes


def action_rows() -> list[dict[str, object]]:
    """One row per action: code, side drives, motion and exact duration (as text)."""
    return [
        {
            "action": a.code,
            "l": a.left,
            "r": a.right,
            "motion": a.motion.name,
            "kind": a.motion.kind.value,
            "duration": str(a.duration),
        }
        for a in four_wheel.ACTIONS
    ]


_TABLE_COLUMNS = ("action", "l", "r", "motion", "duration")


def markdown_action_table() -> str:
    """The 81-row action table as Markdown, as ``docs/robot.md`` shows it (a test compares)."""
    lines = ["| " + " | ".join(_TABLE_COLUMNS) + " |", "|---|---:|---:|---|---:|"]
    lines += [
        "| " + " | ".join(str(row[c]) for c in _TABLE_COLUMNS) + " |" for row in action_rows()
    ]
    return "\n".join(lines) + "\n"


def markdown_single_fault_table() -> str:
    """Per single fault: the motions it removes and those it slows (fastest duration before and
    after), as Markdown. ``docs/robot.md`` shows it and a test keeps the two equal."""
    healthy = {m: a.duration for m, a in four_wheel.fastest_by_motion().items()}
    lines = [
        "| fault | actions left | motions lost | motions slowed (ticks) |",
        "|---|---:|---|---|",
    ]
    for fault in four_wheel.SINGLE_FAULTS:
        best = four_wheel.fastest_by_motion([fault])
        left = sum(four_wheel.available(a, [fault]) for a in four_wheel.ACTIONS)
        lost = [m.name for m in four_wheel.MOTIONS if m not in best]
        slowed = [
            f"{m.name} {healthy[m]} → {best[m].duration}"
            for m in four_wheel.MOTIONS
            if m in best and best[m].duration > healthy[m]
        ]
        lines.append(
            f"| {fault} | {left} | {', '.join(lost) or '–'} | {', '.join(slowed) or '–'} |"
        )
    return "\n".join(lines) + "\n"


def markdown_double_fault_summary() -> str:
    """The 66 double faults grouped by the motions they remove, as Markdown (in the docs)."""
    groups: dict[tuple[str, ...], list[str]] = {}
    for pair in four_wheel.DOUBLE_FAULTS:
        best = four_wheel.fastest_by_motion(pair)
        lost = tuple(m.name for m in four_wheel.MOTIONS if m not in best)
        groups.setdefault(lost, []).append(four_wheel.format_faults(pair))
    lines = ["| motions lost | double faults | for example |", "|---|---:|---|"]
    for lost, pairs in sorted(groups.items(), key=lambda kv: (len(kv[0]), kv[0])):
        lines.append(f"| {', '.join(lost) or '–'} | {len(pairs)} | {min(pairs)} |")
    return "\n".join(lines) + "\n"


@app.command()
def actions(
    as_json: Annotated[
        bool, typer.Option("--json", help="Print JSON rows instead of a table.")
    ] = False,
    as_markdown: Annotated[
        bool, typer.Option("--markdown", help="Print the Markdown table of docs/robot.md.")
    ] = False,
) -> int:
    """Print the 81 actions: wheel code, side drives l and r, motion and duration in ticks."""
    rows = action_rows()
    if as_json:
        echo_json(rows)
        return 0
    if as_markdown:
        sys.stdout.write(markdown_action_table())
        return 0
    table = Table(title="The 81 actions of the four-wheel robot")
    for column in ("action", "l", "r", "motion", "duration"):
        table.add_column(column, justify="right" if column in ("l", "r", "duration") else "left")
    for row in rows:
        table.add_row(*(str(row[c]) for c in ("action", "l", "r", "motion", "duration")))
    console().print(table)
    return 0


# --- mazes ------------------------------------------------------------------------------------


def _routes_for(spec: str, maze: Maze, routes_file: Path | None) -> tuple[Route, ...]:
    """The routes to overlay: an explicit file, a bundled maze's own routes, or ``FILE.routes``."""
    if routes_file is not None:
        return load_routes(routes_file, maze=maze)
    if spec in bundled.maze_names():
        return bundled.bundled_routes(spec)
    sibling = Path(spec).with_suffix(".routes")
    if not sibling.is_file():
        raise InputError(
            f"expected a route file {sibling} next to the maze (or give --routes-file)",
            source=spec,
        )
    return load_routes(sibling, maze=maze)


def route_picture(maze: Maze, routes: Sequence[Route]) -> str:
    """The maze with ``routes`` drawn on it, followed by one line per route."""
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
    spec: Annotated[
        str, typer.Argument(metavar="FILE|NAME", help="Bundled maze name, .maze file or .map file.")
    ],
    routes: Annotated[
        bool,
        typer.Option("--routes", help="Overlay the routes (bundled ones, or FILE.routes)."),
    ] = False,
    routes_file: Annotated[
        Path | None,
        typer.Option("--routes-file", help="Overlay the routes of this route file."),
    ] = None,
    route: Annotated[
        str | None, typer.Option("--route", help="Overlay only the route with this name.")
    ] = None,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Print a maze as ASCII ('#' wall, '.' free), optionally with its routes drawn on it."""
    maze = bundled.resolve_maze(spec, max_cells=max_cells)
    if not (routes or routes_file is not None or route is not None):
        sys.stdout.write(render_ascii(maze))
        return 0
    chosen = _routes_for(spec, maze, routes_file)
    if route is not None:
        chosen = tuple(r for r in chosen if r.name == route)
        if not chosen:
            raise InputError(f"unknown route {route!r} for maze {spec}", source="--route")
    sys.stdout.write(route_picture(maze, chosen))
    return 0


@maze_app.command("generate")
def maze_generate(
    width: Annotated[int, typer.Option("--width", help="Columns, border included.")],
    height: Annotated[int, typer.Option("--height", help="Rows, border included.")],
    seed: Annotated[int, typer.Option("--seed", help="Random seed (non-negative integer).")],
    corridor: Annotated[int, typer.Option("--corridor", help="Corridor width in cells.")] = 1,
    braid: Annotated[
        float, typer.Option("--braid", help="Share of dead ends to open (0 = perfect maze).")
    ] = 0.0,
    output: Annotated[
        Path | None,
        typer.Option("-o", "--output", help="Write the maze here (default: print it)."),
    ] = None,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Generate a seeded maze in the plain-text format; the same options give the same maze.

    Sizes of the form k * (corridor + 1) + 1 use the whole grid; otherwise the spare columns and
    rows at the right and bottom stay wall.
    """
    if seed < 0:
        raise InputError(f"expected a non-negative integer seed, got {seed}", source="--seed")
    if output is not None and output.suffix == ".map":
        raise InputError(
            "expected a plain-text maze file name (e.g. maze.maze): .map would be read back as "
            "a MovingAI map",
            source=str(output),
        )
    maze = generate_maze(
        width, height, corridor=corridor, braid=braid, seed=seed, max_cells=max_cells
    )
    if output is None:
        sys.stdout.write(format_maze(maze))
        return 0
    try:
        save_maze(maze, output)
    except OSError as exc:
        raise InputError(f"cannot write maze file: {exc.strerror}", source=str(output)) from exc
    echo(
        f"wrote {output}: {width}x{height}, corridor {corridor}, braid {braid}, seed {seed}, "
        f"{len(maze.free_cells())} free cells"
    )
    return 0


@app.command()
def demo() -> int:
    """Print every bundled maze with its four routes (start pose and goal)."""
    echo("Bundled mazes of the reference experiment. On each picture '#' is wall, '.' free,")
    echo("^ > v < a route's start pose (facing N, E, S, W) and 1-4 the goal of that route.")
    for name in bundled.maze_names():
        info = bundled.describe(name)
        maze = bundled.load_bundled(name)
        echo()
        echo(f"== {name}: {info.summary}")
        sys.stdout.write(route_picture(maze, bundled.bundled_routes(name)))
    return 0
