"""Mission metrics: plan stability and latency statistics.

Plan stability follows Fox, Gerevini, Long and Serina (2006), "Plan stability: replanning versus
plan repair" (ICAPS): the distance between plans ``a`` and ``b`` is the number of actions of ``a``
that are not in ``b`` plus the number of actions of ``b`` that are not in ``a``, with plans taken as
multisets of ground actions. Here a ground action is the pair (start pose, wheel code): the action
together with its parameters, so a plan that drives the same wheels along another route counts as
different. Lower is more stable; 0 means the same multiset of actions.

Plan distance *by motion* (:func:`motion_distance`) takes a ground action as (start pose, motion
class) instead: swapping an action for another of the same motion class (``FFFF`` for the slower
``SFFS``, both "forward one cell") is no change, because the robot does the same thing.

Mission-level figures (docs/experiments.md): ``completed_without_replan`` (the goal reached and no
full replan, table fallbacks included), ``repair_compute_ns`` (the time of every repair added up;
the initial plan, identical for every strategy of a situation, left out) and, when the caller
gives the fault-free optimum at clearance weight 0 (:func:`optimum_ticks`, one reference for
every strategy variant of a route), ``ticks_over_optimum``.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Callable, Hashable, Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import NamedTuple

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.result import (
    MissionResult,
    MissionSpec,
    RepairRecord,
    StepSource,
    TraceStep,
)
from selfrepair.repair.strategies import RepairSource, RepairStatus
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.astar import PlanStatus
from selfrepair.search.backend import backend_ran
from selfrepair.search.lattice import action_cost, plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.stats import lower_median, percentile

__all__ = [
    "ROW_COLUMNS",
    "LatencyStats",
    "PlanDistance",
    "executed_cost",
    "histogram_text",
    "latency_stats",
    "mission_row",
    "motion_distance",
    "optimum_ticks",
    "plan_distance",
]


@dataclass(frozen=True, slots=True)
class PlanDistance:
    """``removed``: actions of the first plan missing from the second; ``added``: the reverse."""

    removed: int
    added: int

    @property
    def total(self) -> int:
        """The plan distance of Fox et al. (2006): ``removed + added``."""
        return self.removed + self.added


def plan_distance(first: Iterable[Hashable], second: Iterable[Hashable]) -> PlanDistance:
    """Multiset difference counts between two plans of ground actions."""
    a, b = Counter(first), Counter(second)
    return PlanDistance(sum((a - b).values()), sum((b - a).values()))


def motion_distance(
    domain_motion: Callable[[object], str],
    first: Iterable[tuple[Hashable, object]],
    second: Iterable[tuple[Hashable, object]],
) -> PlanDistance:
    """:func:`plan_distance` with each ground action ``(start, action)`` taken as
    ``(start, motion class)``: an action swapped for another of the same motion is no change."""
    return plan_distance(
        ((start, domain_motion(a)) for start, a in first),
        ((start, domain_motion(a)) for start, a in second),
    )


_OPTIMUM: BoundedCache[tuple[Hashable, ...], Fraction | None] = BoundedCache(
    "fault-free optimum ticks", 1024, kind=CacheKind.REFERENCE, per_map=True
)


def optimum_ticks(spec: MissionSpec) -> Fraction | None:
    """The duration of the fault-free optimal plan at clearance weight 0 from ``spec``'s start to
    its goal: the common reference of "time to goal" for every strategy variant and weight of a
    route (``None`` when no plan exists). Planned once per (maze, route, robot) and process."""
    key = (spec.maze, spec.start, spec.goal, spec.goal_heading, spec.domain, spec.heuristic)
    return _OPTIMUM.get(key, lambda: _optimum(spec))


def _optimum(spec: MissionSpec) -> Fraction | None:
    problem = PlanningProblem(
        spec.maze,
        spec.start,
        spec.goal,
        spec.goal_heading,
        frozenset(),
        Fraction(0),
        spec.clearance_radius,
        spec.domain,
    )
    result = plan(problem, heuristic=spec.heuristic, backend=spec.backend)
    return result.duration if result.status is PlanStatus.SOLVED else None


@dataclass(frozen=True, slots=True)
class LatencyStats:
    """Summary of nanosecond latencies; every field is ``None`` when there were none."""

    count: int
    median_ns: int | None
    p99_ns: int | None
    max_ns: int | None
    total_ns: int


def latency_stats(latencies_ns: Iterable[int]) -> LatencyStats:
    """Count, lower median, 99th percentile, maximum and total (the percentile and median of
    :mod:`selfrepair.stats`)."""
    ordered = sorted(latencies_ns)
    if not ordered:
        return LatencyStats(0, None, None, None, 0)
    return LatencyStats(
        len(ordered),
        lower_median(ordered),
        percentile(ordered, 0.99),
        ordered[-1],
        sum(ordered),
    )


def histogram_text(values: Iterable[int]) -> str:
    """A compact, sortable histogram such as ``"1:3,5:1"`` (value:count, by value)."""
    return _histogram(Counter(values))


def _histogram(counts: Counter[int]) -> str:
    return ",".join(f"{value}:{counts[value]}" for value in sorted(counts))


Row = dict[str, int | float | str | None]


def executed_cost(result: MissionResult) -> Fraction:
    """The executed plan's cost under the mission's cost model (duration plus clearance term)."""
    spec = result.spec
    return sum(
        (
            action_cost(
                spec.maze,
                s.start,
                s.action,
                clearance_weight=Fraction(spec.clearance_weight),
                clearance_radius=spec.clearance_radius,
                domain=spec.domain,
            )
            for s in result.executed
        ),
        Fraction(0),
    )


def _cost_and_distance(
    result: MissionResult, executed: tuple[TraceStep, ...]
) -> tuple[Fraction, PlanDistance, PlanDistance]:
    """The executed cost, the plan distance and the plan distance by motion: from the executor's
    tally when the result has one, else recomputed from the steps (:func:`executed_cost`,
    :func:`plan_distance`, :func:`motion_distance`)."""
    tally = result.tally
    if tally is None:
        executed = executed or result.executed
        planned = list(zip(result.initial_plan.poses, result.initial_plan.actions, strict=False))
        done = [(s.start, s.action) for s in executed]
        distance = plan_distance(planned, done)
        by_motion = motion_distance(result.spec.domain.motion_class, planned, done)
        return executed_cost(result), distance, by_motion
    cost = Fraction(tally.executed_units, tally.unit)
    if tally.penalty:
        cost += Fraction(result.spec.clearance_weight) * tally.penalty
    return (
        cost,
        PlanDistance(tally.plan_removed, tally.plan_added),
        PlanDistance(tally.motion_removed, tally.motion_added),
    )


class _RepairTotals(NamedTuple):
    """What the row needs from the repairs, gathered in one pass."""

    latencies: list[int]
    replacements: int
    lookaheads: int
    detours: int
    replans: int
    replans_failed: int
    lengths: Counter[int]
    depths: Counter[int]


def _repair_totals(repairs: Sequence[RepairRecord]) -> _RepairTotals:
    latencies: list[int] = []
    replacements = lookaheads = detours = replans = failed = 0
    lengths: Counter[int] = Counter()
    depths: Counter[int] = Counter()
    for record in repairs:
        repair = record.repair
        latencies.append(record.latency_ns)
        replans += repair.replans
        if repair.status is RepairStatus.REPAIRED:
            if repair.source is RepairSource.REPLACEMENT:
                replacements += 1
                lengths[repair.candidate_length or 0] += 1
                depths[repair.depth or 0] += 1
            elif repair.source is RepairSource.LOOKAHEAD:
                lookaheads += 1
            elif repair.source is RepairSource.DETOUR:
                detours += 1 + repair.rewritten  # a rewriting repair takes several
        elif repair.source is RepairSource.REPLAN:
            failed += 1
    return _RepairTotals(
        latencies, replacements, lookaheads, detours, replans, failed, lengths, depths
    )


def _schedule_texts(schedule: FaultSchedule, domain: SomeDomain) -> tuple[str, str]:
    """The row's ``faults`` and ``fault_schedule`` texts (made once per schedule and domain)."""
    return _SCHEDULE_TEXTS.get(
        (schedule, domain),
        lambda: (
            domain.format_faults(schedule.all_faults()),
            json.dumps(schedule.to_json(domain), sort_keys=True),
        ),
    )


