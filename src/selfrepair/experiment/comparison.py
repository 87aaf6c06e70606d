"""The baselines comparison: replacement against D* Lite, LPG-adapt and A* replanning, on the same
missions, with 95% bootstrap intervals (the ``baselines`` experiment; docs/baselines.md).

Rows are the stored mission rows (:meth:`selfrepair.experiment.store.ResultStore.rows`); only
clearance weight 0 is compared. *The same missions*: the table is computed over the situations
(maze, route, faults, fault time, detection, replicate) that **every** variant ran, so a strategy
limited to some mazes (LPG-adapt cannot take ``wide-long``) limits the table to those; the per-maze
figures (:func:`per_maze`) use every row. The unit of every statistic is the mission; intervals
are :func:`~selfrepair.stats.bootstrap_interval`'s (percentile bootstrap, fixed seed).

Columns of :class:`BaselineLine`:

* *reached*: missions that reached the goal, of all;
* *first repair ms*: the repair latency at the first faulty action (``first_repair_ns``: from
  meeting it to having the next executable action; what the robot waits there), over the
  missions that met a fault; median [95% interval]. For LPG-adapt this is the whole call: export,
  unified-planning, the LPG process, reading and re-simulating its plan, and any fallback;
* *repair ms/mission*: every repair of the mission added up (``repair_compute_ns``; the replacing
  robot repairs once per faulty action it meets, the others replan once);
* *expansions/mission*: search nodes the repairs expanded (``repair_expansions``), median over the
  missions that met a fault: search effort independent of the language a planner is written in
  (LPG reports none: ``n/a``);
* *ticks to goal*: the mission's execution time in ticks (failed attempts included), median over
  reached missions (time to goal);
* *ticks over A\\**: plan quality, paired: the mission's ticks minus those of the A* replanner
  (variant ``replan``) in the same situation, mean over the pairs where both reached the goal
  (0: as good as optimal replanning from the fault; the mean, because most differences are 0);
* *plan distance*: plan stability (Fox et al. 2006) between the initial and the executed plan,
  median (lower is more stable);
* *fallbacks*: repairs in which the strategy's own method gave up and replanning took over (table
  misses; LPG's time-outs, failures and no-plan answers), of all repairs; *LPG time-outs* among
  them.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import ClassVar

from selfrepair.experiment.store import Value
from selfrepair.experiment.summary import Row, group_label, met_fault, num, strategy_order
from selfrepair.experiment.verdicts import situation
from selfrepair.repair.strategies import StrategyName
from selfrepair.stats import Interval, bootstrap_interval

__all__ = [
    "BASELINE_STRATEGIES",
    "FIRST_REPAIR",
    "REFERENCE",
    "REPAIR_COMPUTE",
    "BaselineLine",
    "BaselineTables",
    "MazeLatency",
    "baseline_tables",
    "common_rows",
    "compare_baselines",
    "has_baselines",
    "maze_table",
    "per_maze",
]

BASELINE_STRATEGIES = (StrategyName.DSTAR_LITE, StrategyName.LPG_ADAPT)
"""The strategies from neighbouring fields; rows with one of them switch the comparison on."""

REFERENCE = StrategyName.REPLAN
"""The variant plan quality is measured against: A* replanning with the default backend."""

FIRST_REPAIR = "first_repair_ns"
"""Column of the repair latency at the first faulty action."""

REPAIR_COMPUTE = "repair_compute_ns"
"""Column of every repair of a mission added up."""


_TIMEOUT = "lpg-adapt:timeout"
_NO_EFFORT = frozenset({StrategyName.LPG_ADAPT})
"""Strategies whose own search effort is not counted in expansions."""


def has_baselines(rows: Iterable[Row]) -> bool:
    """Whether ``rows`` hold missions of a baseline strategy (D* Lite or LPG-adapt)."""
    return any(r.get("strategy") in BASELINE_STRATEGIES for r in rows)


def _weight_zero(rows: Iterable[Row]) -> list[Row]:
    return [r for r in rows if Fraction(str(r.get("clearance_weight") or "0")) == 0]


def common_rows(rows: Iterable[Row]) -> list[Row]:
    """The weight-0 rows whose situation every variant ran."""
    rows = _weight_zero(rows)
    by_variant: dict[str, set[tuple[Value, ...]]] = defaultdict(set)
    for r in rows:
        by_variant[group_label(r)].add(situation(r))
    if not by_variant:
        return []
    shared = set.intersection(*by_variant.values())
    return [r for r in rows if situation(r) in shared]


@dataclass(frozen=True, slots=True)
class BaselineLine:
    """One variant's line of the comparison (see the module docstring); times in ms.
    ``strategy`` is the rows' ``strategy`` column (read as a column, not from the label)."""

    label: str
    strategy: str
    missions: int
    reached: int
    met_fault: int
    first_ms: Interval | None
    repair_ms: Interval | None
    expansions: Interval | None
    ticks: Interval | None
    over_reference: Interval | None
    plan_distance: Interval | None
    repairs: int
    fallbacks: int
    timeouts: int

    HEADERS: ClassVar[tuple[str, ...]] = (
        "strategy",
        "reached",
        "first repair ms",
        "repair ms/mission",
        "expansions/mission",
        "ticks to goal",
        "ticks over A*",
        "plan distance",
        "fallbacks",
        "LPG time-outs",
    )

    def cells(self) -> tuple[str, ...]:
        """The line as display strings, in :attr:`HEADERS` order."""
        expansions = "n/a" if self.strategy in _NO_EFFORT else _text(self.expansions)
        return (
            self.label,
            f"{self.reached}/{self.missions}",
            _text(self.first_ms, 2),
            _text(self.repair_ms, 2),
            expansions,
            _text(self.ticks, 1),
            _text(self.over_reference, 2),
            _text(self.plan_distance),
            f"{self.fallbacks}/{self.repairs}",
            str(self.timeouts) if self.label.startswith(StrategyName.LPG_ADAPT) else "-",
        )


