"""``selfrepair pddl``: write a planning problem as PDDL (``domain.pddl`` and ``problem.pddl``).

The encoding is :mod:`selfrepair.baselines.pddl`'s: all 81 actions as schemas, known faults as
missing ``(healthy W M)`` facts, durations as action costs in thirds of a tick. With ``--plan`` the
lattice planner's plan is written next to them as ``plan.pddl`` (exit 1 if there is none), for a
PDDL validator such as VAL. Bad input is exit code 2 (see :func:`selfrepair.cli.main`). The
library is imported inside the command (start-up, see :mod:`selfrepair.cli._app`).
"""

from pathlib import Path
from typing import Annotated

import typer

from selfrepair.cli._app import app, echo, flag, limit_option, option
from selfrepair.cli._inputs import (
    DomainOpt,
    Faults,
    GoalPose,
    MazeArg,
    Start,
    domain_named,
    find_input,
)
from selfrepair.errors import InputError

__all__ = ["PDDL_CELLS_DEFAULT", "pddl_command"]

PDDL_CELLS_DEFAULT = 4096
"""Default of this command's ``--max-cells``:
:data:`selfrepair.baselines.pddl.MAX_PDDL_CELLS` (a test keeps them equal; the CLI does not import
the exporter to start)."""


@app.command("pddl")
def pddl_command(
    maze_spec: MazeArg,
    start: Start,
    goal: GoalPose,
    output: Annotated[
        Path, typer.Option("-o", "--output", metavar="DIR", help="Directory for the files.")
    ],
    faults: Faults = "",
    name: Annotated[
        str, option("--name", "NAME", "PDDL problem name (default: the maze's name).")
    ] = "",
    max_cells: Annotated[
        int,
        limit_option("--max-cells", "Largest maze (width x height) to export (raise with care)."),
    ] = PDDL_CELLS_DEFAULT,
    with_plan: Annotated[
        bool, flag("--plan", "Also write the lattice planner's plan as plan.pddl.")
    ] = False,
    domain_name: DomainOpt = "four-wheel",
) -> int:
    """Write the planning problem from START to GOAL as PDDL files.

    domain.pddl and problem.pddl go to DIR; with --plan also plan.pddl. Exit 1 when there is no
    plan to write. The encoding is the four-wheel robot's: --domain names no other.
    """
    if domain_name != "four-wheel":
        domain_named(domain_name)  # an unknown name is told as such
        raise InputError(
            f"the PDDL export encodes the four-wheel robot only (its 81 actions and wheel "
            f"faults), not {domain_name!r}",
            source="--domain",
        )
    from selfrepair.baselines.pddl import export_pddl
    from selfrepair.baselines.pddltext import plan_to_pddl, write_pddl
    from selfrepair.cli.planning import planning_problem
    from selfrepair.robots.four_wheel import FOUR_WHEEL
    from selfrepair.search.astar import PlanStatus
    from selfrepair.search.lattice import plan
    from selfrepair.world.bundled import resolve_maze

    maze = resolve_maze(find_input(maze_spec))
    problem = planning_problem(maze, FOUR_WHEEL, start, goal, faults)
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
