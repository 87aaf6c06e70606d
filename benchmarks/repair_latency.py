"""Repair latency: a replacement-table hit versus a replan from scratch, measured in one run.

For every bundled maze (all its routes) and for a 512x512 MovingAI maze (a few long scenario
queries), missions are run with faults present from the start and detected at once, once with
strategy ``replacement`` (flat recursion, hand-written table) and once with ``replan``. The repair
latency is what the executor records: from meeting the faulty action to having the next executable
action (``time.perf_counter_ns``). Table hits are the replacement repairs that found a candidate;
replans are the ``replan`` strategy's repairs.

Prints, per maze, the median and 99th percentile of both, and their ratio; then the flatness of the
table-hit latency (512x512 median / smallest bundled maze median, target within 2x) and the growth
of replan time. Writes the figures to ``benchmarks/results/repair_latency.json``.

Targets (from the issue): a table hit at least 1000x faster than a replan at the median on the
bundled mazes; table-hit latency flat (within 2x) from the smallest maze to the 512x512 one.

Usage: ``python benchmarks/repair_latency.py [--quick] [--map PATH] [--queries N]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.metrics import latency_stats
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names
from selfrepair.world.maze import Maze
from selfrepair.world.movingai import load_map, load_scenario

ROOT = Path(__file__).resolve().parents[1]
MAP_CANDIDATES = (
    ROOT / "tests/data/movingai/maze512-4-0.map",
    ROOT.parent / "shared/data/movingai/maze512-4-0.map",
)


def fault_sets(quick: bool) -> list[frozenset[four_wheel.Fault]]:
    """Every single fault, and every third double fault (every sixth with ``--quick``)."""
    singles = [frozenset({f}) for f in four_wheel.SINGLE_FAULTS]
    doubles = list(four_wheel.DOUBLE_FAULTS[:: 6 if quick else 3])
    return singles + doubles


def collect(
    maze: Maze,
    routes: list[tuple[Pose, tuple[int, int]]],
    faults: list[frozenset[four_wheel.Fault]],
) -> dict[str, list[int]]:
    """Latencies of table hits and of replans over every route and fault set."""
    hits: list[int] = []
    replans: list[int] = []
    for start, goal in routes:
        for fault_set in faults:
            schedule = FaultSchedule.permanent(fault_set)
            table_run = run_mission(
                MissionSpec(maze, start, goal, schedule=schedule, strategy="replacement")
            )
            hits.extend(
                r.latency_ns
                for r in table_run.repairs
                if r.repair.source == "replacement" and r.repair.status == "repaired"
            )
            replan_run = run_mission(
                MissionSpec(maze, start, goal, schedule=schedule, strategy="replan")
            )
            replans.extend(r.latency_ns for r in replan_run.repairs if r.repair.replans)
    return {"hits": hits, "replans": replans}


def movingai_routes(path: Path, count: int) -> list[tuple[Pose, tuple[int, int]]]:
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


def summary(samples: dict[str, list[int]]) -> dict[str, float | int | None]:
    """Median, p99 and counts of both kinds, and the replan/hit ratios."""
    hit, rep = latency_stats(samples["hits"]), latency_stats(samples["replans"])
    ratio_median = rep.median_ns / hit.median_ns if hit.median_ns and rep.median_ns else None
    ratio_p99 = rep.p99_ns / hit.p99_ns if hit.p99_ns and rep.p99_ns else None
    return {
        "hits": hit.count,
        "hit_median_ns": hit.median_ns,
        "hit_p99_ns": hit.p99_ns,
        "replans": rep.count,
        "replan_median_ns": rep.median_ns,
        "replan_p99_ns": rep.p99_ns,
        "ratio_median": ratio_median,
        "ratio_p99": ratio_p99,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer fault sets and queries")
    parser.add_argument("--map", type=Path, default=None, help="a 512x512 MovingAI .map")
    parser.add_argument("--queries", type=int, default=None, help="scenario queries on the map")
    args = parser.parse_args()
    faults = fault_sets(args.quick)
    # Warm up: load the table, compile the planner's kernels.
    warm = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    run_mission(
        MissionSpec(warm, route.start, route.goal, schedule=FaultSchedule.permanent(faults[0]))
    )
    results: dict[str, dict[str, float | int | None]] = {}
    started = time.perf_counter()
    for name in maze_names():
        maze = load_bundled(name)
        routes = [(r.start, r.goal) for r in bundled_routes(name)]
        results[name] = {
            "cells": maze.width * maze.height,
            **summary(collect(maze, routes, faults)),
        }
    map_path = args.map or next((p for p in MAP_CANDIDATES if p.is_file()), None)
    if map_path is not None:
        count = args.queries or (2 if args.quick else 4)
        big = load_map(map_path)
        big_faults = faults[:6] if args.quick else faults[:12]
        results[map_path.stem] = {
            "cells": big.width * big.height,
            **summary(collect(big, movingai_routes(map_path, count), big_faults)),
        }
    elapsed = time.perf_counter() - started
    print(
        f"{'maze':<16}{'cells':>8}{'hits':>7}{'hit med':>10}{'hit p99':>10}{'replans':>8}"
        f"{'rep med':>12}{'rep p99':>12}{'x med':>8}{'x p99':>8}"
    )
    for name, row in results.items():

        def us(value: object) -> str:
            return "-" if value is None else f"{value / 1000:.1f}us"  # type: ignore[operator]

        def ratio(value: object) -> str:
            return "-" if value is None else f"{value:.0f}"

        print(
            f"{name:<16}{row['cells']:>8}{row['hits']:>7}{us(row['hit_median_ns']):>10}"
            f"{us(row['hit_p99_ns']):>10}{row['replans']:>8}{us(row['replan_median_ns']):>12}"
            f"{us(row['replan_p99_ns']):>12}{ratio(row['ratio_median']):>8}"
            f"{ratio(row['ratio_p99']):>8}"
        )
    names = list(results)
    first, last = results[names[0]], results[names[-1]]
    flat = (
        last["hit_median_ns"] / first["hit_median_ns"]  # type: ignore[operator]
        if first["hit_median_ns"] and last["hit_median_ns"]
        else None
    )
    growth = (
        last["replan_median_ns"] / first["replan_median_ns"]  # type: ignore[operator]
        if first["replan_median_ns"] and last["replan_median_ns"]
        else None
    )
    bundled_ratios = [results[n]["ratio_median"] for n in maze_names()]
    print(
        f"table-hit median, {names[-1]} / {names[0]}: {flat:.2f}x (target <= 2x)"
        if flat
        else "table-hit flatness: not measured"
    )
    print(f"replan median, {names[-1]} / {names[0]}: {growth:.1f}x" if growth else "")
    print(
        f"replan/hit median ratio on bundled mazes: "
        f"{', '.join(f'{r:.0f}x' if r else '-' for r in bundled_ratios)} (target >= 1000x)"
    )
    print(f"elapsed {elapsed:.1f}s")
    out = ROOT / "benchmarks/results/repair_latency.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "benchmark": "repair_latency",
                "quick": args.quick,
                "python": platform.python_version(),
                "machine": platform.machine(),
                "fault_sets": len(faults),
                "results": results,
                "hit_flatness": flat,
                "replan_growth": growth,
                "elapsed_s": elapsed,
            },
            indent=2,
            sort_keys=True,
        )
        + "\n"
    )
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
