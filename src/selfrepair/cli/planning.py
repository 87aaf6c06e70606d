"""Planning commands: ``selfrepair plan``, ``selfrepair path`` and ``selfrepair check-scen``.

Exit codes: ``plan`` and ``path`` return 0 when a plan or path was found and 1 otherwise (no path,
or the budget ran out); ``check-scen`` returns 1 if any checked line does not match. Bad input is
exit code 2 (see :func:`selfrepair.cli.main`).

Times: the compiled kernels are loaded (or compiled) before the search starts, and that load is
reported on its own line (``kernels loaded in ... ms``); the search time is the search alone.
"""

import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from selfrepair.cli._app import (
    MaxCells,
    MaxFileBytes,
    app,
    echo,
    echo_json,
    exact_json,
    number_json,
    option,
)
from selfrepair.cli._inputs import (
    Backend,
    ClearanceWeight,
    DomainOpt,
    Faults,
    GoalPose,
    Heuristic,
    Json,
    MaxExpansions,
    MazeArg,
    Start,
    TimeLimit,
    domain_named,
    find_input,
    parse_faults,
    parse_weight,
)
from selfrepair.cli._mission import Recursion, TableOpt
from selfrepair.errors import InputError
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES
from selfrepair.textio import JSONObject

if TYPE_CHECKING:
    from collections.abc import Iterable

    from selfrepair.geometry import Cell, Heading
    from selfrepair.robots.domain import SomeDomain
    from selfrepair.search.astar import PlanResult
    from selfrepair.search.problem import GridResult, PlanningProblem
    from selfrepair.world.maze import Maze

__all__ = ["kernel_load_ns", "parse_goal", "path_json", "plan_json", "planning_problem"]

MAX_PICTURE_CELLS = 100 * 100
"""``path`` draws its picture by default only for mazes up to this many cells (``--picture``
draws any size)."""


def parse_goal(text: str) -> "tuple[Cell, Heading | None]":
    """Parse ``X,Y`` (any heading) or ``X,Y,H`` into a goal cell and optional heading."""
    from selfrepair.geometry import parse_cell, parse_pose

    if text.count(",") == 2:
        pose = parse_pose(text, source="--goal")
        return pose.cell, pose.heading
    return parse_cell(text, source="--goal"), None


def planning_problem(
    maze: "Maze",
    domain: "SomeDomain",
    start: str,
    goal: str,
    faults: str,
    clearance_weight: str = "0",
    *,
    clearance_radius: int = 2,
) -> "PlanningProblem":
    """The problem of planning on ``maze`` that the options ``--start`` (X,Y,H), ``--goal``
    (X,Y or X,Y,H), ``--faults`` and ``--clearance-weight`` give, each checked."""
    from selfrepair.geometry import parse_pose
    from selfrepair.search.problem import PlanningProblem

    goal_cell, goal_heading = parse_goal(goal)
    return PlanningProblem(
        maze=maze,
        start=parse_pose(start, source="--start"),
        goal=goal_cell,
        goal_heading=goal_heading,
        faults=parse_faults(domain, faults),
        clearance_weight=parse_weight(clearance_weight),
        clearance_radius=clearance_radius,
        domain=domain,
    )


def kernel_load_ns(backend: str, *kinds: str, domain: "SomeDomain | None" = None) -> int:
    """Load the compiled kernels of ``kinds`` (default: all; see
    :data:`selfrepair.search.warmup.KERNELS`) if ``backend`` uses them (for the robot ``domain``
    when given: an explicit ``numba`` it does not fit is refused); the nanoseconds it took (0
    when they were loaded already in this process or are not used)."""
    from selfrepair.search.astar import BACKENDS
    from selfrepair.search.backend import use_numba

    if backend not in BACKENDS:
        raise InputError(
            f"expected one of {', '.join(BACKENDS)}, got {backend!r}", source="--backend"
        )
    if not use_numba(backend, domain):
        return 0
    from selfrepair.search.warmup import ensure_warm

    return ensure_warm(*kinds)


def _ms(ns: int) -> float:
    return round(ns / 1e6, 3)


def plan_json(
    result: "PlanResult", load_ns: int = 0, domain: "SomeDomain | None" = None
) -> JSONObject:
    """The ``plan --json`` object: ``cost`` and ``duration`` as numbers with exact ``_exact``
    strings; ``actions`` in the text form of ``domain`` (default: the four-wheel robot);
    ``search_ms`` is the search alone, ``kernel_load_ms`` the one-off kernel load."""
    if domain is None:
        from selfrepair.robots.four_wheel import FOUR_WHEEL

        domain = FOUR_WHEEL
    return {
        "status": result.status.value,
        "cost": number_json(result.cost),
        "cost_exact": exact_json(result.cost),
        "duration": number_json(result.duration),
        "duration_exact": exact_json(result.duration),
        "actions": [domain.format_action(a) for a in result.actions],
        "poses": [[p.x, p.y, p.heading.name] for p in result.poses],
        "expansions": result.expansions,
        "search_ms": _ms(result.wall_time_ns),
        "kernel_load_ms": _ms(load_ns),
    }


