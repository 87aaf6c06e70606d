"""Planner benchmark: plain grid A* against networkx and nano-astar, and the robot lattice.

On each shared MovingAI maze map (corridor widths 1, 4 and 32), ``--queries`` scenario lines
spread evenly over the file are solved by

* ``selfrepair.search.grid.grid_astar`` (8-connected, MovingAI rules, numba backend),
* ``nano_astar.astar`` (C++; its defaults are MovingAI's rules), on the same queries,
* ``networkx.astar_path`` with the octile heuristic on a prebuilt graph, on every
  ``len/--networkx-queries``-th of those queries (it is slow; the ratio uses the same queries),
* ``selfrepair.search.lattice.plan`` for the healthy robot from the same start cell (facing east)
  to the same goal cell, with clearance weight 0 and with weight ``--weight``.

Each timing (ours and the peers' alike) is the best of ``--repeats`` runs of one query, in CPU
seconds of the calling thread (``time.thread_time``; every planner searches in that thread, and
CPU time is less disturbed than wall time by other load on the machine); the tables report the
median over the queries. Costs must agree (grid: |ours - peer| < 1e-6, and within 0.01 of the
listed optimum).

Targets (issue 12): the grid planner at most 1.0x nano-astar's time (median ratio per map), and
the lattice planner's expansions per second at least 0.75x the grid planner's (weight 0, per map
and overall). ``plan`` and ``grid_astar`` report kernel loading apart (``kernel_load_ns``); the
timings here are of loaded kernels.
Numba compile time is measured in a subprocess with an empty cache and reported separately; all
kernels are warmed up (loaded from the cache) before any timing, and per-map precomputation
(padded grid, neighbourhood masks) is also timed separately. Results go to
``benchmarks/results/planner.json``.

Run: ``.venv/bin/python benchmarks/planner.py`` (about two minutes).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

import nano_astar
import networkx as nx
import numpy as np

from selfrepair.geometry import Heading, Pose
from selfrepair.search.astar import PlanStatus
from selfrepair.search.backend import numba_available
from selfrepair.search.grid import grid_astar
from selfrepair.search.lattice import plan
from selfrepair.search.problem import SQRT2, PlanningProblem
from selfrepair.search.scenarios import sample_indices
from selfrepair.search.warmup import warm_up
from selfrepair.world.maze import Maze
from selfrepair.world.movingai import ScenarioQuery, load_map, load_scenario

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "movingai"
MAPS = ("maze512-1-0", "maze512-4-0", "maze512-32-9")
OUT = ROOT / "benchmarks" / "results" / "planner.json"


def best_of(repeats: int, fn: Callable[[], Any]) -> tuple[float, Any]:
    """Smallest CPU time (this thread) in seconds over ``repeats`` calls, and the last result."""
    best = math.inf
    result = None
    for _ in range(repeats):
        t0 = time.thread_time()
        result = fn()
        best = min(best, time.thread_time() - t0)
    return best, result


def compile_seconds() -> float:
    """Numba compile time of every kernel, in a fresh process with an empty cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        code = "from selfrepair.search.warmup import warm_up; print(warm_up())"
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
    return int(out.stdout.strip()) / 1e9


def octile_graph(maze: Maze) -> nx.Graph:
    """The 8-connected MovingAI graph (no corner cutting) of ``maze`` for networkx."""
    graph = nx.Graph()
    free = ~maze.walls
    h, w = free.shape
    for y in range(h):
        for x in range(w):
            if not free[y, x]:
                continue
            graph.add_node((x, y))
            if x + 1 < w and free[y, x + 1]:
                graph.add_edge((x, y), (x + 1, y), weight=1.0)
            if y + 1 < h and free[y + 1, x]:
                graph.add_edge((x, y), (x, y + 1), weight=1.0)
            for dx in (-1, 1):
                nx_, ny = x + dx, y + 1
                if 0 <= nx_ < w and ny < h and free[ny, nx_] and free[y, nx_] and free[ny, x]:
                    graph.add_edge((x, y), (nx_, ny), weight=SQRT2)
    return graph


def octile(a: tuple[int, int], b: tuple[int, int]) -> float:
    dx, dy = abs(a[0] - b[0]), abs(a[1] - b[1])
    return max(dx, dy) + (SQRT2 - 1.0) * min(dx, dy)


