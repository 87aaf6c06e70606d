"""Planning commands: ``selfrepair plan``, ``selfrepair path`` and ``selfrepair check-scen``.

Exit codes: ``plan`` and ``path`` return 0 when a plan or path was found and 1 otherwise (no path,
or the budget ran out); ``check-scen`` returns 1 if any checked line does not match. Bad input is
exit code 2 (see :func:`selfrepair.cli.main`).
"""

from __future__ import annotations

import time
from fractions import Fraction
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from selfrepair.cli._app import MaxCells, app, echo, echo_json
from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Heading, parse_cell, parse_pose
from selfrepair.limits import MAX_CELLS, MAX_CLEARANCE_WEIGHT
from selfrepair.robots import four_wheel
from selfrepair.search.astar import PlanResult, PlanStatus
from selfrepair.search.backend import BACKENDS
from selfrepair.search.grid import grid_astar
from selfrepair.search.lattice import HEURISTICS, plan
from selfrepair.search.problem import CONNECTIVITIES, GridResult, PlanningProblem
from selfrepair.world.bundled import resolve_maze
from selfrepair.world.maze import Maze
from selfrepair.world.movingai import ScenarioQuery, load_map, load_scenario
from selfrepair.world.render import GOAL_CHAR, path_layer, pose_layer, render_ascii

__all__ = [
    "SCEN_TOLERANCE",
    "check_scenarios",
    "fraction_json",
    "parse_goal",
    "parse_weight",
    "path_json",
    "plan_json",
    "sample_indices",
]

SCEN_TOLERANCE = 0.01
"""Absolute tolerance against MovingAI ``optimal_length`` (hog2-era files round sqrt(2))."""

_Backend = Annotated[str, typer.Option("--backend", help=f"Search backend: {', '.join(BACKENDS)}.")]
_Json = Annotated[bool, typer.Option("--json", help="Print a JSON object instead of a picture.")]
_MaxExpansions = Annotated[
    int | None, typer.Option("--max-expansions", help="Node budget (expansions).")
]
_TimeLimit = Annotated[float | None, typer.Option("--time-limit", help="Time budget in seconds.")]


def parse_goal(text: str) -> tuple[Cell, Heading | None]:
    """Parse ``X,Y`` (any heading) or ``X,Y,H`` into a goal cell and optional heading."""
    if text.count(",") == 2:
        pose = parse_pose(text, source="--goal")
        return pose.cell, pose.heading
    return parse_cell(text, source="--goal"), None


def parse_weight(text: str) -> Fraction:
    """Parse an exact weight such as ``2``, ``1/3`` or ``0.25``, from 0 to
    :data:`~selfrepair.limits.MAX_CLEARANCE_WEIGHT`."""
    try:
        weight = Fraction(text.strip())
    except (ValueError, ZeroDivisionError) as exc:
        raise InputError(
            f"expected a number such as 2, 1/3 or 0.25, got {text[:40]!r}",
            source="--clearance-weight",
        ) from exc
    if not 0 <= weight <= MAX_CLEARANCE_WEIGHT:
        raise InputError(
            f"expected a weight from 0 to {MAX_CLEARANCE_WEIGHT:,}, got {text[:40]!r}",
            source="--clearance-weight",
        )
    return weight


def fraction_json(value: Fraction) -> int | str:
    """An exact number for JSON: an integer when whole, else a string such as ``"31/3"``."""
    return value.numerator if value.denominator == 1 else str(value)


def plan_json(result: PlanResult) -> dict[str, Any]:
    """The ``plan --json`` object."""
    return {
        "status": result.status.value,
        "cost": None if result.cost is None else fraction_json(result.cost),
        "duration": fraction_json(result.duration),
        "actions": [a.code for a in result.actions],
        "poses": [[p.x, p.y, p.heading.name] for p in result.poses],
        "expansions": result.expansions,
        "wall_time_ms": result.wall_time_ns / 1e6,
    }


def path_json(result: GridResult) -> dict[str, Any]:
    """The ``path --json`` object; ``cost`` is a float, ``cost_exact`` its exact form."""
    cost = result.cost
    return {
        "status": result.status.value,
        "cost": None if cost is None else cost.value,
        "cost_exact": None
        if cost is None
        else {"straight": cost.straight, "diagonal": cost.diagonal, "text": str(cost)},
        "path": [[x, y] for x, y in result.path],
        "expansions": result.expansions,
        "wall_time_ms": result.wall_time_ns / 1e6,
    }