_SCHEDULE_TEXTS: BoundedCache[tuple[FaultSchedule, SomeDomain], tuple[str, str]] = (
    BoundedCache("fault schedule texts", 256, kind=CacheKind.RECORD)
)


def mission_row(result: MissionResult, *, optimum: Fraction | None = None) -> Row:
    """Flatten a mission result into one row; the columns are :data:`ROW_COLUMNS`, documented in
    docs/replacement.md. Exact values are strings (``"31/3"``) with ``_float`` twins; times are
    integer nanoseconds. Computed in one pass over the repairs, and from the executor's tally
    (:class:`~selfrepair.execution.result.MissionTally`) instead of the steps when the result has
    one. ``optimum`` is the reference duration of ``ticks_over_optimum`` (:func:`optimum_ticks`);
    without it that column is ``None``."""
    spec = result.spec
    options = spec.options
    initial = result.initial_plan
    tally = result.tally
    executed = result.executed if tally is None else ()
    n_executed = len(executed) if tally is None else tally.actions_executed
    repairs = result.repairs
    totals = _repair_totals(repairs)
    stats = latency_stats(totals.latencies)
    cost_after, distance, by_motion = _cost_and_distance(result, executed)
    compute_ns = result.initial_planning_ns + stats.total_ns
    faults, schedule = _schedule_texts(spec.schedule, spec.domain)
    replans = totals.replans
    row: Row = {
        "maze": spec.maze.name,
        "maze_width": spec.maze.width,
        "maze_height": spec.maze.height,
        "start": str(spec.start),
        "goal": f"{spec.goal[0]},{spec.goal[1]}",
        "goal_heading": None if spec.goal_heading is None else spec.goal_heading.name,
        "domain": spec.domain.name,
        "strategy": str(spec.strategy),
        "table": options.table_label,
        "recursion": options.recursion.value,
        "max_depth": options.max_depth,
        "window": options.window,
        "faults": faults,
        "fault_schedule": schedule,
        "detection": spec.schedule.detection.value,
        "seed": spec.seed,
        "clearance_weight": str(spec.clearance_weight),
        "clearance_radius": spec.clearance_radius,
        "heuristic": spec.heuristic,
        "backend": spec.backend,
        "backend_ran": backend_ran(spec.backend, spec.domain),
        "footing": result.footing,
        "status": result.status.value,
        "reached": int(result.reached),
        "reason": result.reason,
        "ticks": str(result.ticks),
        "ticks_float": float(result.ticks),
        "steps": len(result.steps),
        "actions_executed": n_executed,
        "failed_attempts": len(result.steps) - n_executed,
        "plan_length_before": len(initial.actions),
        "plan_cost_before": None if initial.cost is None else str(initial.cost),
        "plan_cost_before_float": None if initial.cost is None else float(initial.cost),
        "initial_expansions": initial.expansions,
        "plan_length_after": n_executed,
        "plan_cost_after": str(cost_after),
        "plan_cost_after_float": float(cost_after),
        "faulty_encounters": len(result.repairs),
        "replacements": totals.replacements,
        "lookaheads": totals.lookaheads,
        "replans": totals.replans,
        "replans_failed": totals.replans_failed,
        "replacement_lengths": _histogram(totals.lengths),
        "replacement_depths": _histogram(totals.depths),
        "initial_planning_ns": result.initial_planning_ns,
        "repair_count": stats.count,
        "repair_latency_median_ns": stats.median_ns,
        "repair_latency_p99_ns": stats.p99_ns,
        "repair_latency_max_ns": stats.max_ns,
        "repair_latency_total_ns": stats.total_ns,
        "repair_latencies_ns": json.dumps(totals.latencies),
        "compute_ns": compute_ns,
        "compute_per_action_ns": compute_ns / n_executed if n_executed else None,
        "plan_distance": distance.total,
        "plan_distance_removed": distance.removed,
        "plan_distance_added": distance.added,
        "final_pose": str(result.final_pose),
        "completed_without_replan": int(result.reached and replans == 0),
        "repair_compute_ns": stats.total_ns,
        "plan_distance_motion": by_motion.total,
        "optimum_ticks": None if optimum is None else float(optimum),
        "ticks_over_optimum": (
            float(result.ticks - optimum) if optimum is not None and result.reached else None
        ),
        "plan_repairs": sum(
            1
            for r in repairs
            if r.repair.status is RepairStatus.REPAIRED
            and r.repair.source is RepairSource.PLAN_REPAIR
        ),
        "repair_expansions": sum(r.repair.expansions for r in repairs),
        "fallbacks": sum(1 for r in repairs if len(r.repair.attempts) > 1),
        "repair_attempts": json.dumps(
            dict(sorted(Counter(a for r in repairs for a in r.repair.attempts).items()))
        ),
        "waits": tally.waits if tally is not None else _count(result, StepSource.WAIT),
        "world_events": len(spec.world.events),
        "detours": totals.detours,
        "bumps": tally.bumps if tally is not None else _count(result, StepSource.BUMPED),
        **_diagnosis_columns(result),
    }
    return row


