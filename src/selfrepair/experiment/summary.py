"""The per-strategy summary of stored rows: mission-level figures first, with 95% intervals.

Rows are the dicts of :meth:`selfrepair.experiment.store.ResultStore.rows`: label columns
(``variant``, ``clearance_weight``, ``maze``, ``route``, ``faults``, ...) and the metrics.
Every number of the CLI's table, the report and the README is computed here from those rows.

Definitions (also in docs/experiments.md). A mission *met a fault* when it met at least one faulty
action (``faulty_encounters > 0``); the mission-level shares are over those missions, because a
mission that never meets a faulty action says nothing about repair.

* *no replan*: share of the missions that met a fault which reached the goal without any full
  replan (``completed_without_replan``; a table's fallback replan counts);
* *resolved locally (per encounter)*: share of faulty encounters repaired by a table replacement
  or a lookahead window. Weighted by encounters, whose number depends on the robot (a robot that
  replans stops meeting faults), so it is shown after the mission-level share;
* *over optimum*: ticks taken minus the fault-free optimum at clearance weight 0 on the same route
  (one reference for every variant), mean over reached missions, with its interval;
* *repair compute/mission*: every repair's time added up, per mission that met a fault; median
  over missions with its interval. The initial plan is left out: every strategy of a situation
  makes the same one;
* *first repair cold / warm*: the first repair of the mission when every derived-data cache of the
  process was emptied, and the same repair in a warm run (see ``timing.execute_mission``); medians
  over missions with intervals;
* *repair latency median, p99*: over every repair of every mission (pooled; descriptive only,
  repairs of one mission are not independent);
* *repairs/mission*: repairs (faulty encounters and defensive replans), mean over missions that
  met a fault (a whole-plan rewrite is one repair, however many actions it substitutes);
* *hit latency median*: over the repairs a table replacement resolved (for a rewriting variant,
  its whole-plan rewrites), pooled;
* *plan distance* (Fox et al. 2006) between initial and executed plan, mean over missions, as
  ground actions and by motion class.
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from collections.abc import Iterable
from dataclasses import dataclass
from typing import ClassVar

from selfrepair.experiment.store import Value
from selfrepair.repair.strategies import RepairSource, StrategyName
from selfrepair.stats import Interval, bootstrap_interval, lower_median, percentile

__all__ = [
    "STRATEGY_ORDER",
    "FaultSetBite",
    "Row",
    "StrategySummary",
    "fault_set_bite",
    "group_label",
    "is_reference_replan",
    "local_share",
    "met_fault",
    "num",
    "repairs_of",
    "strategy_order",
    "summarize",
]

Row = dict[str, Value]


def group_label(row: Row) -> str:
    """``variant`` plus the clearance weight when it is not 0, e.g. ``replan`` or
    ``replacement[handwritten,guarded] w=1``."""
    weight = str(row.get("clearance_weight") or "0")
    return str(row["variant"]) + ("" if weight == "0" else f" w={weight}")


def num(row: Row, column: str) -> float:
    """A numeric column as a float (0 when missing or not a number)."""
    value = row.get(column)
    return float(value) if isinstance(value, int | float) else 0.0


def is_reference_replan(row: Row) -> bool:
    """Whether ``row`` is a mission of the replanning robot the findings compare with: strategy
    ``replan`` with the default planner backend (variant ``replan``; an experiment may also run
    ``replan[python]``, the pure-Python search, which is not the reference)."""
    return (
        row.get("strategy") == StrategyName.REPLAN
        and row.get("variant", StrategyName.REPLAN) == StrategyName.REPLAN
    )


def met_fault(row: Row) -> bool:
    """Whether the mission met at least one faulty action."""
    return num(row, "faulty_encounters") > 0


def repairs_of(row: Row) -> list[tuple[str, int]]:
    """``(source, latency_ns)`` of every repair of a mission row."""
    latencies = json.loads(str(row.get("repair_latencies_ns") or "[]"))
    sources = json.loads(str(row.get("repair_sources") or "[]"))
    if len(sources) != len(latencies):
        sources = ["?"] * len(latencies)
    return list(zip(sources, latencies, strict=True))


def local_share(rows: Iterable[Row]) -> tuple[float | None, int, int]:
    """(share, resolved locally, encounters) over ``rows``: per encounter."""
    resolved = encounters = 0
    for row in rows:
        resolved += int(num(row, "replacements") + num(row, "lookaheads"))
        encounters += int(num(row, "faulty_encounters"))
    return (resolved / encounters if encounters else None), resolved, encounters


def _values(rows: Iterable[Row], column: str, scale: float = 1.0) -> list[float]:
    return [float(v) * scale for r in rows if isinstance(v := r.get(column), int | float)]


@dataclass(frozen=True, slots=True)
class StrategySummary:
    """One line of the per-strategy table. Times are in microseconds."""

    label: str
    missions: int
    completed: int
    met_fault: int
    no_replan: int
    resolved_locally: float | None
    replans_per_mission: float
    over_optimum: Interval | None
    plan_distance_mean: float
    plan_distance_motion_mean: float | None
    repair_compute_us: Interval | None
    cold_first_repair_us: Interval | None
    warm_first_repair_us: Interval | None
    latency_median_us: float | None
    latency_p99_us: float | None
    repairs_per_mission: float | None = None
    hit_latency_median_us: float | None = None

    HEADERS: ClassVar[tuple[str, ...]] = (
        "strategy",
        "completed",
        "met a fault",
        "no replan",
        "resolved locally (per encounter)",
        "replans/mission",
        "ticks over optimum",
        "plan distance",
        "plan distance by motion",
        "repair compute/mission µs",
        "first repair cold µs",
        "first repair warm µs",
        "repair latency median µs",
        "repair latency p99 µs",
        "repairs/mission",
        "hit latency median µs",
    )

    @property
    def no_replan_share(self) -> float | None:
        """Share of the missions that met a fault completed without a replan."""
        return self.no_replan / self.met_fault if self.met_fault else None

    def cells(self) -> tuple[str, ...]:
        """The row as display strings, in :attr:`HEADERS` order."""
        share = self.no_replan_share
        return (
            self.label,
            f"{self.completed}/{self.missions}",
            str(self.met_fault),
            "-" if share is None else f"{self.no_replan}/{self.met_fault} ({100 * share:.1f}%)",
            "-" if self.resolved_locally is None else f"{100 * self.resolved_locally:.1f}%",
            f"{self.replans_per_mission:.2f}",
            _interval(self.over_optimum, 1),
            f"{self.plan_distance_mean:.1f}",
            _fmt(self.plan_distance_motion_mean, 1),
            _interval(self.repair_compute_us),
            _interval(self.cold_first_repair_us),
            _interval(self.warm_first_repair_us),
            _fmt(self.latency_median_us),
            _fmt(self.latency_p99_us),
            _fmt(self.repairs_per_mission, 2),
            _fmt(self.hit_latency_median_us),
        )


def _interval(value: Interval | None, digits: int = 0) -> str:
    return "-" if value is None else value.text(digits)


def _fmt(value: float | None, digits: int = 0) -> str:
    if value is None:
        return "-"
    if digits == 0:
        return f"{value:,.0f}" if value >= 10 else f"{value:.1f}"
    return f"{value:.{digits}f}"


def summarize(rows: Iterable[Row]) -> list[StrategySummary]:
    """One summary per strategy variant and clearance weight, in a stable order."""
    groups: dict[str, list[Row]] = defaultdict(list)
    for row in rows:
        groups[group_label(row)].append(row)
    return [_summary(label, groups[label]) for label in sorted(groups, key=strategy_order)]


STRATEGY_ORDER = (
    StrategyName.REPLAN,
    StrategyName.DSTAR_LITE,
    StrategyName.LPG_ADAPT,
    StrategyName.REPLACEMENT,
    StrategyName.LOOKAHEAD,
)
"""The order of strategies in tables: the replanners first (the reference, then the baselines
from neighbouring fields), then the table-based strategies; other strategies after them."""


def strategy_order(label: str) -> tuple[int, str]:
    """Sort key of a variant label (``replan``, ``replacement[handwritten,guarded] w=1/2``, ...):
    by :data:`STRATEGY_ORDER`, then by label."""
    strategy = label.split("[")[0].split(" ")[0]
    rank = STRATEGY_ORDER.index(strategy) if strategy in STRATEGY_ORDER else len(STRATEGY_ORDER)
    return rank, label


def _summary(label: str, rows: list[Row]) -> StrategySummary:
    met = [r for r in rows if met_fault(r)]
    repairs = [(source, lat / 1000) for r in rows for source, lat in repairs_of(r)]
    latencies = [lat for _, lat in repairs]
    hits = [lat for source, lat in repairs if source == _HIT]
    share, _, _ = local_share(rows)
    motion = _values(rows, "plan_distance_motion")
    return StrategySummary(
        label=label,
        missions=len(rows),
        completed=sum(1 for r in rows if r.get("reached") == 1),
        met_fault=len(met),
        no_replan=sum(1 for r in met if r.get("completed_without_replan") == 1),
        resolved_locally=share,
        replans_per_mission=sum(num(r, "replans") for r in rows) / len(rows),
        over_optimum=bootstrap_interval(_values(rows, "ticks_over_optimum"), "mean"),
        plan_distance_mean=sum(num(r, "plan_distance") for r in rows) / len(rows),
        plan_distance_motion_mean=sum(motion) / len(motion) if motion else None,
        repair_compute_us=bootstrap_interval(_values(met, "repair_compute_ns", 1e-3)),
        cold_first_repair_us=bootstrap_interval(_values(met, "cold_first_repair_ns", 1e-3)),
        warm_first_repair_us=bootstrap_interval(_values(met, "first_repair_ns", 1e-3)),
        latency_median_us=lower_median(latencies) if latencies else None,
        latency_p99_us=percentile(latencies, 0.99) if latencies else None,
        repairs_per_mission=sum(num(r, "repair_count") for r in met) / len(met) if met else None,
        hit_latency_median_us=lower_median(hits) if hits else None,
    )


_HIT = RepairSource.REPLACEMENT
"""The ``repair_sources`` entry of a table hit (``RepairSource.REPLACEMENT``)."""


@dataclass(frozen=True, slots=True)
class FaultSetBite:
    """How often a fault set mattered: missions run under it, and those that met a faulty action
    (all strategies together, and variant ``replan`` alone: its count is the share of routes
    whose initial plan the set touches)."""

    faults: str
    missions: int
    met: int
    replan_missions: int
    replan_met: int


def fault_set_bite(rows: Iterable[Row]) -> list[FaultSetBite]:
    """Per fault set, in order of first appearance: missions, and missions that met a fault."""
    missions: Counter[str] = Counter()
    met: Counter[str] = Counter()
    replan: Counter[str] = Counter()
    replan_met: Counter[str] = Counter()
    for r in rows:
        faults = str(r.get("faults") or "")
        missions[faults] += 1
        met[faults] += met_fault(r)
        if is_reference_replan(r):
            replan[faults] += 1
            replan_met[faults] += met_fault(r)
    return [FaultSetBite(f, missions[f], met[f], replan[f], replan_met[f]) for f in missions]
