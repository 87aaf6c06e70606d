"""Commands that run and check missions: ``selfrepair run``, ``selfrepair compare``,
``selfrepair replay``, ``selfrepair table show`` and ``selfrepair table check``.

Exit codes: ``run`` 0 when the goal is reached, 1 when the mission ends otherwise; ``compare`` 0
when every strategy reached the goal, 1 otherwise; ``replay`` 0 when every step holds, 1
otherwise; ``table check`` 0 without errors (warnings allowed), 1 with errors; bad input is exit 2
(see :func:`selfrepair.cli.main`).

Times: the compiled kernels are loaded before the mission starts (reported apart, never inside a
planning time or a repair latency), and by default the mission runs once untimed first.
"""


from typing import TYPE_CHECKING, Annotated

from selfrepair.cli._app import (
    MaxTableBytes,
    MaxTableCandidates,
    MaxTraceBytes,
    app,
    console,
    echo,
    echo_json,
    flag,
    number_json,
    option,
    table_app,
)
from selfrepair.cli._inputs import Json, TableArg, TraceArg, TraceOut, domain_named, find_input
from selfrepair.cli._mission import MissionOptions, mission_options
from selfrepair.cli._rowjson import row_json
from selfrepair.cli._spec import mission_spec, table_note
from selfrepair.cli.planning import kernel_load_ns
from selfrepair.limits import MAX_TABLE_BYTES, MAX_TABLE_CANDIDATES, MAX_TRACE_BYTES
from selfrepair.textio import JSONObject

if TYPE_CHECKING:
    from selfrepair.execution.result import MissionResult
    from selfrepair.experiment.compare import Comparison

__all__ = ["compare", "mission_picture", "replay", "run", "table_check", "table_show"]

PLANNED_CHAR = "+"
EXECUTED_CHAR = "*"
SITE_CHARS = {
    "replacement": "R",
    "lookahead": "L",
    "replan": "P",
    "plan-repair": "A",
    "probe": "D",
}
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
    "plan_repairs",
    "fallbacks",
    "initial_planning_ns",
    "repair_latency_median_ns",
    "repair_latency_p99_ns",
    "compute_per_action_ns",
    "plan_distance",
)
_HIDDEN_SHOWN = (
    "behaviour",
    "observation_noise",
    "bumps",
    "surprise_step",
    "isolation_actions",
    "isolated_right",
    "probes",
    "classes_left",
)
"""Shown too when the faults are hidden (docs/diagnosis.md)."""


def mission_picture(result: "MissionResult") -> str:
    """The maze with the planned path, the executed path, the repair sites, start and goal."""
    from selfrepair.execution.result import StepSource
    from selfrepair.geometry import Cell
    from selfrepair.world.render import GOAL_CHAR, HEADING_CHARS, render_ascii

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


def _picture_legend() -> str:
    from selfrepair.world.render import GOAL_CHAR

    legend = (
        ("#", "wall"),
        (".", "free"),
        ("^ > v <", "start pose facing N, E, S, W"),
        (GOAL_CHAR, "goal"),
        (PLANNED_CHAR, "planned path (initial plan), not executed"),
        (EXECUTED_CHAR, "executed path"),
        (
            "R L P A D",
            "repair site: table replacement, lookahead window (or rejoin), replan, plan repair "
            "(LPG), diagnosis probe",
        ),
        (FAILED_CHAR, "failed attempt (fault learned on use)"),
    )
    width = max(len(char) for char, _ in legend)
    return "".join(f"{char:<{width}}  {meaning}\n" for char, meaning in legend)


def _timing_note(load_ns: int, warmed: bool) -> str:
    parts = []
    if load_ns:
        parts.append(f"kernels loaded in {load_ns / 1e6:.0f} ms before the mission")
    parts.append("timed after an untimed warm-up run" if warmed else "no warm-up run")
    return "times: " + "; ".join(parts) + " (neither is counted)"