ROW_COLUMNS: tuple[str, ...] = (
    "maze",
    "maze_width",
    "maze_height",
    "start",
    "goal",
    "goal_heading",
    "domain",
    "strategy",
    "table",
    "recursion",
    "max_depth",
    "window",
    "faults",
    "fault_schedule",
    "detection",
    "seed",
    "clearance_weight",
    "clearance_radius",
    "heuristic",
    "backend",
    "backend_ran",
    "footing",
    "status",
    "reached",
    "reason",
    "ticks",
    "ticks_float",
    "steps",
    "actions_executed",
    "failed_attempts",
    "plan_length_before",
    "plan_cost_before",
    "plan_cost_before_float",
    "initial_expansions",
    "plan_length_after",
    "plan_cost_after",
    "plan_cost_after_float",
    "faulty_encounters",
    "replacements",
    "lookaheads",
    "replans",
    "replans_failed",
    "replacement_lengths",
    "replacement_depths",
    "initial_planning_ns",
    "repair_count",
    "repair_latency_median_ns",
    "repair_latency_p99_ns",
    "repair_latency_max_ns",
    "repair_latency_total_ns",
    "repair_latencies_ns",
    "compute_ns",
    "compute_per_action_ns",
    "plan_distance",
    "plan_distance_removed",
    "plan_distance_added",
    "final_pose",
    "completed_without_replan",
    "repair_compute_ns",
    "plan_distance_motion",
    "optimum_ticks",
    "ticks_over_optimum",
    "plan_repairs",
    "repair_expansions",
    "fallbacks",
    "repair_attempts",
    "waits",
    "world_events",
    "detours",
    "bumps",
    "behaviour",
    "observation_noise",
    "observers",
    "surprise_step",
    "isolation_actions",
    "isolated_right",
    "probes",
    "classes_left",
)
"""The row's columns, in order. Stable: the experiments' SQLite schema is built from it."""


