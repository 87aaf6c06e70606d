"""``selfrepair tolerance``: which faults, appearing at which step, a plan survives by replacement.

The plan is the mission's initial plan (made with no fault known); each (step, fault set) pair of
the fault model (every set of 1 to ``--k`` faults, or the ``--fault-set`` sets given) is covered
when that fault set appearing before that step lets the ``replacement`` strategy reach the goal
without a replan (see :mod:`selfrepair.repair.tolerance`). Exit 0 when every pair is covered (the
plan is tolerant), 1 otherwise or when no plan exists; bad input is exit 2.
"""

from typing import TYPE_CHECKING, Annotated, Any

from selfrepair.cli._app import (
    MaxCells,
    app,
    echo,
    echo_json,
    exact_json,
    flag,
    number_json,
    option,
)
from selfrepair.cli._inputs import (
    Backend,
    ClearanceWeight,
    Json,
    MazeArg,
    Start,
    find_input,
    parse_weight,
)
from selfrepair.cli._mission import Goal, MaxDepth, Recursion, Rewrite, TableOpt, check_choice
from selfrepair.errors import InputError
from selfrepair.limits import MAX_CELLS
from selfrepair.textio import JSONObject

if TYPE_CHECKING:
    from selfrepair.repair.tolerance import FaultModel, PlanTolerance
    from selfrepair.robots.domain import SomeDomain
    from selfrepair.search.astar import PlanResult

__all__ = [
    "heat_strip",
    "model_from_options",
    "plan_tolerance_of",
    "print_tolerance",
    "tolerance_json",
]

K = Annotated[int, option("--k", "K", "Fault model: every set of 1 to K faults.", min=1, max=3)]
FaultSets = Annotated[
    list[str] | None,
    option(
        "--fault-set",
        "FAULTS",
        "A fault set of the model, e.g. FL:F,RR:B (repeat it; replaces --k).",
    ),
]

HEAT = " .:-=+*#%@"
"""Heat strip characters: a step with no uncovered fault set is a space, then darker by the
share of the model's fault sets uncovered there (``@``: all)."""


def model_from_options(
    domain: "SomeDomain", k: int, sets: "list[str] | None"
) -> "FaultModel":
    """The fault model of ``--k`` or of the ``--fault-set`` options."""
    from selfrepair.repair.tolerance import FaultModel, fault_model

    if not sets:
        return fault_model(domain, k)
    parsed = []
    for text in sets:
        try:
            faults = domain.parse_faults(text)
        except InputError as exc:
            raise InputError(exc.reason, source="--fault-set") from None
        if not faults:
            raise InputError("expected at least one fault", source="--fault-set")
        if faults in parsed:
            raise InputError(f"fault set {text!r} given twice", source="--fault-set")
        parsed.append(faults)
    return FaultModel(tuple(parsed), ";".join(domain.format_faults(f) for f in parsed))


