"""Repair latency and compute per mission: compiled table look-ups, whole-plan rewriting and
replanning, measured in one run.

Mazes: the four bundled ones (their routes), generated 64x64, 128x128 and 256x256 mazes (seeded
random long routes) and a 512x512 MovingAI maze (its longest scenario queries). On each, missions
run with the paper's 12 fault sets (permanent, present from the start, detected at once) for the
strategies of :data:`VARIANTS`, twice: the first pass right after emptying every cache (cold),
the second one warm. Four measurements come out of it:

1. **Hit latency at the strategy level** (the issue's "hit"): the table hits of the warm
   per-encounter missions are replayed against a repairer of the same mission
   (``ReplacementRepairer.repair`` on the recorded pose, action and faults), ``--calls`` calls
   per timing, median of ``--repeats`` timings per hit, best of ``--rounds`` passes over all
   hits, median over hits. *Warm*: the compiled look-up and the pattern are stored. *Cold*:
   every cache emptied before the single timed call (compiling the action's look-up and
   answering its pattern included). For scale, a bare ``dict.get`` with an integer key is timed
   the same way right after each hit (the physical limit of one look-up). The passes are there
   because the development VM runs the same code at two speeds (about 1.7x apart, each for
   seconds at a time): one pass can fall in the slow one, as the ``dict.get`` reference shows.
2. **Replan latency at the strategy level**: ``replan`` from the same poses (``--replans`` per
   maze, best of 3), and the ratio replan / warm hit (target >= 1000x from 64x64 up).
3. **Executor-recorded latencies** (what ``selfrepair experiment`` stores): table hits and
   replans as the executor times them, request building and queue splicing included.
4. **Repair compute per mission** (executor-recorded, warm pass, summed over a mission's repairs;
   the initial plan is left out as every strategy makes the same one), mean and median per
   strategy, and the ratio of each replacement variant to ``replan`` (target with rewriting: at
   most 1/10 on the bundled mazes).

It also prints the memory the compiled look-ups hold, per table and fault set (measured by
:func:`selfrepair.repair.lookups.lookup_memory`), against the documented bound, and the memory of
the occupancy codes per maze. Results go to ``benchmarks/results/repair_latency.json``.

Usage: ``python benchmarks/repair_latency.py [--quick] [--map PATH] [--queries N]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
import timeit
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from selfrepair.caching import clear_caches
from selfrepair.execution.context import mission_context
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.experiment.faultsets import PAPER_FAULT_SETS
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair import lookups
from selfrepair.repair.strategies import (
    MissionContext,
    RepairRequest,
    RepairSource,
    ReplacementRepairer,
    StrategyOptions,
    replan,
)
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.movingai import load_map, load_scenario
from selfrepair.world.routes import random_routes

ROOT = Path(__file__).resolve().parents[1]
MAP_CANDIDATES = (
    ROOT / "tests/data/movingai/maze512-4-0.map",
    ROOT.parent / "shared/data/movingai/maze512-4-0.map",
)
GENERATED = (64, 128, 256)

Route = tuple[Pose, Cell]


@dataclass(frozen=True, slots=True)
class Variant:
    """One strategy of the comparison."""

    label: str
    strategy: str
    table: str = "handwritten"
    recursion: str = "flat"
    rewrite: bool = False

    def options(self) -> StrategyOptions:
        return StrategyOptions(table=self.table, recursion=self.recursion, rewrite=self.rewrite)  # type: ignore[arg-type]


VARIANTS = (
    Variant("replan", "replan"),
    Variant("flat", "replacement"),
    Variant("flat+rewrite", "replacement", rewrite=True),
    Variant("guarded", "replacement", recursion="guarded"),
    Variant("guarded+rewrite", "replacement", recursion="guarded", rewrite=True),
    Variant("indexed+rewrite", "replacement", table="generated-indexed", rewrite=True),
)
"""``replan``; the hand-written table per encounter and rewriting, flat and guarded; and the
fault-indexed generated table rewriting (flat)."""

PER_ENCOUNTER = ("flat", "guarded")
"""The variants whose table hits are replayed for the strategy-level hit latency."""


# --- timing helpers ------------------------------------------------------------------------------


def per_call_ns(fn: Callable[[], object], calls: int, repeats: int) -> float:
    """Median over ``repeats`` timings of ``calls`` calls, per call, in ns."""
    return statistics.median(timeit.timeit(fn, number=calls) / calls * 1e9 for _ in range(repeats))


def median(values: Sequence[float]) -> float | None:
    return statistics.median(values) if values else None


def p99(values: Sequence[float]) -> float | None:
    if not values:
        return None
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))]


def mean(values: Sequence[float]) -> float | None:
    return sum(values) / len(values) if values else None


# --- missions ------------------------------------------------------------------------------------


@dataclass(slots=True)
class MazeRun:
    """Everything measured on one maze: per variant, the missions of the last warm pass, each
    mission's repair compute (median over the warm passes) and its compute in the cold pass."""

    name: str
    maze: Maze
    results: dict[str, list[MissionResult]] = field(default_factory=lambda: defaultdict(list))
    compute: dict[str, list[float]] = field(default_factory=lambda: defaultdict(list))
    cold_compute: dict[str, list[int]] = field(default_factory=lambda: defaultdict(list))


