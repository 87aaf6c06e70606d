"""Commands that make and measure replacement tables: ``selfrepair table generate|coverage``."""


import json
import time
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from selfrepair.cli._app import (
    MaxCells,
    MaxTableBytes,
    MaxTableCandidates,
    console,
    echo,
    echo_json,
    flag,
    option,
    table_app,
)
from selfrepair.cli._inputs import DomainOpt, Json, TableArg, domain_named, find_input
from selfrepair.cli._mission import Recursion
from selfrepair.errors import InputError
from selfrepair.limits import MAX_CELLS, MAX_TABLE_BYTES, MAX_TABLE_CANDIDATES

if TYPE_CHECKING:
    from rich.table import Table

    from selfrepair.repair.coverage import CoverageReport
    from selfrepair.tables.model import SomeTable
    from selfrepair.world.maze import Maze

__all__ = ["table_coverage", "table_generate"]


def _choice(value: str, allowed: Iterable[str], option: str) -> str:
    names = [str(a) for a in allowed]
    if value not in names:
        raise InputError(f"expected one of {', '.join(names)}, got {value!r}", source=option)
    return value


_FaultScope = Annotated[
    str, option("--faults", "SCOPE", "Fault sets: all, singles, doubles or none.")
]


@table_app.command("generate")
def table_generate(
    output: Annotated[
        Path, typer.Option("-o", "--output", metavar="FILE", help="Where to write the table.")
    ],
    domain: DomainOpt = "four-wheel",
    max_length: Annotated[int, option("--max-length", "N", "Longest candidate, in actions.")] = 5,
    per_action: Annotated[int, option("--per-action", "K", "Candidates per entry.")] = 5,
    faults: _FaultScope = "all",
    objective: Annotated[
        str, option("--objective", "NAME", "Cost: duration (ticks) or length.")
    ] = "duration",
    shape: Annotated[
        str, option("--shape", "NAME", "Table shape: fault-agnostic or fault-indexed.")
    ] = "fault-agnostic",
    priority: Annotated[
        str, option("--priority", "NAME", "Fault-agnostic tie-break after coverage: cost or walls.")
    ] = "cost",
) -> int:
    """Generate a replacement table as JSON.

    The candidates come from the robot model.
    """
    from selfrepair.tables.enumerate import FaultScope, Objective
    from selfrepair.tables.fileformat import dump_table
    from selfrepair.tables.generate import generate_table
    from selfrepair.tables.model import GenerateOptions, Priority, TableShape

    robot = domain_named(domain)
    options = GenerateOptions(
        shape=TableShape(_choice(shape, TableShape, "--shape")),
        max_length=max_length,
        per_action=per_action,
        faults=FaultScope(_choice(faults, FaultScope, "--faults")),
        objective=Objective(_choice(objective, Objective, "--objective")),
        priority=Priority(_choice(priority, Priority, "--priority")),
    )
    started = time.perf_counter()
    table = generate_table(robot, options)
    elapsed = time.perf_counter() - started
    text = dump_table(table)
    output.write_text(text, encoding="utf-8")
    candidates = sum(len(e.candidates) for e in table.entries)
    echo(
        f"{output}: {robot.name} {table.shape} table, {len(table.entries)} entries, "
        f"{candidates} candidates, {len(text.encode())} bytes, generated in {elapsed:.2f} s"
    )
    return 0


def _mazes(names: list[str] | None, no_walls: bool, max_cells: int) -> "list[tuple[str, Maze]]":
    from selfrepair.world.bundled import load_bundled, maze_names, resolve_maze

    if no_walls:
        return []
    if not names:
        return [(name, load_bundled(name)) for name in maze_names()]
    return [(name, resolve_maze(find_input(name), max_cells=max_cells)) for name in names]


@table_app.command("coverage")
def table_coverage(
    spec: TableArg,
    faults: _FaultScope = "all",
    objective: Annotated[
        str | None,
        option(
            "--objective",
            "NAME",
            "Cost for optimality: duration or length (default: the table's own).",
        ),
    ] = None,
    recursion: Recursion = "flat",
    maze: Annotated[
        list[str] | None,
        option(
            "--maze", "MAZE", "Maze for wall coverage (repeatable; default: every bundled maze)."
        ),
    ] = None,
    no_walls: Annotated[bool, flag("--no-walls", "Skip wall coverage.")] = False,
    per_fault: Annotated[bool, flag("--per-fault", "Also print one row per fault set.")] = False,
    json_out: Annotated[
        Path | None, option("--json-out", "FILE", "Write the full report as JSON.")
    ] = None,
    as_json: Json = False,
    max_cells: MaxCells = MAX_CELLS,
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES,
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES,
) -> int:
    """Measure a table's coverage and optimality.

    Against the exact optimum, in free space and next to the walls of mazes.
    """
    from selfrepair.repair.coverage import coverage_report
    from selfrepair.repair.replacement import RecursionMode
    from selfrepair.tables.enumerate import FaultScope, Objective
    from selfrepair.tables.fileformat import resolve_table

    table = resolve_table(
        find_input(spec), max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
    )
    _choice(faults, FaultScope, "--faults")
    _choice(recursion, RecursionMode, "--recursion")
    if objective is not None:
        _choice(objective, Objective, "--objective")
    report = coverage_report(
        table,
        faults=faults,
        objective=objective,
        mode=recursion,
        mazes=_mazes(maze, no_walls, max_cells),
        label=spec,
    )
    data = report.to_json()
    longer = _longer_needed(report, table)
    if longer is not None:
        data["longer_needed"] = longer
    if json_out is not None:
        json_out.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    if as_json:
        echo_json(data)
        return 0
    if per_fault:
        console().print(_fault_table(report))
    console().print(_summary_table(report))
    if report.walls:
        console().print(_wall_table(report))
    if longer is not None:
        echo(_longer_text(longer))
    return 0