def path_json(result: "GridResult", load_ns: int = 0) -> JSONObject:
    """The ``path --json`` object; ``cost`` is a float, ``cost_exact`` its exact form."""
    cost = result.cost
    return {
        "status": result.status.value,
        "cost": None if cost is None else number_json(cost.value),
        "cost_exact": None
        if cost is None
        else {"straight": cost.straight, "diagonal": cost.diagonal, "text": str(cost)},
        "path": [[x, y] for x, y in result.path],
        "expansions": result.expansions,
        "search_ms": _ms(result.wall_time_ns),
        "kernel_load_ms": _ms(load_ns),
    }


def _times(result_ns: int, load_ns: int) -> str:
    load = f"  (kernels loaded in {load_ns / 1e6:.0f} ms before, not counted)" if load_ns else ""
    return f"search: {result_ns / 1e6:.2f} ms{load}"


@app.command("plan")
def plan_command(
    maze_spec: MazeArg,
    start: Start,
    goal: GoalPose,
    faults: Faults = "",
    clearance_weight: ClearanceWeight = "0",
    clearance_radius: Annotated[
        int, option("--clearance-radius", "N", "Clearance below which cells cost extra.")
    ] = 2,
    heuristic: Heuristic = "grid-distance",
    max_expansions: MaxExpansions = None,
    time_limit: TimeLimit = None,
    backend: Backend = "auto",
    domain_name: DomainOpt = "four-wheel",
    as_json: Json = False,
    max_cells: MaxCells = MAX_CELLS,
    tolerance_k: Annotated[
        int | None,
        option(
            "--tolerance",
            "K",
            "Also show, per step, the sets of 1 to K faults the plan does not survive by "
            "replacement (see `selfrepair tolerance`).",
        ),
    ] = None,
    table: TableOpt = None,
    recursion: Recursion = "flat",
) -> int:
    """Plan the robot's actions with exact A*.

    Exit 1 when there is no plan (or the budget ran out).
    """
    from selfrepair.search.astar import PlanStatus
    from selfrepair.search.lattice import plan
    from selfrepair.world.bundled import resolve_maze

    domain = domain_named(domain_name)
    maze = resolve_maze(find_input(maze_spec), max_cells=max_cells)
    problem = planning_problem(
        maze, domain, start, goal, faults, clearance_weight, clearance_radius=clearance_radius
    )
    load_ns = kernel_load_ns(backend, "lattice", domain=domain)
    result = plan(
        problem,
        heuristic=heuristic,
        max_expansions=max_expansions,
        time_limit=time_limit,
        backend=backend,
    )
    tolerance = None
    if tolerance_k is not None and result.status is PlanStatus.SOLVED:
        from selfrepair.cli.tolerance import plan_tolerance_of

        tolerance = plan_tolerance_of(problem, result, tolerance_k, table, recursion)
    if as_json:
        out = plan_json(result, load_ns, domain)
        if tolerance is not None:
            from selfrepair.cli.tolerance import tolerance_json

            out["tolerance"] = tolerance_json(problem.domain, tolerance)
        echo_json(out)
    else:
        _print_plan(problem, result, load_ns)
        if tolerance is not None:
            from selfrepair.cli.tolerance import print_tolerance

            print_tolerance(problem.domain, tolerance, per_step=True)
    return 0 if result.status is PlanStatus.SOLVED else 1


def _print_plan(problem: "PlanningProblem", result: "PlanResult", load_ns: int) -> None:
    from selfrepair.world.render import GOAL_CHAR, path_layer, pose_layer, render_ascii

    domain = problem.domain
    swept = [
        cell
        for pose, action in zip(result.poses, result.actions, strict=False)
        for cell in domain.footprint(pose, action)
    ]
    layers = [path_layer(swept), {problem.goal: GOAL_CHAR}, pose_layer(result.poses[:1])]
    echo(render_ascii(problem.maze, layers).rstrip("\n"))
    echo(f"status: {result.status.value}")
    if result.cost is not None:
        echo(
            f"cost: {result.cost}  duration: {result.duration} ticks  steps: {len(result.actions)}"
        )
        echo("actions: " + " ".join(domain.format_action(a) for a in result.actions))
    echo(f"expansions: {result.expansions}  {_times(result.wall_time_ns, load_ns)}")


