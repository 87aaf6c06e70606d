"""One flat row of metrics per team mission (the store's columns for team experiments).

:func:`team_row` reads a :class:`~selfrepair.team.result.TeamResult`; ``baseline`` is the
makespan of the same scenario without faults (the fault-free team plan, run by the same engine),
which the makespan is compared with. Columns (:data:`TEAM_COLUMNS`) are described in
docs/team.md.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from fractions import Fraction

import numpy as np

from selfrepair.execution.result import StepSource
from selfrepair.repair.strategies import RepairSource, StrategyName
from selfrepair.stats import percentile
from selfrepair.team.result import RepairOutcome, TeamResult, TeamSource

__all__ = ["TEAM_COLUMNS", "executed_own_replacements", "team_row"]

TEAM_COLUMNS = (
    "scenario",
    "team_size",
    "grippers",
    "tasks",
    "strategy",
    "team_table",
    "variant",
    "fault_kinds",
    "status",
    "reason",
    "delivered",
    "all_delivered",
    "delivered_share",
    "makespan",
    "baseline_makespan",
    "makespan_ratio",
    "incidents",
    "repairs",
    "team_replacements",
    "reallocations",
    "deferrals",
    "candidates",
    "repair_sources",
    "repair_latency_median_ns",
    "repair_latency_p99_ns",
    "repair_latency_max_ns",
    "repair_latencies_ns",
    "repair_cpu_median_ns",
    "repair_cpu_p99_ns",
    "repair_cpus_ns",
    "repair_plans",
    "repair_expansions",
    "disturbed_total",
    "disturbed_max",
    "disturbed_mean",
    "preemptions",
    "messages",
    "plans",
    "expansions",
    "yields",
    "own_repairs",
    "own_replacements",
    "detection",
    "failed_attempts",
    "discoveries",
    "discovery_delay_max_ticks",
    "discovery_delays_ticks",
    "moves",
    "acts",
    "allocation_ns",
    "ticks_simulated",
)
"""The row's columns, in order."""


def _percentile(values: Sequence[int], q: float) -> int | None:
    """The nearest-rank ``q`` quantile of :mod:`selfrepair.stats` (``None`` for no values): the
    same definition as the single-robot rows, so the 99th percentile of fewer than 100 repairs
    is the slowest one."""
    return percentile(values, q) if values else None


def team_row(
    result: TeamResult, baseline: Fraction | None = None
) -> dict[str, int | float | str | None]:
    """The metrics row of ``result`` (see the module docstring)."""
    scenario, options = result.scenario, result.options
    repairs = result.repairs
    latencies = [r.latency_ns for r in repairs if r.outcome is RepairOutcome.REPAIRED]
    cpus = [r.cpu_ns for r in repairs if r.outcome is RepairOutcome.REPAIRED]
    disturbed = [len(r.disturbed) for r in repairs if r.outcome is RepairOutcome.REPAIRED]
    makespan = result.makespan
    delays = [float(Fraction(d.delay, result.scale)) for d in result.discoveries]
    ratio = (
        float(makespan / baseline)
        if baseline is not None and baseline > 0 and result.all_delivered
        else None
    )
    return {
        "scenario": scenario.name,
        "team_size": len(scenario.robots),
        "grippers": sum(r.gripper for r in scenario.robots),
        "tasks": len(scenario.tasks),
        "strategy": str(options.strategy),
        "team_table": (
            str(options.table) if options.strategy == StrategyName.TEAM_REPLACEMENT else None
        ),
        "variant": options.label,
        "fault_kinds": ",".join(sorted({str(f.kind) for f in scenario.faults})),
        "status": str(result.status),
        "reason": result.reason,
        "delivered": len(result.delivered),
        "all_delivered": int(result.all_delivered),
        "delivered_share": len(result.delivered) / len(scenario.tasks) if scenario.tasks else 1.0,
        "makespan": float(makespan),
        "baseline_makespan": None if baseline is None else float(baseline),
        "makespan_ratio": ratio,
        "incidents": len(result.incidents),
        "repairs": len(repairs),
        "team_replacements": sum(r.source is TeamSource.TEAM_REPLACEMENT for r in repairs),
        "reallocations": sum(r.source is TeamSource.REALLOCATION for r in repairs),
        "deferrals": sum(r.outcome is RepairOutcome.DEFERRED for r in repairs),
        "candidates": json.dumps([r.candidate for r in repairs if r.candidate]),
        "repair_sources": json.dumps([str(r.source) for r in repairs]),
        "repair_latency_median_ns": _percentile(latencies, 0.5),
        "repair_latency_p99_ns": _percentile(latencies, 0.99),
        "repair_latency_max_ns": max(latencies, default=None),
        "repair_latencies_ns": json.dumps(latencies),
        "repair_cpu_median_ns": _percentile(cpus, 0.5),
        "repair_cpu_p99_ns": _percentile(cpus, 0.99),
        "repair_cpus_ns": json.dumps(cpus),
        "repair_plans": sum(r.plans for r in repairs),
        "repair_expansions": sum(r.expansions for r in repairs),
        "disturbed_total": sum(disturbed),
        "disturbed_max": max(disturbed, default=0),
        "disturbed_mean": float(np.mean(disturbed)) if disturbed else None,
        "preemptions": sum(r.preempted for r in repairs),
        "messages": result.messages,
        "plans": result.plans,
        "expansions": result.expansions,
        "yields": result.yields,
        "own_repairs": len(result.own_repairs),
        "own_replacements": executed_own_replacements(result),
        "detection": str(scenario.detection),
        "failed_attempts": sum(m.source is StepSource.FAILED_ATTEMPT for m in result.moves),
        "discoveries": len(result.discoveries),
        "discovery_delay_max_ticks": max(delays, default=None),
        "discovery_delays_ticks": json.dumps(delays),
        "moves": len(result.moves),
        "acts": len(result.acts),
        "allocation_ns": result.allocation_ns,
        "ticks_simulated": float(Fraction(result.end, result.scale)),
    }


def executed_own_replacements(result: TeamResult) -> int:
    """Own repairs by table replacement whose replacement ran: the robot executed at least one
    move marked ``replacement`` after the repair and before its next own repair. A repair whose
    drive was placed again by cooperative A* before any of its actions ran (the queue then holds
    that planner's actions) is not counted."""
    moves: dict[str, list[tuple[int, StepSource]]] = {}
    for m in result.moves:
        moves.setdefault(m.robot, []).append((m.start, m.source))
    following: list[int | None] = [None] * len(result.own_repairs)  # the robot's next repair
    last: dict[str, int] = {}
    for i, r in enumerate(result.own_repairs):
        if r.robot in last:
            following[last[r.robot]] = r.at
        last[r.robot] = i
    count = 0
    for r, until in zip(result.own_repairs, following, strict=True):
        if r.source is not RepairSource.REPLACEMENT:
            continue
        count += any(
            source is StepSource.REPLACEMENT and start >= r.at and (until is None or start < until)
            for start, source in moves.get(r.robot, ())
        )
    return count
