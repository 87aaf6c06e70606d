"""Every strategy on one mission, side by side, with a one-line verdict.

:func:`compare_strategies` runs the same mission (maze, start, goal, fault schedule, planner
settings, seed) once per strategy. Timings are taken after a warm-up run of the same mission in the
same process (the results are deterministic, so the warm-up run only pays the one-off costs: kernel
loading, table loading, first allocations), so the latencies of the strategies compare fairly.
:func:`verdict` says in one line who repaired fastest, who reached the goal in the fewest ticks
and who kept closest to the initial plan. ``selfrepair compare`` prints both.

By default every registered strategy that can run here runs: :func:`runnable_strategies` leaves
out, with the reason, those that cannot (``lpg-adapt`` without the ``pddl`` extra or for another
robot than the four-wheel one), and the comparison lists them as skipped.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction

from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection
from selfrepair.execution.metrics import latency_stats, motion_distance, plan_distance
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.repair.strategies import (
    RepairSource,
    RepairStatus,
    StrategyName,
    strategy_entries,
    uses_table,
)
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "Comparison",
    "StrategyRun",
    "compare_strategies",
    "runnable_strategies",
    "strategy_label",
    "strategy_refusal",
    "verdict",
]


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

    @property
    def motion_distance(self) -> int:
        """Plan distance by motion: an action swapped for another of the same motion class at
        the same pose (the path kept, only the wheel speeds changed) is no change."""
        initial = self.result.initial_plan
        planned = list(zip(initial.poses, initial.actions, strict=False))
        executed = [(s.start, s.action) for s in self.result.executed]
        motion = self.result.spec.domain.motion_class
        return motion_distance(motion, planned, executed).total


def strategy_refusal(name: str, domain: SomeDomain) -> str | None:
    """Why strategy ``name`` cannot run for robot ``domain`` in this installation (one line), or
    ``None`` when it can. Only ``lpg-adapt`` has conditions: the ``pddl`` extra and the
    four-wheel robot (:func:`selfrepair.baselines.adapt.check_lpg_adapt`, which an experiment
    file's validation asks too)."""
    if name != StrategyName.LPG_ADAPT:
        return None
    from selfrepair.baselines.adapt import check_lpg_adapt

    try:
        check_lpg_adapt(domain.name)
    except ProblemError as exc:
        return str(exc)
    return None


def runnable_strategies(
    domain: SomeDomain, names: Sequence[str] | None = None, *, hidden: bool = False
) -> tuple[tuple[str, ...], tuple[tuple[str, str], ...]]:
    """The strategies of ``names`` (default: every registered one, in registry order, that is
    for faults the robot is not told when ``hidden``, else every other one) that can run for
    ``domain`` here, and the others as ``(name, reason)`` pairs, in the same order."""
    runnable: list[str] = []
    skipped: list[tuple[str, str]] = []
    if names is None:
        names = tuple(e.name for e in strategy_entries() if e.hidden == hidden)
    for name in names:
        reason = strategy_refusal(name, domain)
        if reason is None:
            runnable.append(name)
        else:
            skipped.append((name, reason))
    return tuple(runnable), tuple(skipped)


@dataclass(frozen=True, slots=True)
class Comparison:
    """The runs of one mission, in the order the strategies were given, and the strategies left
    out because they cannot run here (``(name, reason)``; see :func:`runnable_strategies`)."""

    runs: tuple[StrategyRun, ...]
    warmed_up: bool
    skipped: tuple[tuple[str, str], ...] = ()

    @property
    def verdict(self) -> str:
        return verdict(self.runs)


def compare_strategies(
    spec: MissionSpec, strategies: Sequence[str] | None = None, *, warm_up: bool = True
) -> Comparison:
    """Run ``spec`` once per strategy, each after a warm-up run of the same mission when
    ``warm_up`` is true; every other field of ``spec`` is shared.

    By default every registered strategy that can run for the spec's robot here runs, and the
    others are listed in :attr:`Comparison.skipped`; strategies named in ``strategies`` all run
    (one that cannot raises :class:`ProblemError` with the reason)."""
    skipped: tuple[tuple[str, str], ...] = ()
    if strategies is None:
        hidden = spec.schedule.detection is Detection.HIDDEN
        names, skipped = runnable_strategies(spec.domain, hidden=hidden)
    else:
        names = tuple(strategies)
        for name in names:
            reason = strategy_refusal(name, spec.domain)
            if reason is not None:
                raise ProblemError(reason)
    if not names:
        raise ProblemError("expected at least one strategy to compare")
    runs = []
    for name in names:
        one = replace(spec, strategy=name)
        if warm_up:
            run_mission(one)
        runs.append(StrategyRun(strategy_label(one), run_mission(one)))
    return Comparison(tuple(runs), warm_up, skipped)


def _us(ns: int) -> str:
    us = ns / 1000
    return f"{us:,.0f} µs" if us >= 100 else f"{us:.1f} µs"


def _names(runs: Sequence[StrategyRun]) -> str:
    return ", ".join(r.label for r in runs)


def _best(
    runs: Sequence[StrategyRun],
    key: Callable[[StrategyRun], Fraction | int],
    what: tuple[str, str],
    show: Callable[[StrategyRun], str],
) -> str:
    """``what[0]``: the runs with the least ``key``, then ``what[1]``: those with the most;
    equal values are one tie, every run with them named."""
    low = min(key(r) for r in runs)
    high = max(key(r) for r in runs)
    best = [r for r in runs if key(r) == low]
    if low == high:
        return f"{what[0]}: a tie at {show(best[0])} (every strategy)"
    worst = [r for r in runs if key(r) == high]

    def group(chosen: list[StrategyRun]) -> str:
        each = " each" if len(chosen) > 1 else ""
        return f"{_names(chosen)} ({show(chosen[0])}{each})"

    return f"{what[0]}: {group(best)}, {what[1]}: {group(worst)}"


def _latency(run: StrategyRun) -> int:
    return run.latency_median_ns or 0


def verdict(runs: Sequence[StrategyRun]) -> str:
    """One line: which strategies reached the goal; who repaired fastest (median latency) and by
    what factor over the slowest, both named; who took the fewest ticks, against who took the
    most; who stayed closest to the initial plan by the motion-level plan distance (an action
    swapped for another of the same motion, the path kept, is no change). Equal values are
    ties: every strategy with the best value is named."""
    reached = [r for r in runs if r.result.reached]
    if not reached:
        return "no strategy reached the goal."
    parts = []
    if len(reached) < len(runs):
        parts.append("only " + _names(reached) + " reached the goal")
    repaired = [r for r in reached if r.latency_median_ns is not None]
    if not repaired:
        parts.append("no faulty action was met: every strategy ran its initial plan")
    else:
        fast_ns = min(_latency(r) for r in repaired)
        slow_ns = max(_latency(r) for r in repaired)
        fastest = [r for r in repaired if _latency(r) == fast_ns]
        slowest = [r for r in repaired if _latency(r) == slow_ns]
        text = f"fastest repair: {_names(fastest)} (median {_us(fast_ns)}"
        if slow_ns > fast_ns > 0:
            ratio = slow_ns / fast_ns
            factor = f"{ratio:.1f}" if ratio < 10 else f"{ratio:,.0f}"
            text += (
                f", {factor}x faster than the slowest, {_names(slowest)}, median {_us(slow_ns)}"
            )
        parts.append(text + ")")
    parts.append(
        _best(reached, lambda r: r.ticks, ("fewest ticks", "most"), lambda r: str(r.ticks))
    )
    parts.append(
        _best(
            reached,
            lambda r: r.motion_distance,
            ("closest to the initial plan by motion", "farthest"),
            lambda r: f"distance {r.motion_distance}",
        )
    )
    return "; ".join(parts) + "."