def specs(
    maze: Maze, routes: Sequence[Route], faults: Sequence[str], variant: Variant
) -> list[MissionSpec]:
    return [
        MissionSpec(
            maze,
            start,
            goal,
            schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults(text)),
            strategy=variant.strategy,
            options=variant.options(),
        )
        for start, goal in routes
        for text in faults
    ]


def run_maze(
    name: str, maze: Maze, routes: Sequence[Route], faults: Sequence[str], passes: int
) -> MazeRun:
    """Per variant: a cold pass (every cache emptied once before it), then ``passes`` warm ones."""
    run = MazeRun(name, maze)
    for variant in VARIANTS:
        missions = specs(maze, routes, faults, variant)
        clear_caches()
        run.cold_compute[variant.label] = [repair_ns(run_mission(s)) for s in missions]
        warm: list[list[int]] = [[] for _ in missions]
        for _ in range(passes):
            results = [run_mission(s) for s in missions]
            for k, result in enumerate(results):
                warm[k].append(repair_ns(result))
        run.results[variant.label] = results
        run.compute[variant.label] = [statistics.median(w) for w in warm]
    return run


def repair_ns(result: MissionResult) -> int:
    """A mission's repair compute: the executor-recorded latencies of its repairs, summed."""
    return sum(r.latency_ns for r in result.repairs)


def executor_hits(results: Sequence[MissionResult]) -> list[int]:
    return [
        r.latency_ns
        for result in results
        for r in result.repairs
        if r.repair.source is RepairSource.REPLACEMENT and r.repair.status == "repaired"
    ]


def executor_replans(results: Sequence[MissionResult]) -> list[int]:
    return [r.latency_ns for result in results for r in result.repairs if r.repair.replans]


# --- strategy-level timings ----------------------------------------------------------------------


