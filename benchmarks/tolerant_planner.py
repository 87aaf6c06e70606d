"""Tolerant planner benchmark: the plain lattice A* against the tolerant one, masks included.

With each bundled four-wheel table (flat recursion) and the fault models k=1 (12 single faults)
and k=2 (78 single and double faults), on each bundled maze and route (48 queries a model), this
times in CPU seconds of this thread (``time.thread_time``), each the best of ``--repeats`` runs,
with both backends (``numba`` and the pure-Python reference):

* ``plain``: :func:`selfrepair.search.lattice.plan` with the default objective;
* ``first hard`` and ``first soft`` (penalty 1 per pair): the first tolerant plan on a map not
  seen before: the term made (:func:`~selfrepair.repair.tolerance_masks.tolerance_term`) and the
  search, with every per-map cache emptied before each run (masks, terms, the kernel's cell
  rows): the masks of the cells the search expands are read then, from the pattern book
  (:mod:`selfrepair.repair.tolerance_book`), which is already filled;
* ``later hard`` and ``later soft``: the same on a map already planned on;
* ``dense masks``: every pose's masks of a new map from the filled book (what the pure-Python
  search reads).

Two more figures bound what the book costs: ``book``, the masks of a process's first map with
every cache emptied (the pattern book filled by the replacement strategy's own search), and,
on 16 generated mazes never seen (25x25 and 49x49, corridors 1 and 2, 4 random routes each; the
book filled only by the bundled mazes), the first hard plan against the plain one: ``unseen
first`` as above (the best of the repeats, per-map caches emptied before each) and ``unseen
once``, the very first run, which also pays the strategy's search for the patterns new to the
book (a process pays it once per pattern).

Prints medians over the queries and the ratios against the plain planner of the same backend
(per query, then the median; the worst query too), MET or NOT MET against the target, and
writes them to ``benchmarks/results/tolerant_planner.json``.

Target (issue 26): the tolerant planner costs at most 2 times the plain planner's time, the
masks included: the median over the queries of ``first`` over ``plain``, for each mode, model
and backend, and of ``unseen first`` and ``unseen once`` over ``plain`` (the coldest case: the
target is met only when every one of these is).
Usage: ``python benchmarks/tolerant_planner.py [--repeats N]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from collections.abc import Callable
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.caching import CacheKind, clear_caches
from selfrepair.geometry import FreeGrid
from selfrepair.repair import tolerance_masks as masks_module
from selfrepair.repair.replacement import table_reach
from selfrepair.repair.tolerance import fault_model
from selfrepair.repair.tolerance_masks import tolerance_masks, tolerance_term
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search import _kernels
from selfrepair.search.lattice import plan, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.search.warmup import warm_up
from selfrepair.tables.fileformat import resolve_table
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.routes import random_routes

RESULTS = Path(__file__).resolve().parent / "results"
TABLES = ("handwritten", "generated-indexed", "generated-agnostic")
BACKENDS = ("numba", "python")
MODES = {"hard": None, "soft": Fraction(1)}
TARGET = 2.0


def _best(fn: Callable[[], Any], repeats: int, before: Callable[[], Any] | None = None) -> float:
    best = float("inf")
    for _ in range(repeats):
        if before is not None:
            before()
        t0 = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t0)
    return best


def _forget_maps() -> None:
    """Empty every per-map cache of the tolerant planner (masks, terms, the kernel's cell rows);
    keep the pattern books (and the planner's other caches, warm for the plain plan too)."""
    for cache in (masks_module._MASKS, masks_module._TERMS, _kernels._TERM_STATES):
        cache.clear()


class _Queries:
    """The timings of one table and fault model."""

    def __init__(self, table_name: str, k: int, repeats: int) -> None:
        self.table = resolve_table(table_name)
        self.model = fault_model(FOUR_WHEEL, k)
        self.actions = planning_actions(FOUR_WHEEL, frozenset())
        self.margin = max(2, table_reach(self.table))
        self.repeats = repeats
        self.few = max(1, repeats // 2)

    def term(self, grid: FreeGrid, penalty: Fraction | None) -> Any:
        return tolerance_term(self.table, grid, self.actions, self.model, penalty=penalty)

    def row(self, maze: Maze, grid: FreeGrid, start: Any, goal: Any) -> dict[str, Any]:
        """Plain, first and later tolerant plans of one query, both backends."""
        plain = PlanningProblem(maze, start, goal)
        row: dict[str, Any] = {}
        for backend in BACKENDS:
            n = self.repeats if backend == "numba" else self.few
            row[f"{backend} plain"] = _best(lambda b=backend: plan(plain, backend=b), n)
            for mode, penalty in MODES.items():

                def tolerant(p: Fraction | None = penalty, b: str = backend) -> Any:
                    problem = PlanningProblem(maze, start, goal, step_term=self.term(grid, p))
                    return plan(problem, backend=b)

                row[f"{backend} first {mode}"] = _best(tolerant, n, _forget_maps)
                row[f"{backend} later {mode}"] = _best(tolerant, n)
                if backend == "numba":
                    found = tolerant()
                    row[f"{mode} solved"] = found.status.value == "solved"
                    row[f"{mode} expansions"] = found.expansions
            if backend == "numba":
                row["plain expansions"] = plan(plain, backend=backend).expansions
        return row

    def bundled(self) -> list[dict[str, Any]]:
        grids = {n: load_bundled(n).free_grid(self.margin) for n in maze_names()}

        def every_mask(grid: FreeGrid) -> Any:
            return tolerance_masks(self.table, grid, self.actions, self.model)

        cold = set(CacheKind) - {CacheKind.PREFILLED, CacheKind.INPUT}
        book = {n: _best(lambda g=g: every_mask(g), self.few, lambda: clear_caches(cold))
                for n, g in grids.items()}  # fmt: skip
        for grid in grids.values():  # fill the book with every bundled map's patterns
            every_mask(grid)
        rows = []
        for name, grid in grids.items():
            maze = load_bundled(name)
            dense = _best(lambda g=grid: every_mask(g), self.repeats, _forget_maps)
            for route in bundled_routes(name):
                row = self.row(maze, grid, route.start, route.goal)
                row.update(route=f"{name} {route.name}", book=book[name], dense=dense)
                rows.append(row)
        return rows

    def unseen(self) -> list[dict[str, float]]:
        """First hard plans (numba) on generated mazes the book has not met, against plain."""
        rows = []
        for size in (25, 49):
            for corridor in (1, 2):
                maze = generate_maze(size, size, corridor=corridor, braid=0.3, seed=size + corridor)
                grid = maze.free_grid(self.margin)
                for route in random_routes(maze, 4, seed=7):
                    plain = PlanningProblem(maze, route.start, route.goal)
                    base = _best(lambda p=plain: plan(p, backend="numba"), self.repeats)


                    def tolerant(r: Any = route, g: FreeGrid = grid, m: Maze = maze) -> Any:
                        term = self.term(g, None)
                        return plan(PlanningProblem(m, r.start, r.goal, step_term=term),
                                    backend="numba")  # fmt: skip

                    once = _best(tolerant, 1, _forget_maps)  # the book's misses: paid once
                    first = _best(tolerant, self.repeats, _forget_maps)
                    rows.append({"plain": base, "first": first, "once": once})
        return rows


def _summary(rows: list[dict[str, Any]], key: str, over: str) -> dict[str, float]:
    ratios = [r[key] / r[over] for r in rows]
    out = {
        "median_us": round(statistics.median(r[key] for r in rows) * 1e6, 1),
        "median_over_plain": round(statistics.median(ratios), 2),
        "worst_over_plain": round(max(ratios), 2),
        "within_2x": sum(x <= TARGET for x in ratios),
    }
    mode = key.rsplit(" ", 1)[-1]
    if f"{mode} expansions" in rows[0]:  # the queries beyond 2x whose search did 2x the work
        out["beyond_2x_with_2x_expansions"] = sum(
            x > TARGET and r[f"{mode} expansions"] >= TARGET * r["plain expansions"]
            for x, r in zip(ratios, rows, strict=True)
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    warm_up()
    report: dict[str, Any] = {"machine": platform.machine(), "python": platform.python_version()}
    met = True
    for k in (1, 2):
        rows: list[dict[str, Any]] = []
        unseen: list[dict[str, float]] = []
        for table in TABLES:
            queries = _Queries(table, k, args.repeats)
            rows += queries.bundled()
            unseen += queries.unseen()
        out: dict[str, Any] = {"queries": len(rows)}
        print(f"k={k}, {len(rows)} queries (median us; over plain per query: median, worst; "
              f"queries within {TARGET:g}x):")  # fmt: skip
        for backend in BACKENDS:
            plain = f"{backend} plain"
            for key in [plain] + [f"{backend} {when} {m}" for when in ("first", "later")
                                  for m in MODES]:  # fmt: skip
                s = out[key] = _summary(rows, key, plain)
                verdict = ""
                if " first " in key:
                    ok = s["median_over_plain"] <= TARGET
                    met &= ok
                    verdict = "MET" if ok else "NOT MET"
                if "beyond_2x_with_2x_expansions" in s and s["within_2x"] < len(rows):
                    beyond = len(rows) - s["within_2x"]
                    verdict += (f" ({s['beyond_2x_with_2x_expansions']} of the {beyond} "
                                "beyond 2x expand 2x the states)")  # fmt: skip
                print(f"  {key:19} {s['median_us']:>9} us {s['median_over_plain']:>6}x "
                      f"{s['worst_over_plain']:>6}x {s['within_2x']:>3}/{len(rows)} "
                      f"{verdict}")  # fmt: skip
        for key in ("dense", "book"):
            s = out[key] = _summary(rows, key, "numba plain")
            print(f"  {key + ' masks':19} {s['median_us']:>9} us {s['median_over_plain']:>6}x")
        for key, what in (("first", "as above"), ("once", "its very first, book misses")):
            s = out[f"unseen {key} hard"] = _summary(unseen, key, "plain")
            ok = s["median_over_plain"] <= TARGET  # the coldest cases count for the target too
            met &= ok
            print(f"  {'unseen ' + key + ' hard':19} {s['median_us']:>9} us "
                  f"{s['median_over_plain']:>6}x {s['worst_over_plain']:>6}x "
                  f"{s['within_2x']:>3}/{len(unseen)} {'MET' if ok else 'NOT MET'} "
                  f"(numba, {what})")  # fmt: skip
        out["hard_solved"] = sum(r["hard solved"] for r in rows)
        report[f"k={k}"] = out
    print(f"target: first tolerant plan at most {TARGET:g}x the plain one (median): "
          f"{'MET' if met else 'NOT MET'}")  # fmt: skip
    report["target_met"] = met
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "tolerant_planner.json").write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