def run_map(name: str, args: argparse.Namespace) -> dict[str, Any]:
    """Time every planner on one map's sampled queries."""
    t0 = time.perf_counter()
    maze = load_map(DATA / f"{name}.map")
    queries: list[ScenarioQuery] = list(load_scenario(DATA / f"{name}.map.scen"))
    load_s = time.perf_counter() - t0
    picked = [queries[i] for i in sample_indices(len(queries), args.queries, args.seed)]
    t0 = time.perf_counter()
    grid_astar(maze, picked[0].start, picked[0].start)  # trivial query: fills the per-map caches
    plan(PlanningProblem(maze, Pose(*picked[0].start, Heading.E), picked[0].goal), max_expansions=1)
    precompute_s = time.perf_counter() - t0
    walls_u8 = np.ascontiguousarray(maze.walls, dtype=np.uint8)
    t0 = time.perf_counter()
    graph = octile_graph(maze) if args.networkx_queries else None
    graph_s = time.perf_counter() - t0
    nx_every = max(1, len(picked) // args.networkx_queries) if args.networkx_queries else 0
    rows = []
    for i, q in enumerate(picked):
        row = run_query(maze, q, walls_u8, graph if nx_every and i % nx_every == 0 else None, args)
        rows.append(row)
        print(
            f"  line {q.line:5d} opt {q.optimal_length:9.3f}  grid {row['grid_ms']:7.2f} ms"
            f"  nano {row['nano_ms']:7.2f} ms"
            + (f"  networkx {row['networkx_ms']:8.1f} ms" if "networkx_ms" in row else "")
            + f"  lattice w0 {row['lattice_w0_ms']:7.2f} ms  w{args.weight} "
            f"{row['lattice_w_ms']:7.2f} ms",
            flush=True,
        )
    return {
        "map": name,
        "load_s": load_s,
        "precompute_s": precompute_s,
        "networkx_graph_build_s": graph_s,
        "queries": rows,
        "summary": summarise(rows),
    }


def run_query(
    maze: Maze,
    q: ScenarioQuery,
    walls_u8: np.ndarray,
    graph: nx.Graph | None,
    args: argparse.Namespace,
) -> dict[str, Any]:
    """Time one query with every planner and check that the costs agree."""
    grid_s, ours = best_of(args.repeats, lambda: grid_astar(maze, q.start, q.goal))
    assert ours.status is PlanStatus.SOLVED
    cost = ours.cost.value
    assert abs(cost - q.optimal_length) <= 0.01, (q.line, cost, q.optimal_length)
    rc_start, rc_goal = (q.start[1], q.start[0]), (q.goal[1], q.goal[0])
    nano_s, nano = best_of(args.repeats, lambda: nano_astar.astar(walls_u8, rc_start, rc_goal))
    assert abs(nano[1] - cost) < 1e-6, (q.line, nano[1], cost)
    row: dict[str, Any] = {
        "line": q.line,
        "start": list(q.start),
        "goal": list(q.goal),
        "optimal_length": q.optimal_length,
        "grid_cost": cost,
        "grid_cost_exact": str(ours.cost),
        "grid_ms": grid_s * 1e3,
        "grid_expansions": ours.expansions,
        "nano_ms": nano_s * 1e3,
        "nano_cost": float(nano[1]),
    }
    if graph is not None:
        nx_s, path = best_of(
            args.repeats,
            lambda: nx.astar_path(graph, q.start, q.goal, heuristic=octile, weight="weight"),
        )
        row["networkx_ms"] = nx_s * 1e3
        row["networkx_cost"] = nx.path_weight(graph, path, weight="weight")
        assert abs(row["networkx_cost"] - cost) < 1e-6, (q.line, row["networkx_cost"], cost)
    start = Pose(q.start[0], q.start[1], Heading.E)
    for key, weight in (("w0", Fraction(0)), ("w", Fraction(args.weight))):
        problem = PlanningProblem(maze, start, q.goal, clearance_weight=weight)
        seconds, result = best_of(args.repeats, lambda problem=problem: plan(problem))
        assert result.status is PlanStatus.SOLVED
        row[f"lattice_{key}_ms"] = seconds * 1e3
        row[f"lattice_{key}_expansions"] = result.expansions
        row[f"lattice_{key}_cost"] = str(result.cost)
        row[f"lattice_{key}_duration"] = str(result.duration)
    return row


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Medians, ratios and expansion rates over ``rows``."""
    med = {k: statistics.median(r[k] for r in rows) for k in ("grid_ms", "nano_ms")}
    for key in ("lattice_w0", "lattice_w"):
        med[f"{key}_ms"] = statistics.median(r[f"{key}_ms"] for r in rows)
    nx_rows = [r for r in rows if "networkx_ms" in r]
    out: dict[str, Any] = {"median_ms": med, "queries": len(rows)}
    out["grid_vs_nano"] = statistics.median(r["grid_ms"] / r["nano_ms"] for r in rows)
    if nx_rows:
        out["networkx_queries"] = len(nx_rows)
        out["networkx_median_ms"] = statistics.median(r["networkx_ms"] for r in nx_rows)
        out["networkx_vs_grid"] = statistics.median(
            r["networkx_ms"] / r["grid_ms"] for r in nx_rows
        )
    out["grid_expansions_per_s"] = rate(rows, "grid")
    for key in ("lattice_w0", "lattice_w"):
        out[f"{key}_expansions_per_s"] = rate(rows, key)
        out[f"{key}_rate_vs_grid"] = out[f"{key}_expansions_per_s"] / out["grid_expansions_per_s"]
    return out


def rate(rows: list[dict[str, Any]], key: str) -> float:
    """Total expansions over total time."""
    return sum(r[f"{key}_expansions"] for r in rows) / (sum(r[f"{key}_ms"] for r in rows) / 1e3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--queries", type=int, default=20)
    parser.add_argument("--networkx-queries", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--weight", type=str, default="1")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    if not numba_available():
        sys.exit("numba is not installed: the benchmark measures the compiled backend")
    compile_s = compile_seconds()
    cache_load_s = warm_up() / 1e9
    print(f"numba compile (empty cache) {compile_s:.2f} s, load from cache {cache_load_s:.2f} s")
    maps = []
    for name in MAPS:
        print(name, flush=True)
        maps.append(run_map(name, args))
    all_rows = [r for m in maps for r in m["queries"]]
    overall = summarise(all_rows)
    report = {
        "benchmark": "planner",
        "when": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": {
            "python": platform.python_version(),
            "cpu_count": os.cpu_count(),
            "platform": platform.platform(),
        },
        "versions": {
            "numba": _version("numba"),
            "networkx": nx.__version__,
            "nano_astar": _version("nano-astar"),
            "numpy": np.__version__,
        },
        "settings": vars(args) | {"out": str(args.out)},
        "numba_compile_s": compile_s,
        "numba_cache_load_s": cache_load_s,
        "maps": maps,
        "overall": overall,
        "targets": {"grid_vs_nano_at_most": 1.0, "lattice_rate_vs_grid_at_least": 0.75},
        "met": {
            "grid_vs_nano": {m["map"]: m["summary"]["grid_vs_nano"] <= 1.0 for m in maps},
            "lattice_rate_vs_grid": {
                m["map"]: m["summary"]["lattice_w0_rate_vs_grid"] >= 0.75 for m in maps
            }
            | {"overall": overall["lattice_w0_rate_vs_grid"] >= 0.75},
        },
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    print_summary(maps, overall, args.weight)
    print(f"wrote {args.out}")


def print_summary(maps: list[dict[str, Any]], overall: dict[str, Any], weight: str) -> None:
    print()
    head = (
        f"{'map':14} {'grid ms':>8} {'nano ms':>8} {'grid/nano':>9} {'nx/grid':>8}"
        f" {'lat w0 ms':>9} {'lat w' + weight + ' ms':>9} {'grid Mexp/s':>11}"
        f" {'lat w0 rate':>11} {'lat w' + weight + ' rate':>11}"
    )
    print(head)
    for name, s in [(m["map"], m["summary"]) for m in maps] + [("overall", overall)]:
        med = s["median_ms"]
        print(
            f"{name:14} {med['grid_ms']:8.2f} {med['nano_ms']:8.2f} {s['grid_vs_nano']:9.2f}"
            f" {s.get('networkx_vs_grid', float('nan')):8.1f} {med['lattice_w0_ms']:9.2f}"
            f" {med['lattice_w_ms']:9.2f} {s['grid_expansions_per_s'] / 1e6:11.2f}"
            f" {s['lattice_w0_rate_vs_grid']:11.2f} {s['lattice_w_rate_vs_grid']:11.2f}"
        )
    print("targets: grid/nano <= 1.0 per map; lattice w0 rate / grid rate >= 0.75")
    for name, s in [(m["map"], m["summary"]) for m in maps] + [("overall", overall)]:
        grid_ok = "met" if s["grid_vs_nano"] <= 1.0 else "NOT met"
        lattice_ok = "met" if s["lattice_w0_rate_vs_grid"] >= 0.75 else "NOT met"
        print(
            f"  {name:14} grid/nano {s['grid_vs_nano']:.2f} ({grid_ok}), "
            f"lattice/grid rate {s['lattice_w0_rate_vs_grid']:.2f} ({lattice_ok})"
        )


def _version(dist: str) -> str:
    from importlib.metadata import version

    return version(dist)


if __name__ == "__main__":
    main()
