"""Summaries of team mission rows, per strategy variant: what the CLI prints and the report shows.

Rows are dicts as the results store returns them (columns of
:func:`selfrepair.team.metrics.team_row` plus the experiment's labels). Pure functions, no
plotting.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from selfrepair.repair.strategies import MissionKind, StrategyName
from selfrepair.stats import lower_median, percentile

__all__ = ["TeamSummary", "by_fault_case", "summarize_team"]

Row = Mapping[str, object]


@dataclass(frozen=True, slots=True)
class TeamSummary:
    """One strategy variant over its missions (see :data:`HEADERS`)."""

    variant: str
    missions: int
    tasks: int
    delivered: int
    all_delivered: int
    makespan_ratio: float | None
    latency_median_us: float | None
    latency_p99_us: float | None
    cpu_median_us: float | None
    repairs: int
    disturbed_per_repair: float | None
    messages_per_mission: float
    repair_plans_per_repair: float | None

    HEADERS = (
        "strategy",
        "missions",
        "tasks delivered",
        "missions all delivered",
        "makespan / fault-free (median)",
        "repair latency median µs",
        "repair latency p99 µs",
        "repair CPU median µs",
        "repairs",
        "robots disturbed / repair",
        "messages / mission",
        "drive plannings / repair",
    )

    def cells(self) -> tuple[str, ...]:
        """The row as text, in :data:`HEADERS` order."""

        def num(value: float | None, digits: int = 2) -> str:
            return "-" if value is None else f"{value:,.{digits}f}"

        share = 100 * self.delivered / self.tasks if self.tasks else 100.0
        return (
            self.variant,
            str(self.missions),
            f"{share:.1f}%",
            f"{100 * self.all_delivered / max(1, self.missions):.1f}%",
            num(self.makespan_ratio),
            num(self.latency_median_us, 0),
            num(self.latency_p99_us, 0),
            num(self.cpu_median_us, 0),
            str(self.repairs),
            num(self.disturbed_per_repair),
            num(self.messages_per_mission, 1),
            num(self.repair_plans_per_repair),
        )


def _number(row: Row, key: str) -> float | None:
    value = row.get(key)
    return float(value) if isinstance(value, int | float) else None


def _latencies(rows: Sequence[Row], key: str = "repair_latencies_ns") -> list[int]:
    out: list[int] = []
    for row in rows:
        text = row.get(key)
        if isinstance(text, str) and text:
            out.extend(int(v) for v in json.loads(text))
    return out


def summarize_team(rows: Sequence[Row]) -> list[TeamSummary]:
    """One :class:`TeamSummary` per variant, in order of first appearance of the strategy
    (team replacement first, then re-allocation, then alone)."""
    groups: dict[str, list[Row]] = defaultdict(list)
    for row in rows:
        groups[str(row.get("variant"))].append(row)
    order: dict[str, int] = {
        name: i for i, name in enumerate(StrategyName.of_kind(MissionKind.TEAM))
    }
    out = []
    def rank(variant: str) -> tuple[int, str]:  # by the strategy column, never the label's text
        return order.get(str(groups[variant][0].get("strategy")), 9), variant

    for variant in sorted(groups, key=rank):
        group = groups[variant]
        ratios = [r for row in group if (r := _number(row, "makespan_ratio")) is not None]
        latencies = _latencies(group)
        repaired = sum(
            int(_number(row, "repairs") or 0) - int(_number(row, "deferrals") or 0) for row in group
        )
        disturbed = sum(int(_number(row, "disturbed_total") or 0) for row in group)
        plans = sum(int(_number(row, "repair_plans") or 0) for row in group)
        out.append(
            TeamSummary(
                variant,
                len(group),
                sum(int(_number(row, "tasks") or 0) for row in group),
                sum(int(_number(row, "delivered") or 0) for row in group),
                sum(int(_number(row, "all_delivered") or 0) for row in group),
                float(lower_median(ratios)) if ratios else None,
                lower_median(latencies) / 1000 if latencies else None,
                percentile(latencies, 0.99) / 1000 if latencies else None,
                lower_median(cpus) / 1000
                if (cpus := _latencies(group, "repair_cpus_ns"))
                else None,
                repaired,
                disturbed / repaired if repaired else None,
                sum(_number(row, "messages") or 0 for row in group) / len(group),
                plans / repaired if repaired else None,
            )
        )
    return out


def by_fault_case(rows: Sequence[Row]) -> tuple[list[str], list[str], dict[tuple[str, str], float]]:
    """Share of tasks delivered per (fault case, variant): the cases, the variants and the
    shares (0..1)."""
    totals: dict[tuple[str, str], list[int]] = defaultdict(lambda: [0, 0])
    for row in rows:
        key = (str(row.get("fault_case")), str(row.get("variant")))
        totals[key][0] += int(_number(row, "delivered") or 0)
        totals[key][1] += int(_number(row, "tasks") or 0)
    cases = sorted({k[0] for k in totals})
    variants = [s.variant for s in summarize_team(rows)]
    shares = {k: v[0] / v[1] if v[1] else 1.0 for k, v in totals.items()}
    return cases, variants, shares