def _text(value: Interval | None, digits: int = 0) -> str:
    if value is None:
        return "-"
    if digits and abs(value.high) >= 100:
        digits = 0
    return value.text(digits)


def compare_baselines(rows: Iterable[Row], *, same_missions: bool = True) -> list[BaselineLine]:
    """One line per variant at clearance weight 0, over the situations every variant ran
    (``same_missions``; otherwise over all weight-0 rows)."""
    kept = common_rows(rows) if same_missions else _weight_zero(rows)
    reference = {situation(r): r for r in kept if r.get("variant") == REFERENCE}
    groups: dict[str, list[Row]] = defaultdict(list)
    for r in kept:
        groups[group_label(r)].append(r)
    return [_line(label, groups[label], reference) for label in sorted(groups, key=strategy_order)]


def _line(label: str, rows: list[Row], reference: dict[tuple[Value, ...], Row]) -> BaselineLine:
    met = [r for r in rows if met_fault(r)]
    reached = [r for r in rows if r.get("reached") == 1]
    over = [
        num(r, "ticks_float") - num(ref, "ticks_float")
        for r in reached
        if (ref := reference.get(situation(r))) is not None and ref.get("reached") == 1
    ]
    return BaselineLine(
        label=label,
        strategy=str(rows[0].get("strategy")),
        missions=len(rows),
        reached=len(reached),
        met_fault=len(met),
        first_ms=bootstrap_interval([num(r, FIRST_REPAIR) / 1e6 for r in met]),
        repair_ms=bootstrap_interval([num(r, REPAIR_COMPUTE) / 1e6 for r in met]),
        expansions=bootstrap_interval([num(r, "repair_expansions") for r in met]),
        ticks=bootstrap_interval([num(r, "ticks_float") for r in reached]),
        over_reference=bootstrap_interval(over, "mean"),
        plan_distance=bootstrap_interval([num(r, "plan_distance") for r in rows]),
        repairs=sum(int(num(r, "repair_count")) for r in rows),
        fallbacks=sum(int(num(r, "fallbacks")) for r in rows),
        timeouts=sum(_attempts(r).get(_TIMEOUT, 0) for r in rows),
    )