def hit_situations(
    results: Sequence[MissionResult], limit: int
) -> list[tuple[MissionSpec, RepairRequest]]:
    """Distinct table hits (pose, action, faults), spread evenly, at most ``limit``."""
    seen: dict[tuple[Any, ...], tuple[MissionSpec, RepairRequest]] = {}
    for result in results:
        known = result.spec.schedule.all_faults()
        for r in result.repairs:
            if r.repair.source is RepairSource.REPLACEMENT and r.action is not None:
                key = (r.pose, r.action, known)
                seen.setdefault(
                    key, (result.spec, RepairRequest(r.pose, (r.action,), known, r.step))
                )
    items = list(seen.values())
    step = max(1, len(items) // limit)
    return items[::step][:limit]


def contexts() -> Callable[[MissionSpec], MissionContext]:
    cache: dict[tuple[int, str, str], MissionContext] = {}

    def get(spec: MissionSpec) -> MissionContext:
        key = (id(spec.maze), str(spec.options.table), spec.options.recursion)
        if key not in cache:
            cache[key] = mission_context(spec, spec.options.resolved_table())
        return cache[key]

    return get


def warm_hits(
    situations: Sequence[tuple[MissionSpec, RepairRequest]], calls: int, repeats: int, rounds: int
) -> tuple[list[float], list[float]]:
    """Per situation, the warm hit and, timed right after it, one ``dict.get`` with an integer
    key (the reference): each the median of ``repeats`` timings of ``calls`` calls, and the best
    of ``rounds`` passes over all situations (the same treatment for both, and as the replans
    get: this VM runs the same code at two speeds, for seconds at a time, so a single pass can
    fall in the slow one; the passes spread each situation's timings over the run)."""
    context_of = contexts()
    repairers = []
    for spec, request in situations:
        repairer = ReplacementRepairer(context_of(spec))
        repairer.repair(request)  # compile and store
        repairers.append((repairer, request))
    lookup = {0: 1, 5: 6}
    hits = [float("inf")] * len(repairers)
    dicts = [float("inf")] * len(repairers)
    for _ in range(rounds):
        for k, (repairer, request) in enumerate(repairers):
            hit = per_call_ns(lambda r=repairer, q=request: r.repair(q), calls, repeats)
            hits[k] = min(hits[k], hit)
            dicts[k] = min(dicts[k], per_call_ns(lambda: lookup.get(5), calls, repeats))
    return hits, dicts


def cold_hits(
    situations: Sequence[tuple[MissionSpec, RepairRequest]], everything: bool
) -> list[float]:
    """The first look-up of an action under a fault set: the compiled look-ups emptied (or, with
    ``everything``, every cache: table geometry, action index, occupancy codes too) before a
    repairer is made (the mission start, untimed) and its first repair timed."""
    context_of = contexts()
    out = []
    for spec, request in situations:
        context = context_of(spec)
        if everything:
            clear_caches()
        else:
            lookups._LOOKUPS.clear()
        repairer = ReplacementRepairer(context)
        t0 = time.perf_counter_ns()
        repairer.repair(request)
        out.append(float(time.perf_counter_ns() - t0))
    return out


def rewrites(results: Sequence[MissionResult]) -> list[tuple[MissionSpec, RepairRequest]]:
    """Each mission's first repair when it is a rewrite, with the queue it saw (the rest of the
    initial plan: before the first repair the robot follows the plan exactly)."""
    out = []
    for result in results:
        first = result.repairs[0] if result.repairs else None
        if first is None or first.repair.source is not RepairSource.REPLACEMENT:
            continue
        queue = result.initial_plan.actions[first.step :]
        known = result.spec.schedule.all_faults()
        out.append((result.spec, RepairRequest(first.pose, queue, known, first.step)))
    return out


def warm_rewrites(
    situations: Sequence[tuple[MissionSpec, RepairRequest]], repeats: int
) -> tuple[list[float], list[float]]:
    """Per rewrite: its time (median of ``repeats`` timings of 10 calls) and time per queued
    action."""
    context_of = contexts()
    times, per_action = [], []
    for spec, request in situations:
        repairer = ReplacementRepairer(context_of(spec))
        repairer.repair(request)
        t = per_call_ns(lambda r=repairer, q=request: r.repair(q), 10, repeats)
        times.append(t)
        per_action.append(t / len(request.queue))
    return times, per_action


def strategy_replans(
    situations: Sequence[tuple[MissionSpec, RepairRequest]], count: int
) -> list[float]:
    context_of = contexts()
    out = []
    step = max(1, len(situations) // count)
    for spec, request in list(situations)[::step][:count]:
        context = context_of(spec)
        times = timeit.repeat(lambda c=context, q=request: replan(c, q), number=1, repeat=3)
        out.append(min(times) * 1e9)
    return out


# --- memory --------------------------------------------------------------------------------------


def memory_snapshot(into: dict[tuple[str, str, str], dict[str, int]]) -> None:
    """Merge the compiled look-ups kept now into ``into`` (largest seen per key)."""
    for m in lookups.lookup_memory():
        key = (m.table.removeprefix("<bundled:").rstrip(">"), m.faults, str(m.mode))
        old = into.get(key, {"bytes": 0, "patterns": 0, "actions": 0})
        into[key] = {
            "bytes": max(old["bytes"], m.bytes),
            "patterns": max(old["patterns"], m.patterns),
            "actions": max(old["actions"], m.actions),
        }


def codes_bytes(maze: Maze, radius: int = 1) -> int:
    """The occupancy codes of the hand-written table (reach 1) on the mission grid (margin 2):
    the row lists and the distinct integers."""
    rows = lookups.occupancy_rows(maze.free_grid(2), radius)
    distinct = {id(c): c for row in rows for c in row}
    lists = sys.getsizeof(rows) + sum(map(sys.getsizeof, rows))
    return lists + sum(sys.getsizeof(c) for c in distinct.values())


# --- routes --------------------------------------------------------------------------------------


def movingai_routes(path: Path, count: int) -> list[Route]:
    """The ``count`` longest scenario queries, each with a start heading that has a plan."""
    maze = load_map(path)
    queries = sorted(load_scenario(Path(str(path) + ".scen")), key=lambda q: -q.optimal_length)
    chosen = []
    for query in queries[: count * 4 : 4]:
        for heading in Heading:
            start = Pose(query.start[0], query.start[1], heading)
            if plan(PlanningProblem(maze, start, query.goal)).status is PlanStatus.SOLVED:
                chosen.append((start, query.goal))
                break
    return chosen


def mazes(args: argparse.Namespace) -> list[tuple[str, Maze, list[Route]]]:
    out = []
    for name in maze_names():
        out.append((name, load_bundled(name), [(r.start, r.goal) for r in bundled_routes(name)]))
    for size in GENERATED[:1] if args.quick else GENERATED:
        maze = generate_maze(size, size, braid=0.2, seed=size, name=f"gen{size}")
        routes = [(r.start, r.goal) for r in random_routes(maze, 2 if args.quick else 4, size)]
        out.append((f"gen{size}x{size}", maze, routes))
    map_path = args.map or next((p for p in MAP_CANDIDATES if p.is_file()), None)
    if map_path is not None:
        count = args.queries or (2 if args.quick else 4)
        out.append((map_path.stem, load_map(map_path), movingai_routes(map_path, count)))
    return out


# --- report --------------------------------------------------------------------------------------


def us(value: float | None, digits: int = 2) -> str:
    return "-" if value is None else f"{value / 1000:.{digits}f}"


def ratio(a: float | None, b: float | None) -> float | None:
    return a / b if a is not None and b else None


def measure_maze(
    name: str,
    maze: Maze,
    routes: Sequence[Route],
    faults: Sequence[str],
    args: argparse.Namespace,
    memory: dict[tuple[str, str, str], dict[str, int]],
) -> dict[str, Any]:
    run = run_maze(name, maze, routes, faults, args.passes)
    memory_snapshot(memory)
    situations = [
        s for label in PER_ENCOUNTER for s in hit_situations(run.results[label], args.hits)
    ]
    warm, dict_gets = warm_hits(situations, args.calls, args.repeats, args.rounds)
    dict_get = median(dict_gets)
    memory_snapshot(memory)
    sample = situations[:: max(1, len(situations) // args.cold)]
    cold = cold_hits(sample, everything=False)
    first = cold_hits(sample[:5], everything=True)
    rewrite, per_action = warm_rewrites(rewrites(run.results["guarded+rewrite"]), args.repeats)
    replans = strategy_replans(situations, args.replans)
    compute = run.compute
    replan_mean = mean(compute["replan"])
    replan_median = median(compute["replan"])
    per_variant = {
        label: {
            "missions": len(values),
            "repairs_per_mission": mean([len(r.repairs) for r in run.results[label]]),
            "compute_mean_ns": mean(values),
            "compute_median_ns": median(values),
            "cold_compute_mean_ns": mean(run.cold_compute[label]),
            "ratio_mean_to_replan": ratio(mean(values), replan_mean),
            "ratio_median_to_replan": ratio(median(values), replan_median),
        }
        for label, values in compute.items()
    }
    hits = executor_hits([r for label in PER_ENCOUNTER for r in run.results[label]])
    exec_replans = executor_replans(run.results["replan"])
    return {
        "cells": maze.width * maze.height,
        "hit_situations": len(situations),
        "hit_warm_median_ns": median(warm),
        "hit_warm_p99_ns": p99(warm),
        "dict_get_ns": dict_get,
        "hit_cold_median_ns": median(cold),
        "hit_cold_max_ns": max(cold) if cold else None,
        "hit_first_in_process_median_ns": median(first),
        "rewrite_guarded_median_ns": median(rewrite),
        "rewrite_guarded_per_queued_action_ns": median(per_action),
        "replan_median_ns": median(replans),
        "replan_over_warm_hit": ratio(median(replans), median(warm)),
        "executor_hit_median_ns": median([float(h) for h in hits]),
        "executor_hit_p99_ns": p99([float(h) for h in hits]),
        "executor_replan_median_ns": median([float(h) for h in exec_replans]),
        "variants": per_variant,
        "codes_bytes": codes_bytes(maze),
    }


def print_latency(results: dict[str, dict[str, Any]]) -> None:
    dict_get_ns = next(iter(results.values()))["dict_get_ns"]
    print(
        f"\n{'maze':<14}{'cells':>8}{'hits':>6}{'warm med':>10}{'warm p99':>10}{'cold med':>10}"
        f"{'cold max':>10}{'1st in pr':>10}{'replan med':>12}{'x warm':>9}{'exec hit':>10}"
        f"{'exec replan':>12}{'rewrite':>9}{'/action':>9}{'hit/dict':>9}"
    )
    for name, row in results.items():
        x = row["replan_over_warm_hit"]
        print(
            f"{name:<14}{row['cells']:>8}{row['hit_situations']:>6}"
            f"{us(row['hit_warm_median_ns'], 3):>10}{us(row['hit_warm_p99_ns'], 3):>10}"
            f"{us(row['hit_cold_median_ns'], 0):>10}{us(row['hit_cold_max_ns'], 0):>10}"
            f"{us(row['hit_first_in_process_median_ns'], 0):>10}"
            f"{us(row['replan_median_ns'], 0):>12}{'-' if x is None else f'{x:,.0f}':>9}"
            f"{us(row['executor_hit_median_ns'], 1):>10}"
            f"{us(row['executor_replan_median_ns'], 0):>12}"
            f"{us(row['rewrite_guarded_median_ns'], 1):>9}"
            f"{us(row['rewrite_guarded_per_queued_action_ns'], 3):>9}"
            f"{row['hit_warm_median_ns'] / row['dict_get_ns']:>9.1f}"
        )
    print(
        "(µs. warm/cold/1st in pr: strategy-level hit with the look-up stored / look-up cache "
        "emptied / every cache emptied; replan: strategy level; exec: as the executor records "
        "them; rewrite: strategy-level guarded rewrite of the rest of the plan, and per queued "
        f"action. One dict.get with an integer key, timed like a warm hit: "
        f"{dict_get_ns / 1000:.3f} µs)"
    )


def print_compute(results: dict[str, dict[str, Any]]) -> None:
    print("\nrepair compute per mission (warm, µs): mean / median; ratio of means to replan")
    labels = [v.label for v in VARIANTS]
    print(f"{'maze':<14}" + "".join(f"{label:>22}" for label in labels))
    for name, row in results.items():
        cells = []
        for label in labels:
            v = row["variants"][label]
            r = v["ratio_mean_to_replan"]
            cells.append(
                f"{us(v['compute_mean_ns'], 0)}/{us(v['compute_median_ns'], 0)}"
                + ("" if label == "replan" or r is None else f" ({r:.3f})")
            )
        print(f"{name:<14}" + "".join(f"{c:>22}" for c in cells))
    repairs = [
        statistics.mean(row["variants"][label]["repairs_per_mission"] for row in results.values())
        for label in labels
    ]
    print(f"{'repairs/mission':<14}" + "".join(f"{r:>22.2f}" for r in repairs))


def bundled_verdicts(results: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Pooled over the bundled mazes: each variant's mean repair compute per mission / replan's."""
    bundled = [results[n] for n in maze_names() if n in results]
    out: dict[str, Any] = {}
    if not bundled:
        return out
    for v in VARIANTS[1:]:
        ours = statistics.mean(r["variants"][v.label]["compute_mean_ns"] for r in bundled)
        theirs = statistics.mean(r["variants"]["replan"]["compute_mean_ns"] for r in bundled)
        out[v.label] = ours / theirs
    return out


def print_memory(memory: dict[tuple[str, str, str], dict[str, int]]) -> dict[str, Any]:
    per_table: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for (table, faults, _mode), m in memory.items():
        key = f"{table} {faults}"
        per_table[key]["bytes"] += m["bytes"]
        per_table[key]["patterns"] += m["patterns"]
    sizes = sorted(v["bytes"] for v in per_table.values()) or [0]
    bound = lookups.MAX_FAULT_LOOKUPS * lookups.MAX_PATTERNS * 110
    print(
        f"\ncompiled look-ups: {len(memory)} (table, faults, mode) seen, {len(per_table)} (table, "
        f"faults); per (table, fault set), all modes: median {statistics.median(sizes) / 1024:.1f} "
        f"KiB, max {max(sizes) / 1024:.1f} KiB; limit {lookups.MAX_FAULT_LOOKUPS} kept x "
        f"{lookups.MAX_PATTERNS} patterns (about {bound / 2**20:.0f} MiB in all)"
    )
    for key, v in sorted(per_table.items(), key=lambda kv: -kv[1]["bytes"])[:6]:
        print(f"  {key:<40}{v['patterns']:>7} patterns {v['bytes'] / 1024:>8.1f} KiB")
    return {k: dict(v) for k, v in per_table.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer fault sets, mazes and hits")
    parser.add_argument("--map", type=Path, default=None, help="a 512x512 MovingAI .map")
    parser.add_argument("--queries", type=int, default=None, help="scenario queries on the map")
    parser.add_argument("--hits", type=int, default=60, help="hits replayed per maze and variant")
    parser.add_argument("--cold", type=int, default=30, help="cold hits per maze")
    parser.add_argument("--replans", type=int, default=10, help="replans timed per maze")
    parser.add_argument("--calls", type=int, default=500, help="calls per warm timing")
    parser.add_argument("--rounds", type=int, default=5, help="passes over the warm hits (best)")
    parser.add_argument("--repeats", type=int, default=7, help="timings per warm hit")
    parser.add_argument("--passes", type=int, default=3, help="warm passes over the missions")
    parser.add_argument("--mazes", default=None, help="comma-separated maze names to measure")
    args = parser.parse_args()
    faults = PAPER_FAULT_SETS[:6] if args.quick else PAPER_FAULT_SETS
    started = time.perf_counter()
    warm_maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    run_mission(MissionSpec(warm_maze, route.start, route.goal))  # load tables, planner kernels
    memory: dict[tuple[str, str, str], dict[str, int]] = {}
    results = {}
    chosen = None if args.mazes is None else set(args.mazes.split(","))
    for name, maze, routes in mazes(args):
        if chosen is not None and name not in chosen:
            continue
        results[name] = measure_maze(name, maze, routes, faults, args, memory)
        print(f"measured {name} ({time.perf_counter() - started:.0f} s)", flush=True)
    print_latency(results)
    print_compute(results)
    verdicts = bundled_verdicts(results)
    print(
        "\nbundled mazes, mean repair compute per mission / replan's: "
        + ", ".join(f"{k} {v:.3f}" for k, v in verdicts.items())
        + " (target with rewriting <= 0.1)"
    )
    warm_ok = all(r["hit_warm_median_ns"] <= 500 for r in results.values())
    big = [r["replan_over_warm_hit"] for n, r in results.items() if r["cells"] >= 64 * 64]
    print(
        f"warm hit median <= 0.5 µs on every maze: {'yes' if warm_ok else 'NO'}; replan / warm "
        f"hit from 64x64 up: {', '.join(f'{x:,.0f}x' for x in big)} (target >= 1000x)"
    )
    table_memory = print_memory(memory)
    for name, row in results.items():
        print(f"  occupancy codes {name}: {row['codes_bytes'] / 1024:.0f} KiB")
    elapsed = time.perf_counter() - started
    print(f"elapsed {elapsed:.0f} s")
    out = ROOT / "benchmarks/results/repair_latency.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "benchmark": "repair_latency",
        "quick": args.quick,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "fault_sets": list(faults),
        "results": results,
        "bundled_compute_ratio": verdicts,
        "lookup_memory": table_memory,
        "elapsed_s": elapsed,
    }
    out.write_text(json.dumps(payload, indent=2, sort_keys=True) + "\n")
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
