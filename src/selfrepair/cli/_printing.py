"""Experiment results on a terminal: the per-strategy summary as rich tables that fit the
width, the findings, the baselines comparison, the crossover analysis and the fault sets."""

import sys
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from selfrepair.cli._app import console, echo

if TYPE_CHECKING:
    from rich.table import Table

    from selfrepair.experiment.findings import Finding, StrategySummary
    from selfrepair.experiment.store import Value
    from selfrepair.experiment.summary import FaultSetBite

__all__ = [
    "print_baselines",
    "print_crossover",
    "print_fault_sets",
    "print_findings",
    "print_summary",
]


_SHORT_HEADERS = {
    "completed": "done",
    "met a fault": "met a\nfault",
    "no replan": "no replan\n(missions)",
    "resolved locally (per encounter)": "resolved\nlocally\n(per enc.)",
    "replans/mission": "replans/\nmission",
    "ticks over optimum": "ticks over\noptimum",
    "plan distance": "plan\ndistance",
    "plan distance by motion": "plan dist.\nby motion",
    "repair compute/mission µs": "repair\ncompute/\nmission µs",
    "first repair cold µs": "first\nrepair\ncold µs",
    "first repair warm µs": "first\nrepair\nwarm µs",
    "repair latency median µs": "repair\nlatency\nmedian µs",
    "repair latency p99 µs": "repair\nlatency\np99 µs",
    "repairs/mission": "repairs/\nmission",
    "hit latency median µs": "hit\nlatency\nmedian µs",
}
"""Stacked headers for a terminal, where every column must fit without truncating a number."""


def print_summary(summaries: "list[StrategySummary]", *, title: str) -> None:
    """The per-strategy summary as a rich table: one wide table with full headers when piped
    (logs and files are never cut, whatever ``COLUMNS`` says), stacked headers on a terminal,
    split into as many tables as the terminal's width needs. Numbers are never truncated; long
    strategy names wrap after a comma on a terminal."""
    from selfrepair.experiment.findings import StrategySummary

    rows = [s.cells() for s in summaries]
    headers = StrategySummary.HEADERS
    out = console()  # piped: as wide as the table needs (see console())
    if not sys.stdout.isatty():
        out.print(_table(title, headers, rows, range(1, len(headers)), short=False))
        return
    groups = _column_groups(headers, rows, out.width)
    for part, columns in enumerate(groups, start=1):
        label = title if len(groups) == 1 else f"{title} ({part}/{len(groups)})"
        out.print(_table(label, headers, rows, columns, short=True))


_NAME_WIDTH = 24
"""Room kept for the strategy column on a terminal (names wrap after a comma)."""


def _column_groups(
    headers: tuple[str, ...], rows: list[tuple[str, ...]], width: int
) -> list[list[int]]:
    """The summary's columns packed, in order, into tables that each fit ``width``."""
    groups: list[list[int]] = [[]]
    used = _NAME_WIDTH
    for i in range(1, len(headers)):
        header = max(len(part) for part in _SHORT_HEADERS[headers[i]].split("\n"))
        need = max([header, *(len(r[i]) for r in rows)]) + 3  # padding and rule
        if groups[-1] and used + need > width:
            groups.append([])
            used = _NAME_WIDTH
        groups[-1].append(i)
        used += need
    return groups


def _table(
    title: str,
    headers: tuple[str, ...],
    rows: list[tuple[str, ...]],
    columns: Sequence[int],
    *,
    short: bool,
) -> "Table":
    from rich import box
    from rich.table import Table
    from rich.text import Text

    table = Table(title=title, box=box.SIMPLE_HEAD if short else box.HEAVY_HEAD)
    table.add_column(headers[0], overflow="fold", no_wrap=not short)
    for i in columns:
        header = _SHORT_HEADERS[headers[i]] if short else headers[i]
        widest = max([len(r[i]) for r in rows] + ([] if short else [len(header)]))
        table.add_column(header, justify="right", no_wrap=True, min_width=widest)
    for row in rows:
        name = row[0].replace(",", ", ") if short else row[0]
        table.add_row(Text(name), *(Text(row[i]) for i in columns))
    return table


def print_findings(findings: "list[Finding]", note: str | None = None) -> None:
    """Each finding as a short paragraph: its outcome and claim, then the evidence (wrapped);
    ``note`` (:func:`~selfrepair.experiment.findings.reference_note`) first, when given."""
    if note is not None:
        echo(textwrap.fill(note, 96, subsequent_indent="  "))
    for f in findings:
        echo(f.paragraph())


def print_crossover(rows: "list[dict[str, Value]]", figure: Path) -> None:
    """The crossover analysis of every replacement variant, and its figure when matplotlib is
    installed."""
    from selfrepair.experiment.scale import crossover
    from selfrepair.repair.strategies import StrategyName

    replacing = StrategyName.REPLACEMENT
    variants = sorted({str(r["variant"]) for r in rows if r.get("strategy") == replacing})
    results = [crossover(rows, v) for v in variants]
    echo(
        "Crossover: the maze side where repair compute per mission falls below 1/10 of the "
        "replanner's"
    )
    for result in results:
        for line in result.lines():
            echo("  " + line)
    from importlib.util import find_spec

    if find_spec("matplotlib") is None:  # extra viz missing: the numbers are enough
        echo("(no figure: it needs matplotlib, pip install 'selfrepair[viz]')")
        return
    from selfrepair.experiment.plots import figure_crossover

    echo(f"wrote {figure_crossover(results, figure)}")


def print_baselines(rows: "list[dict[str, Value]]") -> None:
    """When the rows hold D* Lite or LPG-adapt missions: the comparison on the missions every
    strategy ran, with 95% intervals, and repair time by maze (see docs/baselines.md)."""
    from selfrepair.experiment.comparison import baseline_tables, has_baselines

    if not has_baselines(rows):
        return
    tables = baseline_tables(rows)
    out = console()  # piped: as wide as the table needs (see console())
    for title, (headers, body) in (
        (f"Baselines on the same missions ({', '.join(tables.mazes)})", tables.comparison),
        ("First repair ms by maze", tables.first_repair),
        ("Repair ms/mission by maze", tables.repair_compute),
    ):
        title += ": medians [95% intervals]"
        out.print(_table(title, headers, body, range(1, len(headers)), short=False))


def print_fault_sets(bites: "list[FaultSetBite]") -> None:
    """Per fault set: missions that met a faulty action, of all missions and of variant
    ``replan``'s (the A* replanner the findings compare with)."""
    echo("Fault sets: missions that met a faulty action (all strategies; variant replan)")
    for b in bites:
        echo(
            f"  {b.faults or '(none)':<12} {b.met:>5}/{b.missions:<5} "
            f"{b.replan_met:>4}/{b.replan_missions}"
        )