@app.command("plan")
def plan_command(
    maze_spec: Annotated[
        str,
        typer.Argument(metavar="MAZE", help="Bundled maze name, maze file or MovingAI .map."),
    ],
    start: Annotated[str, typer.Option("--start", help="Start pose X,Y,H (H in N, E, S, W).")],
    goal: Annotated[str, typer.Option("--goal", help="Goal cell X,Y or pose X,Y,H.")],
    faults: Annotated[str, typer.Option("--faults", help="Known faults, e.g. FL:F,RR:B.")] = "",
    clearance_weight: Annotated[
        str, typer.Option("--clearance-weight", help="Weight of the wall-clearance term.")
    ] = "0",
    clearance_radius: Annotated[
        int, typer.Option("--clearance-radius", help="Clearance below which cells cost extra.")
    ] = 2,
    heuristic: Annotated[
        str, typer.Option("--heuristic", help=f"One of {', '.join(HEURISTICS)}.")
    ] = "grid-distance",
    max_expansions: _MaxExpansions = None,
    time_limit: _TimeLimit = None,
    backend: _Backend = "auto",
    as_json: _Json = False,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Plan the robot's actions from START to GOAL with exact A* (exit 1 if no plan)."""
    maze = resolve_maze(maze_spec, max_cells=max_cells)
    goal_cell, goal_heading = parse_goal(goal)
    problem = PlanningProblem(
        maze=maze,
        start=parse_pose(start, source="--start"),
        goal=goal_cell,
        goal_heading=goal_heading,
        faults=four_wheel.parse_faults(faults, source="--faults"),
        clearance_weight=parse_weight(clearance_weight),
        clearance_radius=clearance_radius,
    )
    result = plan(
        problem,
        heuristic=heuristic,
        max_expansions=max_expansions,
        time_limit=time_limit,
        backend=backend,
    )
    if as_json:
        echo_json(plan_json(result))
    else:
        _print_plan(problem, result)
    return 0 if result.status is PlanStatus.SOLVED else 1


def _print_plan(problem: PlanningProblem, result: PlanResult) -> None:
    swept = [
        cell
        for pose, action in zip(result.poses, result.actions, strict=False)
        for cell in four_wheel.swept_cells(pose, action)
    ]
    layers = [path_layer(swept), {problem.goal: GOAL_CHAR}, pose_layer(result.poses[:1])]
    echo(render_ascii(problem.maze, layers).rstrip("\n"))
    echo(f"status: {result.status.value}")
    if result.cost is not None:
        echo(
            f"cost: {result.cost}  duration: {result.duration} ticks  steps: {len(result.actions)}"
        )
        echo("actions: " + " ".join(a.code for a in result.actions))
    echo(f"expansions: {result.expansions}  time: {result.wall_time_ns / 1e6:.2f} ms")


@app.command("path")
def path_command(
    map_spec: Annotated[
        str, typer.Argument(metavar="MAP", help="Bundled maze name, MovingAI .map or maze file.")
    ],
    source: Annotated[str, typer.Option("--from", help="Start cell X,Y.")],
    target: Annotated[str, typer.Option("--to", help="Goal cell X,Y.")],
    connectivity: Annotated[
        int, typer.Option("--connectivity", help="4 or 8 (8: diagonal sqrt2, no corner cutting).")
    ] = 8,
    max_expansions: _MaxExpansions = None,
    time_limit: _TimeLimit = None,
    backend: _Backend = "auto",
    as_json: _Json = False,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Shortest grid path under MovingAI rules (exit 1 if none)."""
    if connectivity not in CONNECTIVITIES:
        raise InputError(f"expected 4 or 8, got {connectivity}", source="--connectivity")
    maze = resolve_maze(map_spec, max_cells=max_cells)
    start = parse_cell(source, source="--from")
    goal = parse_cell(target, source="--to")
    result = grid_astar(
        maze,
        start,
        goal,
        connectivity=connectivity,
        max_expansions=max_expansions,
        time_limit=time_limit,
        backend=backend,
    )
    if as_json:
        echo_json(path_json(result))
    else:
        layers = [path_layer(result.path), {goal: GOAL_CHAR, start: "S"}]
        echo(render_ascii(maze, layers).rstrip("\n"))
        echo(f"status: {result.status.value}")
        if result.cost is not None:
            echo(f"cost: {result.cost.value:.8f} ({result.cost})  steps: {len(result.path) - 1}")
        echo(f"expansions: {result.expansions}  time: {result.wall_time_ns / 1e6:.2f} ms")
    return 0 if result.status is PlanStatus.SOLVED else 1


def sample_indices(total: int, sample: int | None, seed: int) -> list[int]:
    """``sample`` indices spread evenly over ``range(total)`` (all when ``sample`` is None or
    not smaller), one per equal stretch at the same seeded offset within each stretch."""
    if sample is None or sample >= total:
        return list(range(total))
    offset = float(np.random.default_rng(seed).random())
    return [int((i + offset) * total / sample) for i in range(sample)]


def check_scenarios(
    scen_path: Path,
    *,
    sample: int | None = None,
    seed: int = 0,
    backend: str = "auto",
    max_cells: int | None = MAX_CELLS,
) -> tuple[int, list[dict[str, Any]]]:
    """Run the scenario lines (all, or ``sample`` spread evenly) with 8-connected grid A*.

    The map is the file next to ``scen_path`` named by the basename of the map column (checked
    against ``max_cells``). Returns the number of lines in the file and one record per checked
    line (``ok`` false on a mismatch). Every number in a record is finite: the reader refuses a
    non-finite ``optimal_length`` and a path cost is a sum of finite steps.
    """
    queries = load_scenario(scen_path)
    chosen = [queries[i] for i in sample_indices(len(queries), sample, seed)]
    maps: dict[str, Maze] = {}
    records = []
    for query in chosen:
        maze = _scenario_map(scen_path, query, maps, max_cells)
        result = grid_astar(maze, query.start, query.goal, connectivity=8, backend=backend)
        got = None if result.cost is None else result.cost.value
        ok = got is not None and abs(got - query.optimal_length) <= SCEN_TOLERANCE
        records.append(
            {
                "line": query.line,
                "start": list(query.start),
                "goal": list(query.goal),
                "expected": query.optimal_length,
                "got": got,
                "ok": ok,
            }
        )
    return len(queries), records


def _scenario_map(
    scen_path: Path, query: ScenarioQuery, maps: dict[str, Maze], max_cells: int | None
) -> Maze:
    name = query.map_name.replace("\\", "/").rsplit("/", 1)[-1]
    if name not in maps:
        map_path = scen_path.parent / name
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


@app.command("check-scen")
def check_scen_command(
    scen_path: Annotated[Path, typer.Argument(metavar="SCEN", help="MovingAI .map.scen file.")],
    sample: Annotated[
        int | None, typer.Option("--sample", min=1, help="Check N lines spread evenly.")
    ] = None,
    seed: Annotated[
        int, typer.Option("--seed", min=0, help="Offset of the evenly spread sample.")
    ] = 0,
    backend: _Backend = "auto",
    as_json: _Json = False,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Check grid A* against a scenario file's optimal lengths (abs tolerance 0.01; exit 1 on any
    mismatch)."""
    if backend not in BACKENDS:
        raise InputError(
            f"expected one of {', '.join(BACKENDS)}, got {backend!r}", source="--backend"
        )
    t0 = time.perf_counter()
    total, records = check_scenarios(
        scen_path, sample=sample, seed=seed, backend=backend, max_cells=max_cells
    )
    seconds = time.perf_counter() - t0
    bad = [r for r in records if not r["ok"]]
    if as_json:
        echo_json(
            {
                "file": str(scen_path),
                "lines": total,
                "checked": len(records),
                "mismatches": bad,
                "tolerance": SCEN_TOLERANCE,
                "seconds": seconds,
            }
        )
    else:
        for r in bad:
            echo(
                f"{scen_path}:{r['line']}: start {r['start'][0]},{r['start'][1]} goal "
                f"{r['goal'][0]},{r['goal'][1]}: expected {r['expected']}, got {r['got']}"
            )
        echo(
            f"checked {len(records)} of {total} lines of {scen_path}: {len(bad)} mismatches "
            f"({seconds:.2f} s)"
        )
    return 1 if bad else 0