@app.command()
@mission_options
def run(
    *,
    strategy: Annotated[
        str,
        option(
            "--strategy",
            "NAME",
            "Repair strategy: replan, replacement, lookahead, dstar-lite or lpg-adapt "
            "(pddl extra).",
        ),
    ] = "replacement",
    mission: MissionOptions,
    trace: TraceOut = None,
    as_json: Json = False,
) -> int:
    """Run one mission: plan, execute with faults, repair.

    Shows the maze with the planned and executed paths and the repair sites, then the metrics.
    Exit 1 when the goal is not reached.

    Takes every option of compare but --strategies: --strategy names the one strategy to run,
    and --trace is run's own.
    """
    from selfrepair.execution.executor import run_mission
    from selfrepair.execution.metrics import mission_row
    from selfrepair.execution.trace import write_trace

    spec = mission_spec(mission, strategy)
    load_ns = kernel_load_ns(mission.backend, domain=spec.domain)
    warm_up = mission.warm_up
    if warm_up:
        run_mission(spec)
    result = run_mission(spec)
    if trace is not None:
        write_trace(result, trace)
    row = mission_row(result)
    if as_json:
        echo_json({**row_json(row), "kernel_load_ms": round(load_ns / 1e6, 3), "warm_up": warm_up})
        return 0 if result.reached else 1
    from rich.table import Table
    from rich.text import Text

    echo(mission_picture(result) + _picture_legend())
    note = table_note(mission, spec)
    if note is not None:
        echo(note)
    metrics = Table(title=Text(f"Mission on {spec.maze.name or mission.maze}"))
    metrics.add_column("metric")
    metrics.add_column("value", justify="right")
    shown = row_json(row)
    hidden = row["detection"] == "hidden"
    for key in (*_SHOWN, *(_HIDDEN_SHOWN if hidden else ())):
        value = row[key] if key in ("ticks", "plan_cost_before", "plan_cost_after") else shown[key]
        metrics.add_row(key, Text(_cell(value)))
    console().print(metrics)
    echo(_timing_note(load_ns, warm_up))
    return 0 if result.reached else 1


def _cell(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, dict):
        return ",".join(f"{k}:{v}" for k, v in value.items())
    return str(value)


@app.command()
@mission_options
def compare(
    *,
    strategies: Annotated[
        str,
        option(
            "--strategies",
            "NAMES",
            "Comma-separated strategies to run (default: every registered one that can "
            "run here; those that cannot are listed with the reason).",
            show_default=False,
        ),
    ] = "",
    mission: MissionOptions,
    as_json: Json = False,
) -> int:
    """Run every strategy on one mission, side by side.

    Ends with a one-line verdict. Exit 1 when a strategy does not reach the goal.

    Each strategy gets the same maze, route, faults and planner; the table options apply to
    the strategies that use a table, and the other strategy options (--window, --rewrite,
    --lpg-time-limit) to the strategies they name. Latencies are taken after an untimed
    warm-up run.

    Takes every option of run but two: --strategies in place of --strategy, and no --trace
    (a trace holds one mission: write one per strategy with run --trace).
    """
    from selfrepair.experiment.compare import compare_strategies, runnable_strategies

    given = tuple(s.strip() for s in strategies.split(",") if s.strip())
    hidden = mission.detect == "hidden"
    names = given or runnable_strategies(domain_named(mission.domain_name), hidden=hidden)[0]
    spec = mission_spec(mission, names[0], names)
    load_ns = kernel_load_ns(mission.backend, domain=spec.domain)
    comparison = compare_strategies(spec, given or None, warm_up=mission.warm_up)
    if as_json:
        echo_json(_comparison_json(comparison, load_ns))
    else:
        title = (
            f"{spec.maze.name or mission.maze}: {spec.start} to {spec.goal[0]},{spec.goal[1]}, "
            f"faults {mission.faults or 'none'}"
        )
        note = table_note(mission, spec)
        if note is not None:
            echo(note)
        _print_comparison(comparison, title, load_ns)
    return 0 if all(r.result.reached for r in comparison.runs) else 1


_COMPARE_HEADERS = (
    "strategy",
    "status",
    "ticks",
    "repairs",
    "replans",
    "replacements",
    "lookaheads",
    "latency median µs",
    "latency p99 µs",
    "plan distance",
    "motion distance",
)


def _us(ns: int | None) -> str:
    return "–" if ns is None else f"{ns / 1000:,.1f}"


def _print_comparison(comparison: "Comparison", title: str, load_ns: int) -> None:
    from rich.table import Table
    from rich.text import Text

    view = Table(title=Text(title))
    for i, header in enumerate(_COMPARE_HEADERS):
        view.add_column(header, justify="left" if i < 2 else "right", no_wrap=i == 0)
    for r in comparison.runs:
        cells = (
            r.label,
            r.status,
            str(r.ticks),
            str(r.repairs),
            str(r.replans),
            str(r.replacements),
            str(r.lookaheads),
            _us(r.latency_median_ns),
            _us(r.latency_p99_ns),
            str(r.plan_distance),
            str(r.motion_distance),
        )
        view.add_row(*(Text(c) for c in cells))  # Text: "[...]" in a label is not markup
    console().print(view)
    for name, reason in comparison.skipped:
        echo(f"skipped {name}: {reason}")
    echo(f"verdict: {comparison.verdict}")
    echo(_timing_note(load_ns, comparison.warmed_up))


