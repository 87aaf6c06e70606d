"""Replacement table size and scope against what it buys: the original work's open question.

"Balance out the replacement table size and scope against the cost to find a suitable
replacement in it" (issue 26, item 5). This sweeps generated four-wheel tables
(:func:`selfrepair.tables.generate.generate_table`) over the maximum sub-plan length ``L`` (2 to
6) and the candidates per action ``K``: the fault-agnostic shape (``K`` candidates per action,
whatever the faults) for ``K`` in 1, 2, 3, 5, 8; the fault-indexed shape (up to ``K`` per fault
set and disabled action, every single and double fault in scope) for ``K`` 1 and 8 only, since
there ``K`` changes nothing: the generator keeps at most one candidate per entry whatever ``K``
allows (every other candidate's extra cells cover the kept one's, so in flat mode it would never
be the first that fits). Per table, in one run:

* **size**: candidates stored, file size (``dump_table``) and the memory the compiled look-ups
  hold after the run (:func:`selfrepair.repair.lookups.lookup_memory`);
* **coverage next to walls** (:func:`selfrepair.repair.coverage.wall_coverage`): the share of
  (pose, fault set, disabled action) triples on the four bundled mazes (every free cell and
  heading, every single and double fault) whose action is replaceable in free space where some
  usable candidate fits;
* **plan tolerance** of the optimal plans of the 16 bundled routes (flat recursion): the share of
  (step, fault set) pairs covered for the 12 single faults and for all 78 single and double
  faults (exact, from the tolerance masks, :mod:`selfrepair.repair.tolerance_masks`);
* **missions without a replan**: the 192 missions of the 16 routes under the 12 single faults,
  each appearing permanently at a step drawn per (route, fault) from the plan (seed 2026), run by
  the executor with the ``replacement`` strategy (flat, per encounter). The script stops if the
  count differs from the one the masks predict (they agree by the property test of
  ``tests/test_tolerance.py``);
* **cost to find a replacement**: the reference search
  (:func:`~selfrepair.repair.replacement.find_replacement`, uncompiled) and a compiled hit
  (:meth:`~selfrepair.repair.lookups.FaultLookups.get`, pattern stored), mean CPU microseconds
  over the same 400 poses next to walls (a faulty action under a single fault), best of
  ``--repeats`` passes.

The **knee**: over every table, the one on the Pareto front of (log file size, plan tolerance
for single and double faults) farthest above the chord from the front's smallest to its largest
table, both axes scaled to [0, 1] (Kneedle). Also printed: per shape, the smallest table that
reaches its shape's best single-fault and double-fault tolerance. Writes
``benchmarks/results/table_sweep.json`` and the figure (``--figure``, by default
``benchmarks/results/table_sweep.png``; ``docs/figures/table-sweep.png`` is made with
``--figure docs/figures/table-sweep.png``).

Usage: ``python benchmarks/table_sweep.py [--quick] [--repeats N]`` (about 5 minutes on 2
shared cores; ``--quick``: K in 1, 3, 8 and L in 2, 4, 6).
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import random
import time
from pathlib import Path
from typing import Any

from selfrepair.caching import CacheKind, clear_caches
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.figstyle import OKABE_ITO, figure, save
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.coverage import wall_coverage
from selfrepair.repair.lookups import fault_lookups, lookup_memory
from selfrepair.repair.replacement import Replacement, find_replacement, table_reach
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import FaultModel, fault_model
from selfrepair.repair.tolerance_masks import tolerance_masks
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.lattice import plan, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.search.warmup import warm_up
from selfrepair.tables.fileformat import dump_table
from selfrepair.tables.generate import generate_table
from selfrepair.tables.model import GenerateOptions, ReplacementTable
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names
from selfrepair.world.maze import Maze

RESULTS = Path(__file__).resolve().parent / "results"
SHAPES = ("fault-agnostic", "fault-indexed")
SEED = 2026
SAMPLE = 400


def _routes() -> list[tuple[Maze, Any, Any]]:
    """Every bundled route with its optimal plan (no fault known)."""
    out = []
    for name in maze_names():
        maze = load_bundled(name)
        for route in bundled_routes(name):
            found = plan(PlanningProblem(maze, route.start, route.goal))
            out.append((maze, route, found))
    return out


def _uncovered(table: ReplacementTable, maze: Maze, found: Any, model: FaultModel) -> list[int]:
    """Per fault set of ``model``, the last step of the plan that needs a replan under it (-1:
    none): ``(i, F)`` is uncovered exactly when ``i`` is at most that step (flat recursion)."""
    grid = maze.free_grid(max(2, table_reach(table)))
    masks = tolerance_masks(table, grid, planning_actions(FOUR_WHEEL, frozenset()), model)
    actions = masks.actions
    last = [-1] * len(model.fault_sets)
    for j, (pose, action) in enumerate(zip(found.poses, found.actions, strict=False)):
        k = actions.index(action)
        for f in masks.fault_sets_at(pose, k):
            last[model.fault_sets.index(f)] = j
    return last


def _tolerance(table: ReplacementTable, routes: list[Any], model: FaultModel) -> float:
    pairs = uncovered = 0
    for maze, _, found in routes:
        last = _uncovered(table, maze, found, model)
        pairs += len(found.actions) * len(last)
        uncovered += sum(j + 1 for j in last)
    return 1 - uncovered / pairs


def _missions(table: ReplacementTable, routes: list[Any]) -> tuple[int, int, int]:
    """Missions without a replan (the executor), how many the masks predict, and how many."""
    model = fault_model(FOUR_WHEEL, 1)
    rng = random.Random(SEED)
    run = predicted = total = 0
    for maze, route, found in routes:
        last = _uncovered(table, maze, found, model)
        for b, faults in enumerate(model.fault_sets):
            step = rng.randrange(len(found.actions))
            spec = MissionSpec(
                maze, route.start, route.goal,
                options=StrategyOptions(table=table),
                schedule=FaultSchedule.permanent(faults, at=step),
            )  # fmt: skip
            result = run_mission(spec)
            run += result.reached and all(r.repair.replans == 0 for r in result.repairs)
            predicted += step > last[b]
            total += 1
    return run, predicted, total


def _sample() -> list[tuple[Maze, Pose, Any, frozenset[Any]]]:
    """Poses next to walls with a faulty action that fits there (fixed seed)."""
    rng = random.Random(SEED)
    singles = fault_model(FOUR_WHEEL, 1).fault_sets
    actions = planning_actions(FOUR_WHEEL, frozenset())
    out: list[Any] = []
    mazes = [load_bundled(n) for n in maze_names()]
    while len(out) < SAMPLE:
        maze = rng.choice(mazes)
        cells = maze.free_cells()
        x, y = rng.choice(cells)
        pose = Pose(x, y, rng.choice(list(Heading)))
        action = rng.choice(actions)
        faults = rng.choice(singles)
        near = any(not maze.is_free(x + dx, y + dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1))
        _, swept, _ = FOUR_WHEEL.step(pose, action)
        if near and not FOUR_WHEEL.available(action, faults) and maze.all_free(swept):
            out.append((maze, pose, action, faults))
    return out


def _found(found: Replacement) -> Replacement:
    return found


def _latency(table: ReplacementTable, sample: list[Any], repeats: int) -> tuple[float, float]:
    """Mean microseconds per reference search and per compiled hit over ``sample`` (CPU time,
    best of ``repeats`` passes)."""
    grids = {id(m): m.free_grid(max(2, table_reach(table))) for m, *_ in sample}
    compiled = {f: fault_lookups(table, f, answer=_found) for *_, f in sample}
    jobs = [(grids[id(m)], p, a, f, compiled[f]) for m, p, a, f in sample]
    for grid, pose, action, _, lookups in jobs:  # store every pattern first
        lookups.get(action, pose, grid)
    best_search = best_hit = float("inf")
    for _ in range(repeats):
        t0 = time.thread_time()
        for grid, pose, action, faults, _ in jobs:
            find_replacement(table, action, pose, faults, grid.all_free)
        best_search = min(best_search, time.thread_time() - t0)
        t0 = time.thread_time()
        for _ in range(10):
            for grid, pose, action, _, lookups in jobs:
                lookups.get(action, pose, grid)
        best_hit = min(best_hit, (time.thread_time() - t0) / 10)
    return best_search / len(jobs) * 1e6, best_hit / len(jobs) * 1e6


def _knee(points: list[dict[str, Any]]) -> dict[str, Any]:
    """Kneedle on the Pareto front of (log file bytes, plan tolerance for single and double
    faults) over every table, both axes scaled to [0, 1]: the front's table farthest above the
    chord from its smallest to its largest table."""
    front: list[dict[str, Any]] = []
    for p in sorted(points, key=lambda p: (p["file_bytes"], -p["tolerance_k2"])):
        if not front or p["tolerance_k2"] > front[-1]["tolerance_k2"]:
            front.append(p)
    x0, x1 = math.log(front[0]["file_bytes"]), math.log(front[-1]["file_bytes"])
    y0, y1 = front[0]["tolerance_k2"], front[-1]["tolerance_k2"]
    if len(front) < 3 or x1 == x0 or y1 == y0:
        return front[-1]

    def gain(p: dict[str, Any]) -> float:
        x = (math.log(p["file_bytes"]) - x0) / (x1 - x0)
        return (p["tolerance_k2"] - y0) / (y1 - y0) - x

    return max(front, key=gain)


def _smallest(rows: list[dict[str, Any]], shape: str, key: str) -> dict[str, Any]:
    """The table of ``shape`` with the fewest bytes among those with the best ``key``."""
    sub = [r for r in rows if r["shape"] == shape]
    best = max(r[key] for r in sub)
    return min((r for r in sub if r[key] == best), key=lambda r: r["file_bytes"])


def _name(row: dict[str, Any]) -> str:
    return (
        f"{row['shape']} L={row['max_length']} K={row['per_action']} "
        f"({row['file_bytes'] / 1e3:.1f} kB, {row['candidates']} candidates)"
    )


def _figure(rows: list[dict[str, Any]], knee: dict[str, Any], path: Path) -> Path:
    with figure(16, 4.2, 4) as (fig, axes):
        return _draw(fig, axes, rows, knee, path)


def _draw(
    fig: Any, axes: Any, rows: list[dict[str, Any]], knee: dict[str, Any], path: Path
) -> Path:
    panels = (
        ("wall_coverage", "coverage next to walls"),
        ("tolerance_k2", "plan tolerance, single and double faults"),
        ("missions_no_replan", "missions without a replan (of 192)"),
        ("search_us", "reference search per repair (µs)"),
    )
    for ax, (key, title) in zip(axes, panels, strict=True):
        for s, shape in enumerate(SHAPES):
            for li, length in enumerate(sorted({r["max_length"] for r in rows})):
                sub = sorted(
                    (r for r in rows if r["shape"] == shape and r["max_length"] == length),
                    key=lambda r: r["file_bytes"],
                )
                ax.plot(
                    [r["file_bytes"] / 1e3 for r in sub], [r[key] for r in sub],
                    marker="os"[s], linestyle="-" if s == 0 else "--",
                    color=OKABE_ITO[li % len(OKABE_ITO)], alpha=0.85,
                    label=f"{shape}, L={length}",
                )  # fmt: skip
        ax.plot([knee["file_bytes"] / 1e3], [knee[key]], marker="*", markersize=16,
                color="#000000", linestyle="none", label="knee")  # fmt: skip
        ax.set_xscale("log")
        ax.set_xlabel("table file size, kB (log)")
        ax.set_title(title)
    axes[0].legend(fontsize=7, ncol=2)
    return save(fig, path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="K in {1, 3, 8}, L in {2, 4, 6}")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--figure", type=Path, default=RESULTS / "table_sweep.png",
                        help="where the figure goes (PNG)")  # fmt: skip
    args = parser.parse_args()
    per_action = (1, 3, 8) if args.quick else (1, 2, 3, 5, 8)
    lengths = (2, 4, 6) if args.quick else (2, 3, 4, 5, 6)
    warm_up()
    routes = _routes()
    sample = _sample()
    mazes = [(n, load_bundled(n)) for n in maze_names()]
    doubles = fault_model(FOUR_WHEEL, 2)
    rows = []
    for shape in SHAPES:
        for length in lengths:
            for k in per_action if shape == "fault-agnostic" else (per_action[0], per_action[-1]):
                clear_caches({CacheKind.REPAIR})  # this table's compiled look-ups only
                t0 = time.perf_counter()
                options = GenerateOptions(shape=shape, max_length=length, per_action=k)
                table = generate_table(FOUR_WHEEL, options)
                made = time.perf_counter() - t0
                walls = [wall_coverage(table, m, doubles.fault_sets, n) for n, m in mazes]
                pairs = sum(w.pairs for w in walls)
                search_us, hit_us = _latency(table, sample, args.repeats)
                run, predicted, total = _missions(table, routes)
                if run != predicted:
                    raise SystemExit(
                        f"{shape} L={length} K={k}: missions {run} != masks {predicted}"
                    )
                row = {
                    "shape": shape, "max_length": length, "per_action": k,
                    "candidates": sum(len(e.candidates) for e in table.entries),
                    "file_bytes": len(dump_table(table)),
                    "lookup_bytes": sum(m.bytes for m in lookup_memory()),
                    "wall_coverage": 1 - sum(w.uncovered for w in walls) / pairs,
                    "tolerance_k1": _tolerance(table, routes, fault_model(FOUR_WHEEL, 1)),
                    "tolerance_k2": _tolerance(table, routes, doubles),
                    "missions_no_replan": run, "missions": total,
                    "search_us": search_us, "hit_us": hit_us, "generate_s": made,
                }  # fmt: skip
                rows.append(row)
                print(
                    f"{shape:14} L={length} K={k}: {row['candidates']:5} candidates, "
                    f"{row['file_bytes'] / 1e3:7.1f} kB file, walls {row['wall_coverage']:.3f}, "
                    f"tolerance k=1 {row['tolerance_k1']:.3f} k=2 {row['tolerance_k2']:.3f}, "
                    f"missions {run}/{total}, search {search_us:6.1f} us, hit {hit_us:.2f} us, "
                    f"generated in {made:.1f} s",
                    flush=True,
                )
    knee = _knee(rows)
    print(f"knee (log file bytes against plan tolerance k=2, every table): {_name(knee)}: "
          f"tolerance k=1 {knee['tolerance_k1']:.3f}, k=2 {knee['tolerance_k2']:.3f}, "
          f"missions {knee['missions_no_replan']}/{knee['missions']}")  # fmt: skip
    smallest = {}
    for shape in SHAPES:
        for key in ("tolerance_k1", "tolerance_k2"):
            found = smallest[f"{shape} {key}"] = _smallest(rows, shape, key)
            print(f"smallest {shape} table with its best {key} ({found[key]:.3f}): {_name(found)}")
    RESULTS.mkdir(exist_ok=True)
    report = {"machine": platform.machine(), "python": platform.python_version(),
              "rows": rows, "knee": knee, "smallest": smallest}  # fmt: skip
    (RESULTS / "table_sweep.json").write_text(json.dumps(report, indent=2) + "\n")
    print(f"wrote {_figure(rows, knee, args.figure)}")


if __name__ == "__main__":
    main()