def _longer_needed(report: "CoverageReport", table: "SomeTable") -> dict[str, Any] | None:
    """The uncovered replaceable pairs whose every replacement is longer than the table's
    longest candidate (``max_length`` of a generated table; the longest candidate listed
    otherwise), with the fewest actions each needs (exact search, the ``length`` objective);
    ``None`` when there are none."""
    from selfrepair.repair.optimum import optimal_replacements

    dom = table.domain
    limit = table.parameters.get("max_length")
    if not isinstance(limit, int):
        limit = max((len(c) for e in table.entries for c in e.candidates), default=0)
    uncovered = [p for p in report.pairs if p.optimum is not None and p.cost is None]
    shortest: dict[str, dict[object, Any]] = {}
    lengths = []
    for pair in uncovered:
        if pair.faults not in shortest:
            shortest[pair.faults] = optimal_replacements(
                dom, dom.parse_faults(pair.faults), "length"
            )
        fewest = shortest[pair.faults][dom.parse_action(pair.action)]
        if fewest is not None and fewest > limit:
            lengths.append(int(fewest))
    if not lengths:
        return None
    return {
        "pairs": len(lengths),
        "replaceable": sum(r.replaceable for r in report.rows),
        "uncovered": len(uncovered),
        "table_max_length": limit,
        "fewest_actions_min": min(lengths),
        "fewest_actions_max": max(lengths),
    }


def _longer_text(longer: dict[str, Any]) -> str:
    from selfrepair.tables.model import MAX_LENGTH_LIMIT

    low, high = longer["fewest_actions_min"], longer["fewest_actions_max"]
    span = str(low) if low == high else f"{low} to {high}"
    advice = (
        f"regenerate with --max-length {high}"
        if high <= MAX_LENGTH_LIMIT
        else f"the generator searches up to --max-length {MAX_LENGTH_LIMIT}"
    )
    return (
        f"{longer['pairs']} of the {longer['replaceable']} replaceable pairs "
        f"({longer['uncovered']} uncovered) {'needs' if longer['pairs'] == 1 else 'need'} "
        f"longer sub-plans: {span} actions, more than "
        f"the table's {longer['table_max_length']}; {advice}."
    )


def _percent(value: float | None) -> str:
    return "n/a" if value is None else f"{100 * value:.1f}%"


def _summary_table(report: "CoverageReport") -> "Table":
    from rich.table import Table
    t: dict[str, Any] = report.totals()
    view = Table(
        title=f"{report.table}: {report.shape}, made by {report.made_by} "
        f"(faults {report.scope}, {report.mode}, objective {report.objective})"
    )
    rows = [
        ("fault sets", str(t["fault_sets"])),
        ("(fault set, disabled action) pairs", str(t["disabled"])),
        ("replaceable (exact search)", str(t["replaceable"])),
        ("covered by the table", f"{t['covered']} ({_percent(t['coverage'])} of replaceable)"),
        ("fault sets fully covered", f"{t['fault_sets_fully_covered']} of {t['fault_sets']}"),
        (
            "picked replacement optimal",
            f"{t['optimal']} ({_percent(t['optimal_share'])} of covered)",
        ),
        (
            "mean / max cost above optimum",
            f"{_percent(t['mean_excess'])} / {_percent(t['max_excess'])}",
        ),
    ]
    if report.walls:
        rows.append(
            (
                "next to walls: uncovered executable pairs",
                f"{t['wall_uncovered']} of {t['wall_pairs']} "
                f"({_percent(t['wall_uncovered_share'])})",
            )
        )
    view.add_column("measure")
    view.add_column("value", justify="right")
    for row in rows:
        view.add_row(*row)
    return view


def _fault_table(report: "CoverageReport") -> "Table":
    from rich.table import Table
    view = Table(title="Per fault set (free space)")
    for column in ("faults", "disabled", "replaceable", "covered", "optimal", "max excess"):
        view.add_column(column, justify="left" if column == "faults" else "right")
    for r in report.rows:
        view.add_row(
            r.faults,
            str(r.disabled),
            str(r.replaceable),
            str(r.covered),
            str(r.optimal),
            _percent(float(r.excess_max)),
        )
    return view


def _wall_table(report: "CoverageReport") -> "Table":
    from rich.table import Table
    view = Table(
        title="Next to walls (flat): executable (pose, fault set, action) triples with "
        "no fitting usable candidate"
    )
    for column in ("maze", "pairs", "uncovered", "share"):
        view.add_column(column, justify="left" if column == "maze" else "right")
    for w in report.walls:
        view.add_row(w.maze, str(w.pairs), str(w.uncovered), _percent(w.share))
    return view