def _attempts(row: Row) -> dict[str, int]:
    """The ``repair_attempts`` counts of a row (empty for rows stored before the column)."""
    text = row.get("repair_attempts")
    try:
        counts = json.loads(text) if isinstance(text, str) else {}
    except ValueError:
        return {}  # not written by the executor: nothing to count
    if not isinstance(counts, dict):
        return {}
    return {str(k): v for k, v in counts.items() if isinstance(v, int)}


@dataclass(frozen=True, slots=True)
class MazeLatency:
    """A time in ms (a nanosecond column) of one variant on one maze: median [95% interval]."""

    label: str
    maze: str
    free_cells: int
    ms: Interval


def per_maze(rows: Iterable[Row], column: str = FIRST_REPAIR) -> list[MazeLatency]:
    """``column`` (nanoseconds) in ms for every variant and maze (weight 0, missions that met a
    fault), by maze size, then variant."""
    groups: dict[tuple[str, str], list[float]] = defaultdict(list)
    cells: dict[str, int] = {}
    for r in _weight_zero(rows):
        if not met_fault(r):
            continue
        maze = str(r.get("maze"))
        groups[(group_label(r), maze)].append(num(r, column) / 1e6)
        cells[maze] = int(num(r, "maze_free_cells"))
    out = []
    for (label, maze), values in groups.items():
        interval = bootstrap_interval(values)
        assert interval is not None  # every group has a value
        out.append(MazeLatency(label, maze, cells[maze], interval))
    return sorted(out, key=lambda m: (m.free_cells, m.maze, strategy_order(m.label)))


def maze_table(
    rows: Sequence[Row], column: str = FIRST_REPAIR
) -> tuple[tuple[str, ...], list[tuple[str, ...]]]:
    """``column`` in ms by variant (rows) and maze (columns, by size): headers and body of a
    table, as display strings."""
    cells = per_maze(rows, column)
    mazes = list(dict.fromkeys((m.maze, m.free_cells) for m in cells))
    labels = sorted({m.label for m in cells}, key=strategy_order)
    found = {(m.label, m.maze): m.ms for m in cells}
    headers = ("strategy", *(f"{maze} ({free} free cells)" for maze, free in mazes))
    body = [(label, *(_text(found.get((label, maze)), 2) for maze, _ in mazes)) for label in labels]
    return headers, body


TextTable = tuple[tuple[str, ...], list[tuple[str, ...]]]
"""A table's headers and body, as display strings."""


@dataclass(frozen=True, slots=True)
class BaselineTables:
    """What the baselines section shows, whichever way it is printed (a Markdown report or a
    terminal): the comparison on the ``missions`` every variant ran, on ``mazes``; then
    :data:`FIRST_REPAIR` and :data:`REPAIR_COMPUTE` in ms by maze."""

    missions: int
    mazes: tuple[str, ...]
    comparison: TextTable
    first_repair: TextTable
    repair_compute: TextTable


def baseline_tables(rows: Sequence[Row]) -> BaselineTables:
    """The three tables of the baselines section over ``rows`` (see :class:`BaselineTables`)."""
    lines = compare_baselines(rows)
    return BaselineTables(
        missions=lines[0].missions if lines else 0,
        mazes=tuple(sorted({str(r.get("maze")) for r in common_rows(rows)})),
        comparison=(BaselineLine.HEADERS, [line.cells() for line in lines]),
        first_repair=maze_table(rows, FIRST_REPAIR),
        repair_compute=maze_table(rows, REPAIR_COMPUTE),
    )
