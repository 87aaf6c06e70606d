"""Tolerant planner benchmark: the plain lattice A* against the tolerant one, masks included.

On each bundled maze and route, with each bundled four-wheel table (flat recursion) and the
fault models k=1 (12 single faults) and k=2 (78 single and double faults), this times, in CPU
seconds of this thread (``time.thread_time``), each as the best of ``--repeats`` runs:

* ``plain``: :func:`selfrepair.search.lattice.plan` with the default objective;
* ``hard`` and ``soft`` (penalty 1 per pair): the same search with the tolerance term, the
  masks already made and the term already in the kernel's layout (a later plan on that map);
* ``first``: the first hard plan on a map whose masks are not made yet: the masks of that map
  (the pattern book already filled), the term's kernel layout and the search;
* ``masks before``: the masks as the previous method made them (commit 09337be: per fault set,
  action and heading, every cell's pattern through the compiled look-ups), every cache emptied;
* ``masks cold``: the new method (:mod:`selfrepair.repair.tolerance_book`) with every cache
  emptied, pattern book included: what the first map of a process pays (the book is then
  shared by every map);
* ``masks warm``: the new method on a map met for the first time, the pattern book filled.

Prints the medians over the routes and the ratios against the plain planner, side by side, and
writes them to ``benchmarks/results/tolerant_planner.json``.

Target (issue 26): the tolerant planner costs at most 2 times the plain planner's time, the
masks included (``first`` over ``plain``). Usage:
``python benchmarks/tolerant_planner.py [--repeats N]``.
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

import numpy as np

from selfrepair.caching import CacheKind, clear_caches
from selfrepair.geometry import FreeGrid, Heading, Pose
from selfrepair.repair import tolerance_masks as masks_module
from selfrepair.repair.lookups import MISSING, action_index, fault_lookups, occupancy_rows
from selfrepair.repair.replacement import RecursionMode, Replacement, table_reach
from selfrepair.repair.tolerance import FaultModel, fault_model
from selfrepair.repair.tolerance_book import free_cells
from selfrepair.repair.tolerance_masks import tolerance_term
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.lattice import plan, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.search.warmup import warm_up
from selfrepair.tables.fileformat import resolve_table
from selfrepair.tables.model import ReplacementTable
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names

RESULTS = Path(__file__).resolve().parent / "results"
TABLES = ("handwritten", "generated-indexed", "generated-agnostic")
KEYS = ("plain", "hard", "soft", "first", "masks_before", "masks_cold", "masks_warm")


def _best(fn: Callable[[], Any], repeats: int, before: Callable[[], Any] | None = None) -> float:
    best = float("inf")
    for _ in range(repeats):
        if before is not None:
            before()
        t0 = time.thread_time()
        fn()
        best = min(best, time.thread_time() - t0)
    return best


def _valid(found: Replacement) -> bool:
    return True


def _masks_before(
    table: ReplacementTable, grid: FreeGrid, actions: tuple[Any, ...], model: FaultModel
) -> np.ndarray[Any, Any]:
    """The previous method (commit 09337be), kept here only to time it beside the new one: per
    fault set, faulty action and heading, every free cell's neighbourhood pattern packed by
    numpy, each distinct one answered through the compiled look-ups (flat recursion)."""
    domain = table.domain
    index = action_index(domain)
    words = (len(model.fault_sets) + 63) >> 6
    masks = np.zeros((grid.height, grid.width, 4, len(actions), words), dtype=np.uint64)
    free = free_cells(grid)
    ys, xs = np.nonzero(free)
    distinct: dict[Any, Any] = {}
    for b, faults in enumerate(model.fault_sets):
        word, bit = b >> 6, np.uint64(1 << (b & 63))
        lookups = fault_lookups(table, faults, mode=RecursionMode.FLAT, answer=_valid)
        for k, action in enumerate(actions):
            if domain.available(action, faults):
                continue
            lookup = lookups.action(index.of(action))
            radius = lookup.radius
            padded = np.pad(free, radius)
            rows = occupancy_rows(grid, radius)
            for heading in Heading:
                cells = lookup.cells[heading]
                if (radius, cells) not in distinct:
                    packed = np.zeros(len(ys), dtype=np.int64)
                    for j, (dx, dy) in enumerate(sorted(cells)):
                        packed |= padded[ys + radius + dy, xs + radius + dx].astype(np.int64) << j
                    _, first, inverse = np.unique(packed, return_index=True, return_inverse=True)
                    distinct[radius, cells] = (first, inverse.ravel())
                first, inverse = distinct[radius, cells]
                valid = np.zeros(len(first), dtype=bool)
                for u, at in enumerate(first.tolist()):
                    x, y = int(xs[at]), int(ys[at])
                    key = rows[y][x] & lookup.masks[heading]
                    found = lookup.answers[heading].get(key, MISSING)
                    if found is MISSING:
                        found = lookups.fill(lookup, Pose(x, y, heading), key, grid)
                    valid[u] = found is not None
                bad = ~valid[inverse]
                masks[ys[bad], xs[bad], int(heading), k, word] |= bit
    return masks


def _forget_masks() -> None:
    """Empty the per-map masks, terms and terms in kernel layout; keep the pattern books (and
    the planner's other caches, warm for the plain plan too)."""
    from selfrepair.search import _kernels

    for cache in (masks_module._MASKS, masks_module._TERMS, _kernels._EXTRA):
        cache.clear()


def _measure(
    k: int, table_name: str, actions: tuple[Any, ...], repeats: int
) -> list[dict[str, Any]]:
    """The rows of one fault model and table: one per bundled route."""
    model = fault_model(FOUR_WHEEL, k)
    table = resolve_table(table_name)
    cold_clears = set(CacheKind) - {CacheKind.PREFILLED, CacheKind.INPUT}
    grids = {n: load_bundled(n).free_grid(max(2, table_reach(table))) for n in maze_names()}
    few = max(1, repeats // 2)

    def empty() -> None:
        clear_caches(cold_clears)

    def masks(grid: FreeGrid, penalty: Fraction | None = None) -> Any:
        return tolerance_term(table, grid, actions, model, penalty=penalty)

    before = {n: _best(lambda g=g: _masks_before(table, g, actions, model), few, empty)
              for n, g in grids.items()}  # fmt: skip
    cold = {n: _best(lambda g=g: masks(g), few, empty) for n, g in grids.items()}
    for grid in grids.values():  # fill the book with every bundled map's patterns
        masks(grid)
    rows = []
    for name, grid in grids.items():
        maze = load_bundled(name)
        warm = _best(lambda g=grid: masks(g), repeats, _forget_masks)
        for route in bundled_routes(name):
            problem = PlanningProblem(maze, route.start, route.goal)

            def tolerant(penalty: Fraction | None, p: Any = problem, g: Any = grid) -> Any:
                term = masks(g, penalty)
                return plan(PlanningProblem(p.maze, p.start, p.goal, step_term=term),
                            backend="numba")  # fmt: skip

            rows.append({
                "k": k, "maze": name, "table": table_name, "route": route.name,
                "plain": _best(lambda p=problem: plan(p, backend="numba"), repeats),
                "hard": _best(lambda t=tolerant: t(None), repeats),
                "soft": _best(lambda t=tolerant: t(Fraction(1)), repeats),
                "first": _best(lambda t=tolerant: t(None), repeats, _forget_masks),
                "masks_before": before[name], "masks_cold": cold[name], "masks_warm": warm,
                "hard_solved": tolerant(None).status.value == "solved",
            })  # fmt: skip
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    warm_up()
    actions = planning_actions(FOUR_WHEEL, frozenset())
    rows = [
        row for k in (1, 2) for table in TABLES for row in _measure(k, table, actions, args.repeats)
    ]
    report: dict[str, Any] = {"machine": platform.machine(), "python": platform.python_version()}
    for k in (1, 2):
        sub = [r for r in rows if r["k"] == k]
        med = {key: statistics.median(r[key] for r in sub) for key in KEYS}
        ratio = {key: statistics.median(r[key] / r["plain"] for r in sub) for key in KEYS}
        worst_first = max(r["first"] / r["plain"] for r in sub)
        report[f"k={k}"] = {
            "median_us": {key: round(value * 1e6, 1) for key, value in med.items()},
            "median_over_plain": {key: round(value, 2) for key, value in ratio.items()},
            "first_over_plain_max": round(worst_first, 2),
            "first_within_2x": sum(r["first"] <= 2 * r["plain"] for r in sub),
            "hard_solved": sum(r["hard_solved"] for r in sub),
            "queries": len(sub),
        }
        r = report[f"k={k}"]
        print(f"k={k}, medians over {r['queries']} queries (us; x: per query, over plain):")
        for key in KEYS:
            print(f"  {key:13} {r['median_us'][key]:>10} us  {r['median_over_plain'][key]:>8}x")
        print(f"  first plan within 2x of plain in {r['first_within_2x']} of {r['queries']} "
              f"queries (worst {r['first_over_plain_max']}x)")  # fmt: skip
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "tolerant_planner.json").write_text(json.dumps(report, indent=2) + "\n")


if __name__ == "__main__":
    main()
