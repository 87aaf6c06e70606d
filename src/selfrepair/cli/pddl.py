"""``selfrepair pddl``: write a planning problem as PDDL (``domain.pddl`` and ``problem.pddl``).

The encoding is :mod:`selfrepair.baselines.pddl`'s: all 81 actions as schemas, known faults as
missing ``(healthy W M)`` facts, durations as action costs in thirds of a tick. With ``--plan`` the
lattice planner's plan is written next to them as ``plan.pddl`` (exit 1 if there is none), for a
PDDL validator such as VAL. Bad input is exit code 2 (see :func:`selfrepair.cli.main`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from selfrepair.baselines.pddl import MAX_PDDL_CELLS, export_pddl, plan_to_pddl, write_pddl
from selfrepair.cli._app import app, echo
from selfrepair.cli.planning import parse_goal
from selfrepair.geometry import parse_pose
from selfrepair.robots import four_wheel
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import resolve_maze

__all__ = ["pddl_command"]


@app.command("pddl")
def pddl_command(
    maze_spec: Annotated[
        str,
        typer.Argument(metavar="MAZE", help="Bundled maze name, maze file or MovingAI .map."),
    ],
    start: Annotated[str, typer.Option("--start", help="Start pose X,Y,H (H in N, E, S, W).")],
    goal: Annotated[str, typer.Option("--goal", help="Goal cell X,Y or pose X,Y,H.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", metavar="DIR", help="Directory for the files.")
    ],
    faults: Annotated[str, typer.Option("--faults", help="Known faults, e.g. FL:F,RR:B.")] = "",
    name: Annotated[
        str, typer.Option("--name", help="PDDL problem name (default: the maze's name).")
    ] = "",
    max_cells: Annotated[
        int,
        typer.Option(
            "--max-cells", min=1, help="Largest maze (width x height) to export; raise with care."
        ),
    ] = MAX_PDDL_CELLS,
    with_plan: Annotated[
        bool, typer.Option("--plan", help="Also write the lattice planner's plan as plan.pddl.")
    ] = False,
) -> int:
    """Write the planning problem from START to GOAL as PDDL files in DIR."""
    maze = resolve_maze(maze_spec)
    goal_cell, goal_heading = parse_goal(goal)
    problem = PlanningProblem(
        maze=maze,
        start=parse_pose(start, source="--start"),
        goal=goal_cell,
        goal_heading=goal_heading,
        faults=four_wheel.parse_faults(faults, source="--faults"),
    )
    task = export_pddl(problem, name=name, max_cells=max_cells)
    domain_path, problem_path = write_pddl(task, output)
    echo(f"wrote {domain_path} and {problem_path}")
    echo(
        f"{len(task.cells)} cells, {task.static_facts} static facts, "
        f"{task.ground_actions} ground actions"
    )
    if not with_plan:
        return 0
    result = plan(problem)
    if result.status is not PlanStatus.SOLVED:
        echo(f"no plan ({result.status.value}): plan.pddl not written")
        return 1
    plan_path = Path(output) / "plan.pddl"
    plan_path.write_text(plan_to_pddl(problem.start, result.actions), encoding="utf-8")
    echo(f"wrote {plan_path}: {len(result.actions)} steps, {result.duration} ticks")
    return 0