@app.command("path")
def path_command(
    maze_spec: MazeArg,
    source: Annotated[str, option("--from", "X,Y", "Start cell.")],
    target: Annotated[str, option("--to", "X,Y", "Goal cell.")],
    connectivity: Annotated[
        int,
        option(
            "--connectivity",
            "4|8",
            "4 or 8 neighbours (8: diagonals cost sqrt 2, no corner cutting).",
        ),
    ] = 8,
    picture: Annotated[
        bool | None,
        typer.Option(
            "--picture/--no-picture",
            help=f"Draw the maze with the path (default: only up to {MAX_PICTURE_CELLS} cells).",
            show_default=False,
        ),
    ] = None,
    max_expansions: MaxExpansions = None,
    time_limit: TimeLimit = None,
    backend: Backend = "auto",
    as_json: Json = False,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Shortest grid path under MovingAI rules.

    Exit 1 when there is no path (or the budget ran out). Large mazes are not drawn unless
    --picture is given.
    """
    from selfrepair.geometry import parse_cell
    from selfrepair.search.astar import PlanStatus
    from selfrepair.search.grid import grid_astar
    from selfrepair.search.problem import CONNECTIVITIES
    from selfrepair.world.bundled import resolve_maze

    if connectivity not in CONNECTIVITIES:
        raise InputError(f"expected 4 or 8, got {connectivity}", source="--connectivity")
    maze = resolve_maze(find_input(maze_spec), max_cells=max_cells)
    start = parse_cell(source, source="--from")
    goal = parse_cell(target, source="--to")
    load_ns = kernel_load_ns(backend, "grid")
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
        echo_json(path_json(result, load_ns))
        return 0 if result.status is PlanStatus.SOLVED else 1
    draw = picture if picture is not None else maze.width * maze.height <= MAX_PICTURE_CELLS
    if draw:
        _print_path_picture(maze, result.path, start, goal)
    echo(f"status: {result.status.value}")
    if result.cost is not None:
        echo(f"cost: {result.cost.value:.8f} ({result.cost})  steps: {len(result.path) - 1}")
    echo(f"expansions: {result.expansions}  {_times(result.wall_time_ns, load_ns)}")
    if not draw:
        echo(f"(no picture of the {maze.width}x{maze.height} maze: --picture draws it)")
    return 0 if result.status is PlanStatus.SOLVED else 1


def _print_path_picture(
    maze: "Maze", path: "Iterable[Cell]", start: "Cell", goal: "Cell"
) -> None:
    from selfrepair.world.render import GOAL_CHAR, path_layer, render_ascii

    layers = [path_layer(path), {goal: GOAL_CHAR, start: "S"}]
    echo(render_ascii(maze, layers).rstrip("\n"))


@app.command("check-scen")
def check_scen_command(
    scen_path: Annotated[
        Path,
        typer.Argument(
            metavar="SCEN", help="MovingAI .map.scen file (its map must lie next to it)."
        ),
    ],
    sample: Annotated[
        int | None, option("--sample", "N", "Check N lines spread evenly.", min=1)
    ] = None,
    seed: Annotated[int, option("--seed", "S", "Offset of the evenly spread sample.", min=0)] = 0,
    backend: Backend = "auto",
    as_json: Json = False,
    max_cells: MaxCells = MAX_CELLS,
    max_file_bytes: MaxFileBytes = MAX_FILE_BYTES,
) -> int:
    """Check grid A* against a MovingAI scenario file.

    Each checked line's cost must match its optimal length.
    Tolerance: 0.01 absolute; exit 1 on any mismatch.
    """
    from selfrepair.search.scenarios import SCEN_TOLERANCE, check_scenarios

    scen = Path(find_input(str(scen_path)))
    load_ns = kernel_load_ns(backend, "grid")
    t0 = time.perf_counter()
    report = check_scenarios(
        scen,
        sample=sample,
        seed=seed,
        backend=backend,
        max_cells=max_cells,
        max_file_bytes=max_file_bytes,
    )
    seconds = time.perf_counter() - t0
    bad = report.mismatches
    if as_json:
        echo_json(
            {
                "file": str(scen_path),
                "lines": report.lines,
                "checked": len(report.checks),
                "mismatches": [c.to_json() for c in bad],
                "tolerance": SCEN_TOLERANCE,
                "seconds": round(seconds, 3),
                "kernel_load_ms": _ms(load_ns),
            }
        )
    else:
        for c in bad:
            echo(
                f"{scen_path}:{c.line}: start {c.start[0]},{c.start[1]} goal "
                f"{c.goal[0]},{c.goal[1]}: expected {c.expected}, got {c.got}"
            )
        echo(
            f"checked {len(report.checks)} of {report.lines} lines of {scen_path}: {len(bad)} "
            f"mismatches ({seconds:.2f} s)"
        )
    return 1 if bad else 0