def _count(result: MissionResult, source: StepSource) -> int:
    """The steps of ``source`` in a result without a tally."""
    return sum(1 for s in result.steps if s.source is source)


def _diagnosis_columns(result: MissionResult) -> Row:
    """The diagnosis columns (faults hidden, docs/diagnosis.md): the behaviour model,
    odometry noise and observing teammates of the mission, and what a diagnosing strategy
    recorded (``None`` for any other): the step of the first surprise, commands after it until
    one class was isolated, whether that class holds the true fault set (1/0), probes run,
    classes still possible."""
    spec = result.spec
    hidden = spec.schedule.detection is Detection.HIDDEN
    row: Row = {
        "behaviour": (spec.behaviour or spec.domain.behaviour().name)
        if hidden and spec.domain.behaviours
        else None,
        "observation_noise": spec.observation.noise if hidden else None,
        "observers": len(spec.observers) if hidden else None,
    }
    report = result.diagnosis or {}
    isolated = report.get("isolated", ())
    row["surprise_step"] = report.get("surprise_step")
    row["isolation_actions"] = report.get("isolation_actions")
    row["isolated_right"] = (
        int(spec.schedule.all_faults() in isolated) if isolated else None
    )
    row["probes"] = report.get("probes")
    row["classes_left"] = report.get("classes_left")
    return row
