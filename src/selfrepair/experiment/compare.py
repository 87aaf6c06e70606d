"""Every strategy on one mission, side by side, with a one-line verdict.

:func:`compare_strategies` runs the same mission (maze, start, goal, fault schedule, planner
settings, seed) once per strategy. Timings are taken after a warm-up run of the same mission in the
same process (the results are deterministic, so the warm-up run only pays the one-off costs: kernel
loading, table loading, first allocations), so the latencies of the strategies compare fairly.
:func:`verdict` says in one line who repaired fastest, who reached the goal in the fewest ticks
and who kept closest to the initial plan. ``selfrepair compare`` prints both.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from fractions import Fraction

from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.metrics import latency_stats, plan_distance
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.repair.strategies import (
    RepairSource,
    RepairStatus,
    StrategyName,
    strategy_names,
    uses_table,
)

__all__ = ["Comparison", "StrategyRun", "compare_strategies", "strategy_label", "verdict"]


def strategy_label(spec: MissionSpec) -> str:
    """A short readable name of the spec's strategy and options, as the experiments write it
    (``replan``, ``replacement[handwritten,flat]``, ``lookahead[handwritten,flat,k=3]``)."""
    if not uses_table(spec.strategy):
        return str(spec.strategy)
    options = spec.options
    parts = [options.table_label, options.recursion.value]
    if spec.strategy == StrategyName.LOOKAHEAD:
        parts.append(f"k={options.window}")
    return f"{spec.strategy}[{','.join(parts)}]"


@dataclass(frozen=True, slots=True)
class StrategyRun:
    """One strategy's run of the mission and the figures the comparison shows."""

    label: str
    result: MissionResult

    @property
    def status(self) -> str:
        return self.result.status.value

    @property
    def ticks(self) -> Fraction:
        return self.result.ticks

    @property
    def repairs(self) -> int:
        """Faulty actions met (each needed a repair)."""
        return len(self.result.repairs)

    @property
    def replans(self) -> int:
        return sum(r.repair.replans for r in self.result.repairs)

    def resolved_by(self, source: RepairSource) -> int:
        """Repairs that ``source`` resolved."""
        return sum(
            1
            for r in self.result.repairs
            if r.repair.status is RepairStatus.REPAIRED and r.repair.source is source
        )

    @property
    def replacements(self) -> int:
        return self.resolved_by(RepairSource.REPLACEMENT)

    @property
    def lookaheads(self) -> int:
        return self.resolved_by(RepairSource.LOOKAHEAD)

    @property
    def latency_median_ns(self) -> int | None:
        """Median repair latency (``None`` without repairs)."""
        return latency_stats(r.latency_ns for r in self.result.repairs).median_ns

    @property
    def latency_p99_ns(self) -> int | None:
        return latency_stats(r.latency_ns for r in self.result.repairs).p99_ns

    @property
    def plan_distance(self) -> int:
        """Plan stability distance between the initial and the executed plan (Fox et al.)."""
        initial = self.result.initial_plan
        planned = list(zip(initial.poses, initial.actions, strict=False))
        executed = [(s.start, s.action) for s in self.result.executed]
        return plan_distance(planned, executed).total


@dataclass(frozen=True, slots=True)
class Comparison:
    """The runs of one mission, in the order the strategies were given."""

    runs: tuple[StrategyRun, ...]
    warmed_up: bool

    @property
    def verdict(self) -> str:
        return verdict(self.runs)


def compare_strategies(
    spec: MissionSpec, strategies: Sequence[str] | None = None, *, warm_up: bool = True
) -> Comparison:
    """Run ``spec`` once per strategy (default: every registered one), each after a warm-up
    run of the same mission when ``warm_up`` is true; every other field of ``spec`` is shared."""
    names = tuple(strategies) if strategies is not None else strategy_names()
    if not names:
        raise ProblemError("expected at least one strategy to compare")
    runs = []
    for name in names:
        one = replace(spec, strategy=name)
        if warm_up:
            run_mission(one)
        runs.append(StrategyRun(strategy_label(one), run_mission(one)))
    return Comparison(tuple(runs), warm_up)


def _us(ns: int) -> str:
    us = ns / 1000
    return f"{us:.0f} µs" if us >= 100 else f"{us:.1f} µs"


def verdict(runs: Sequence[StrategyRun]) -> str:
    """One line: which strategies reached the goal, who repaired fastest (and by what factor over
    the slowest), who took the fewest ticks and who stayed closest to the initial plan."""
    reached = [r for r in runs if r.result.reached]
    if not reached:
        return "no strategy reached the goal."
    parts = []
    if len(reached) < len(runs):
        parts.append("only " + ", ".join(r.label for r in reached) + " reached the goal")
    repaired = [r for r in reached if r.latency_median_ns is not None]
    if not repaired:
        parts.append("no faulty action was met: every strategy ran its initial plan")
    else:
        fastest = min(repaired, key=lambda r: r.latency_median_ns or 0)
        slowest = max(repaired, key=lambda r: r.latency_median_ns or 0)
        fast_ns, slow_ns = fastest.latency_median_ns or 0, slowest.latency_median_ns or 0
        text = f"fastest repair: {fastest.label} (median {_us(fast_ns)}"
        if slowest is not fastest and fast_ns > 0:
            text += f", {slow_ns / fast_ns:.0f}x faster than {slowest.label}"
        parts.append(text + ")")
    best = min(reached, key=lambda r: r.ticks)
    worst = max(reached, key=lambda r: r.ticks)
    text = f"fewest ticks: {best.label} ({best.ticks}"
    if worst.ticks > best.ticks:
        text += f", {worst.label} {worst.ticks}"
    parts.append(text + ")")
    stable = min(reached, key=lambda r: r.plan_distance)
    parts.append(f"closest to the initial plan: {stable.label} (distance {stable.plan_distance})")
    return "; ".join(parts) + "."
