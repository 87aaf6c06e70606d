"""Commands that run and check missions: ``selfrepair run``, ``selfrepair replay``,
``selfrepair table show`` and ``selfrepair table check``.

Exit codes: ``run`` 0 when the goal is reached, 1 when the mission ends otherwise; ``replay`` 0 when
every step holds, 1 otherwise; ``table check`` 0 without errors (warnings allowed), 1 with errors;
bad input is exit 2 (see :func:`selfrepair.cli.main`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from selfrepair.cli._app import (
    MaxCells,
    MaxTableBytes,
    MaxTableCandidates,
    app,
    console,
    echo,
    echo_json,
    table_app,
)
from selfrepair.cli.planning import parse_weight
from selfrepair.errors import InputError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import (
    Clock,
    Detection,
    FaultEvent,
    FaultSchedule,
    Persistence,
    canonical_order,
)
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionResult, MissionSpec, StepSource
from selfrepair.execution.trace import replay as replay_trace
from selfrepair.execution.trace import write_trace
from selfrepair.geometry import Cell, parse_cell, parse_pose
from selfrepair.limits import MAX_CELLS, MAX_TABLE_BYTES, MAX_TABLE_CANDIDATES
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import StrategyOptions, strategy_names, uses_table
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import get_domain
from selfrepair.tables.fileformat import dump_table, resolve_table
from selfrepair.tables.model import ReplacementTable, check_table
from selfrepair.world.bundled import resolve_maze
from selfrepair.world.render import GOAL_CHAR, HEADING_CHARS, render_ascii

PLANNED_CHAR = "+"
EXECUTED_CHAR = "*"
SITE_CHARS = {"replacement": "R", "lookahead": "L", "replan": "P"}
FAILED_CHAR = "x"

_SHOWN = (
    "status",
    "reason",
    "strategy",
    "table",
    "recursion",
    "faults",
    "detection",
    "ticks",
    "actions_executed",
    "failed_attempts",
    "plan_length_before",
    "plan_cost_before",
    "plan_length_after",
    "plan_cost_after",
    "faulty_encounters",
    "replacements",
    "replacement_lengths",
    "replacement_depths",
    "lookaheads",
    "replans",
    "initial_planning_ns",
    "repair_latency_median_ns",
    "repair_latency_p99_ns",
    "compute_per_action_ns",
    "plan_distance",
)


def build_schedule(
    domain: Domain[Any, Any],
    faults: str,
    at: int,
    clock: str,
    detect: str,
    transient: int | None,
    intermittent: float | None,
) -> FaultSchedule:
    """The fault schedule the ``run`` options describe (one persistence for every fault)."""
    try:
        parsed = canonical_order(domain.parse_faults(faults))
    except InputError as exc:
        raise InputError(exc.reason, source="--faults") from None
    if transient is not None and intermittent is not None:
        raise InputError(
            "expected at most one of --transient and --intermittent", source="--transient"
        )
    persistence = (
        Persistence.TRANSIENT
        if transient is not None
        else Persistence.INTERMITTENT
        if intermittent is not None
        else Persistence.PERMANENT
    )
    events = tuple(
        FaultEvent(
            f,
            at=at,
            clock=Clock(clock),
            persistence=persistence,
            duration=transient,
            probability=intermittent,
        )
        for f in parsed
    )
    return FaultSchedule(events, detect)  # type: ignore[arg-type]


def mission_picture(result: MissionResult) -> str:
    """The maze with the planned path, the executed path, the repair sites, start and goal."""
    spec = result.spec
    domain = spec.domain
    planned: dict[Cell, str] = {}
    pose = spec.start
    for action in result.initial_plan.actions:
        planned.update(dict.fromkeys(domain.footprint(pose, action), PLANNED_CHAR))
        pose = domain.apply(pose, action)
    executed = {
        c: EXECUTED_CHAR for s in result.executed for c in domain.footprint(s.start, s.action)
    }
    failed = {
        s.start.cell: FAILED_CHAR for s in result.steps if s.source is StepSource.FAILED_ATTEMPT
    }
    sites = {r.pose.cell: SITE_CHARS.get(r.repair.source, "?") for r in result.repairs}
    ends = {spec.goal: GOAL_CHAR, spec.start.cell: HEADING_CHARS[spec.start.heading]}
    return render_ascii(spec.maze, [planned, executed, failed, sites, ends])


_LEGEND = (
    ("#", "wall"),
    (".", "free"),
    ("^ > v <", "start pose facing N, E, S, W"),
    (GOAL_CHAR, "goal"),
    (PLANNED_CHAR, "planned path (initial plan), not executed"),
    (EXECUTED_CHAR, "executed path"),
    ("R L P", "repair site: table replacement, lookahead window, replan"),
    (FAILED_CHAR, "failed attempt (fault learned on use)"),
)


def _picture_legend() -> str:
    width = max(len(char) for char, _ in _LEGEND)
    return "".join(f"{char:<{width}}  {meaning}\n" for char, meaning in _LEGEND)


@app.command()
def run(
    maze: Annotated[str, typer.Argument(help="Bundled maze name, maze file or MovingAI .map.")],
    start: Annotated[str, typer.Option("--start", help="Start pose X,Y,H.")],
    goal: Annotated[str, typer.Option("--goal", help="Goal cell X,Y.")],
    faults: Annotated[str, typer.Option("--faults", help="Faults, e.g. FL:F,RL:F.")] = "",
    at: Annotated[int, typer.Option("--at", help="When the faults start (step or tick).")] = 0,
    clock: Annotated[str, typer.Option("--clock", help="What --at counts: step or tick.")] = "step",
    detect: Annotated[
        str, typer.Option("--detect", help="Fault detection: now or on-use.")
    ] = "now",
    transient: Annotated[
        int | None, typer.Option("--transient", help="Faults last this many steps/ticks.")
    ] = None,
    intermittent: Annotated[
        float | None,
        typer.Option(
            "--intermittent", help="Faults are active at each step with this probability."
        ),
    ] = None,
    strategy: Annotated[
        str, typer.Option("--strategy", help="replan, replacement or lookahead.")
    ] = "replacement",
    table: Annotated[
        str, typer.Option("--table", help="Table file or bundled table name.")
    ] = "handwritten",
    recursion: Annotated[
        str, typer.Option("--recursion", help="flat, guarded or layered.")
    ] = "flat",
    max_depth: Annotated[int, typer.Option("--max-depth", help="Depth bound of guarded mode.")] = 2,
    window: Annotated[
        int, typer.Option("--window", help="Lookahead: actions after the faulty one.")
    ] = 3,
    clearance_weight: Annotated[
        str, typer.Option("--clearance-weight", help="Exact weight, e.g. 1/2.")
    ] = "0",
    heuristic: Annotated[str, typer.Option("--heuristic")] = "grid-distance",
    backend: Annotated[str, typer.Option("--backend")] = "auto",
    plan_with_faults: Annotated[
        bool,
        typer.Option(
            "--plan-with-faults", help="Make the initial plan with the faults sensed at step 0."
        ),
    ] = False,
    trace: Annotated[
        Path | None, typer.Option("--trace", help="Write a JSON Lines trace here.")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of intermittent faults.")] = 0,
    as_json: Annotated[bool, typer.Option("--json", help="Print the metrics row as JSON.")] = False,
    domain_name: Annotated[
        str, typer.Option("--domain", help="The robot: a registered domain name.")
    ] = "four-wheel",
    max_cells: MaxCells = MAX_CELLS,
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES,
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES,
) -> int:
    """Run one mission: plan, execute with faults, repair; show the paths and the metrics."""
    domain = _domain(domain_name)
    _check_choice(strategy, strategy_names(), "--strategy")
    _check_choice(recursion, tuple(RecursionMode), "--recursion")
    _check_choice(detect, tuple(Detection), "--detect")
    _check_choice(clock, tuple(Clock), "--clock")
    weight = parse_weight(clearance_weight)
    spec = MissionSpec(
        maze=resolve_maze(maze, max_cells=max_cells),
        start=parse_pose(start, source="--start"),
        goal=parse_cell(goal, source="--goal"),
        schedule=build_schedule(domain, faults, at, clock, detect, transient, intermittent),
        strategy=strategy,
        options=StrategyOptions(
            table=_table_spec(table, strategy, max_table_bytes, max_table_candidates),
            recursion=recursion,  # type: ignore[arg-type]
            max_depth=max_depth,
            window=window,
        ),
        clearance_weight=weight,
        seed=seed,
        heuristic=heuristic,
        backend=backend,
        initial_faults_known=plan_with_faults,
        domain=domain,
    )
    result = run_mission(spec)
    if trace is not None:
        write_trace(result, trace)
    row = mission_row(result)
    if as_json:
        echo_json(row)
    else:
        echo(mission_picture(result) + _picture_legend())
        metrics = Table(title=f"Mission on {spec.maze.name or maze}")
        metrics.add_column("metric")
        metrics.add_column("value", justify="right")
        for key in _SHOWN:
            metrics.add_row(key, "" if row[key] is None else str(row[key]))
        console().print(metrics)
    return 0 if result.reached else 1


def _table_spec(
    table: str, strategy: str, max_table_bytes: int, max_table_candidates: int
) -> str | ReplacementTable:
    """Load the table up front, within the limits (a bad file is exit 2 even when no repair
    needs it); the mission gets the loaded table, so the limits given are the ones that hold."""
    if not uses_table(strategy):
        return table
    return resolve_table(
        table, max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
    )


def _domain(name: str) -> Domain[Any, Any]:
    try:
        return get_domain(name)
    except InputError as exc:
        raise InputError(exc.reason, source="--domain") from None


def _check_choice(value: str, choices: Sequence[str], option: str) -> None:
    if value not in choices:
        raise InputError(f"expected one of {', '.join(choices)}, got {value!r}", source=option)


@app.command()
def replay(
    trace: Annotated[Path, typer.Argument(help="A JSON Lines trace written by run --trace.")],
) -> int:
    """Re-simulate a trace with the robot model; report the first step that does not hold."""
    report = replay_trace(trace)
    echo(f"{trace}: {report}")
    return 0 if report.ok else 1


@table_app.command("show")
def table_show(
    spec: Annotated[str, typer.Argument(help="Table file or bundled table name (handwritten).")],
    as_json: Annotated[bool, typer.Option("--json", help="Print the table file text.")] = False,
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES,
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES,
) -> int:
    """Print a replacement table: header, then each action's candidates in order."""
    table = resolve_table(
        spec, max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
    )
    if as_json:
        echo(dump_table(table).rstrip("\n"))
        return 0
    dom = table.domain
    title = (
        f"{spec}: {dom.name}, {table.shape}, made by {table.made_by}, version {table.version}"
    )
    view = Table(title=title)
    for column in ("action", "class", "faults", "candidates"):
        view.add_column(column)
    for entry in table.entries:
        candidates = (
            " | ".join(" ".join(dom.format_action(a) for a in c) for c in entry.candidates)
            or "(no replacement)"
        )
        faults = "" if entry.faults is None else dom.format_faults(entry.faults)
        view.add_row(
            dom.format_action(entry.action), dom.motion_class(entry.action), faults, candidates
        )
    console().print(view)
    return 0


@table_app.command("check")
def table_check(
    spec: Annotated[str, typer.Argument(help="Table file or bundled table name.")],
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES,
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES,
) -> int:
    """Load a table (re-simulating every candidate) and list gaps and dead candidates."""
    table = resolve_table(
        spec, max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
    )
    problems = check_table(table)
    for problem in problems:
        echo(f"{spec}: {problem}")
    errors = sum(1 for p in problems if p.severity == "error")
    candidates = sum(len(e.candidates) for e in table.entries)
    echo(
        f"{spec}: {len(table.entries)} entries, {candidates} candidates re-simulated; "
        f"{errors} errors, {len(problems) - errors} warnings"
    )
    return 1 if errors else 0