def _comparison_json(comparison: "Comparison", load_ns: int) -> JSONObject:
    return {
        "runs": [
            {
                "strategy": r.label,
                "status": r.status,
                "ticks": number_json(r.ticks),
                "ticks_exact": str(r.ticks),
                "repairs": r.repairs,
                "replans": r.replans,
                "replacements": r.replacements,
                "lookaheads": r.lookaheads,
                "repair_latency_median_ns": r.latency_median_ns,
                "repair_latency_p99_ns": r.latency_p99_ns,
                "plan_distance": r.plan_distance,
                "plan_distance_motion": r.motion_distance,
            }
            for r in comparison.runs
        ],
        "skipped": [{"strategy": name, "reason": reason} for name, reason in comparison.skipped],
        "verdict": comparison.verdict,
        "warm_up": comparison.warmed_up,
        "kernel_load_ms": round(load_ns / 1e6, 3),
    }


_Partial = Annotated[
    bool, flag("--partial", "Accept a trace without a summary line (a run that was cut short).")
]


@app.command()
def replay(
    trace: TraceArg,
    partial: _Partial = False,
    max_trace_bytes: MaxTraceBytes = MAX_TRACE_BYTES,
) -> int:
    """Re-simulate a trace; report the first bad step.

    Every step is checked against the robot model and the fault schedule. Exit 1 when a step
    does not hold.
    """
    from selfrepair.execution.trace import read_trace
    from selfrepair.execution.trace import replay as replay_trace

    parsed = read_trace(trace, partial=partial, max_trace_bytes=max_trace_bytes)
    report = replay_trace(parsed)
    if report.ok:
        cut = " (a partial trace: no summary line)" if report.partial else ""
        echo(f"{trace}: ok: all {report.steps_checked} steps hold under the robot model{cut}")
    else:
        echo(f"{trace}: {report}")
    return 0 if report.ok else 1


@table_app.command("show")
def table_show(
    spec: TableArg,
    as_json: Json = False,
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES,
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES,
) -> int:
    """Print a replacement table.

    The header, then each action's candidates in order.
    """
    from rich.table import Table
    from rich.text import Text

    from selfrepair.tables.fileformat import dump_table, resolve_table

    table = resolve_table(
        find_input(spec), max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
    )
    if as_json:
        echo(dump_table(table).rstrip("\n"))
        return 0
    dom = table.domain
    title = f"{spec}: {dom.name}, {table.shape}, made by {table.made_by}, version {table.version}"
    view = Table(title=Text(title))
    for column in ("action", "class", "faults", "candidates"):
        view.add_column(column)
    for entry in table.entries:
        candidates = (
            " | ".join(" ".join(dom.format_action(a) for a in c) for c in entry.candidates)
            or "(no replacement)"
        )
        faults = "" if entry.faults is None else dom.format_faults(entry.faults)
        action = dom.format_action(entry.action)
        cells = (action, dom.motion_class(entry.action), faults, candidates)
        view.add_row(*(Text(c) for c in cells))
    console().print(view)
    return 0


@table_app.command("check")
def table_check(
    spec: TableArg,
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES,
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES,
) -> int:
    """Check a table: gaps and dead candidates.

    Loads the table (re-simulating every candidate). Exit 1 when there are errors. An empty
    entry of a fault-indexed table marks an action without a replacement under those faults
    (the generator writes them): counted, not warned about.
    """
    from selfrepair.tables.fileformat import resolve_table
    from selfrepair.tables.model import check_table, no_replacement_marks

    table = resolve_table(
        find_input(spec), max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
    )
    problems = check_table(table)
    for problem in problems:
        echo(f"{spec}: {problem}")
    errors = sum(1 for p in problems if p.severity == "error")
    candidates = sum(len(e.candidates) for e in table.entries)
    marks = no_replacement_marks(table)
    marked = (
        f" ({marks} empty fault-indexed entries mark an action without a replacement under "
        "those faults: intended, not warned about)"
        if marks
        else ""
    )
    echo(
        f"{spec}: {len(table.entries)} entries, {candidates} candidates re-simulated; "
        f"{errors} errors, {len(problems) - errors} warnings{marked}"
    )
    return 1 if errors else 0