def heat_strip(tolerance: "PlanTolerance") -> str:
    """One character per step: how many of the model's fault sets are uncovered there."""
    n = len(tolerance.model.fault_sets)
    top = len(HEAT) - 1
    return "".join(
        HEAT[0] if not s.uncovered else HEAT[max(1, -(-len(s.uncovered) * top // n))]
        for s in tolerance.steps
    )


def print_tolerance(domain: "SomeDomain", tolerance: "PlanTolerance", per_step: bool) -> None:
    """The tolerance as text: per step (when ``per_step``), the heat strip and the summary."""
    n = len(tolerance.model.fault_sets)
    if per_step:
        echo(f"{'step':>4}  {'pose':<10} {'action':<6} {'uncovered':>9}  needs a replan here")
        for s in tolerance.steps:
            here = "; ".join(domain.format_faults(f) for f in s.needs_replan[:4])
            more = f" (+{len(s.needs_replan) - 4})" if len(s.needs_replan) > 4 else ""
            echo(
                f"{s.step:>4}  {s.pose!s:<10} {domain.format_action(s.action):<6} "
                f"{len(s.uncovered):>4}/{n:<4}  {here}{more}"
            )
    echo(f"heat:  |{heat_strip(tolerance)}|  (per step; blank: every fault set covered)")
    share = float(tolerance.share)
    verdict = "yes" if tolerance.tolerant else "no"
    echo(
        f"tolerance ({tolerance.model.label}, {n} fault sets): {tolerance.covered} of "
        f"{tolerance.pairs} (step, fault set) pairs covered ({share:.1%}); "
        f"{tolerance.met} pairs meet a faulty action; tolerant: {verdict}"
    )
    if not tolerance.exact_local:
        echo("(deferring recursion: pairs decided by running the strategy from each step)")


def tolerance_json(domain: "SomeDomain", tolerance: "PlanTolerance") -> JSONObject:
    """The tolerance as JSON (:meth:`~selfrepair.repair.tolerance.PlanTolerance.to_json`, the
    share rounded as every JSON number of the CLI): the summary and, per step, the uncovered
    fault sets (what the viewer draws as a heat strip along the route)."""
    out = tolerance.to_json(domain)
    out["share"] = number_json(tolerance.share)
    out["share_exact"] = exact_json(tolerance.share)
    return out


@app.command("tolerance")
def tolerance_command(
    maze_spec: MazeArg,
    start: Start,
    goal: Goal,
    k: K = 1,
    fault_set: FaultSets = None,
    table: TableOpt = None,
    recursion: Recursion = "flat",
    max_depth: MaxDepth = 2,
    rewrite: Rewrite = False,
    clearance_weight: ClearanceWeight = "0",
    backend: Backend = "auto",
    per_step: Annotated[
        bool, flag("--per-step/--summary", "List every step (default) or not.")
    ] = True,
    as_json: Json = False,
    max_cells: MaxCells = MAX_CELLS,
) -> int:
    """Which faults, at which step, a plan survives without a replan.

    For every step of the plan and every fault set of the model appearing there (permanent,
    known at once), whether replacement alone reaches the goal. Exit 1 unless every pair is
    covered.
    """
    from selfrepair.execution.result import MissionSpec
    from selfrepair.execution.tolerance import mission_tolerance
    from selfrepair.geometry import parse_cell, parse_pose
    from selfrepair.repair.replacement import RecursionMode
    from selfrepair.repair.strategies import StrategyOptions
    from selfrepair.robots.four_wheel import FOUR_WHEEL
    from selfrepair.world.bundled import resolve_maze

    check_choice(recursion, tuple(RecursionMode), "--recursion")
    if rewrite and recursion == RecursionMode.PRIMITIVE:
        raise InputError("rewriting is not available in primitive recursion", source="--rewrite")
    domain = FOUR_WHEEL
    model = model_from_options(domain, k, fault_set)
    spec = MissionSpec(
        maze=resolve_maze(find_input(maze_spec), max_cells=max_cells),
        start=parse_pose(start, source="--start"),
        goal=parse_cell(goal, source="--goal"),
        options=StrategyOptions(
            table=_table(domain, table),
            recursion=RecursionMode(recursion),
            max_depth=max_depth,
            rewrite=rewrite,
        ),
        clearance_weight=parse_weight(clearance_weight),
        backend=backend,
        domain=domain,
    )
    initial, tolerance = mission_tolerance(spec, model)
    if tolerance is None:
        if as_json:
            echo_json({"status": "no plan"})
        else:
            echo("status: no plan")
        return 1
    if as_json:
        out = tolerance_json(domain, tolerance)
        out["plan"] = {
            "status": initial.status.value,
            "duration": number_json(initial.duration),
            "duration_exact": exact_json(initial.duration),
            "actions": [domain.format_action(a) for a in initial.actions],
        }
        echo_json(out)
    else:
        echo(f"plan: {len(initial.actions)} steps, {initial.duration} ticks")
        print_tolerance(domain, tolerance, per_step)
    return 0 if tolerance.tolerant else 1


def plan_tolerance_of(
    problem: Any, result: "PlanResult", k: int, table: str | None, recursion: str
) -> "PlanTolerance | None":
    """The tolerance of a ``plan`` command's result (``plan --tolerance K``) for the
    replacement strategy with ``table`` and flat or another ``recursion``."""
    from selfrepair.execution.result import MissionSpec
    from selfrepair.execution.tolerance import mission_tolerance
    from selfrepair.repair.replacement import RecursionMode
    from selfrepair.repair.strategies import StrategyOptions
    check_choice(recursion, tuple(RecursionMode), "--recursion")
    if k < 1:
        raise InputError(f"expected K >= 1, got {k}", source="--tolerance")
    spec = MissionSpec(
        problem.maze,
        problem.start,
        problem.goal,
        problem.goal_heading,
        options=StrategyOptions(
            table=_table(problem.domain, table), recursion=RecursionMode(recursion)
        ),
        clearance_weight=problem.clearance_weight,
        clearance_radius=problem.clearance_radius,
        domain=problem.domain,
    )
    from selfrepair.repair.tolerance import fault_model

    return mission_tolerance(spec, fault_model(problem.domain, k), result)[1]


def _table(domain: "SomeDomain", table: str | None) -> Any:
    """The ``--table`` named, or the robot's own (see ``default_table``)."""
    from selfrepair.tables.fileformat import default_table, resolve_table

    return default_table(domain) if table is None else resolve_table(find_input(table))
