"""Table generation: how long it takes, and what the tables it makes are worth, in one run.

Measures, each the best of ``--repeats`` runs of a fresh process-local generation (caches of
class costs and enumerations are rebuilt every time, since each call builds its own searcher):

* full **fault-indexed** generation (all 12 single and 66 double faults, K = 5, max length 5) --
  target under 10 s on this machine;
* full **fault-agnostic** generation (K = 5), with priority ``cost`` and ``walls``;
* as a peer in the same run, the **exact optimum** for every (fault set, disabled action) pair
  (:func:`selfrepair.repair.coverage.optimal_replacements`, Dijkstra with no length limit): the
  indexed generator must not be much slower than merely computing the answers it has to contain;
* **lookup** time of ``ReplacementTable.candidates`` on the same random single-fault keys for
  tables of 81, 324 and 3402 entries (O(1): the per-lookup time must not grow with the number
  of entries);
* the **coverage report** of each table (hand-written, generated agnostic both priorities,
  generated indexed): free-space coverage and optimality over the 78 fault sets, and coverage
  next to walls over every free cell and heading of the four bundled mazes.

Writes ``benchmarks/results/tablegen.json``. Run: ``.venv/bin/python benchmarks/tablegen.py``
(about a minute; ``--quick`` for one repeat).
"""

from __future__ import annotations

import argparse
import json
import platform
import random
import time
from pathlib import Path
from typing import Any

from selfrepair.repair.coverage import coverage_report, optimal_replacements
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.tables.fileformat import bundled_table, dump_table
from selfrepair.tables.generate import generate_table
from selfrepair.tables.model import GenerateOptions, ReplacementTable
from selfrepair.world.bundled import load_bundled, maze_names

RESULTS = Path(__file__).parent / "results" / "tablegen.json"


def best_time(fn: Any, repeats: int) -> tuple[float, Any]:
    """Best wall-clock seconds of ``repeats`` calls, and the last result."""
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return min(times), result


def lookup_ns(
    tables: dict[str, ReplacementTable], keys: list[tuple[Any, frozenset[Any]]], rounds: int = 9
) -> dict[str, float]:
    """Nanoseconds per ``candidates`` call over ``keys``, for each table: the fastest of
    ``rounds`` passes, the tables taking turns so that machine noise hits them alike."""
    for table in tables.values():
        for action, faults in keys:
            table.candidates(action, faults)
    best = {name: float("inf") for name in tables}
    for _ in range(rounds):
        for name, table in tables.items():
            start = time.perf_counter_ns()
            for action, faults in keys:
                table.candidates(action, faults)
            best[name] = min(best[name], (time.perf_counter_ns() - start) / len(keys))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="one repeat")
    args = parser.parse_args()
    repeats = 1 if args.quick else args.repeats

    indexed_options = GenerateOptions(shape="fault-indexed")
    t_indexed, indexed = best_time(lambda: generate_table(FOUR_WHEEL, indexed_options), repeats)
    t_agnostic, agnostic = best_time(lambda: generate_table(FOUR_WHEEL, GenerateOptions()), repeats)
    t_walls, walls = best_time(
        lambda: generate_table(FOUR_WHEEL, GenerateOptions(priority="walls")), repeats
    )
    t_optimum, _ = best_time(
        lambda: [optimal_replacements(FOUR_WHEEL, f) for f in FOUR_WHEEL.fault_sets], repeats
    )
    _, singles = best_time(
        lambda: generate_table(
            FOUR_WHEEL, GenerateOptions(shape="fault-indexed", faults="singles")
        ),
        1,
    )

    print("generation (best of", repeats, "runs)")
    print(
        f"  fault-indexed, 78 fault sets, {len(indexed.entries)} entries: {t_indexed:.2f} s "
        f"(target < 10 s: {'met' if t_indexed < 10 else 'MISSED'})"
    )
    print(f"  fault-agnostic K=5, priority cost:  {t_agnostic:.2f} s")
    print(f"  fault-agnostic K=5, priority walls: {t_walls:.2f} s")
    print(
        f"  peer: exact optimum for all 3402 pairs: {t_optimum:.2f} s "
        f"(indexed generation / optimum = {t_indexed / t_optimum:.2f}x)"
    )

    rng = random.Random(1)
    singles_sets = [f for f in FOUR_WHEEL.fault_sets if len(f) == 1]
    keys = [(rng.choice(FOUR_WHEEL.actions), rng.choice(singles_sets)) for _ in range(20000)]
    sized = {  # the same keys for every table, so only the table size differs
        "fault-agnostic (81 entries)": agnostic,
        "fault-indexed singles (324 entries)": singles,
        "fault-indexed all (3402 entries)": indexed,
    }
    timed = lookup_ns(sized, keys)
    lookups = {name: (len(table.entries), timed[name]) for name, table in sized.items()}
    print("lookup (ns per candidates() call, fastest of 9 passes over the same 20000 keys)")
    for name, (_, ns) in lookups.items():
        print(f"  {name}: {ns:.0f} ns")
    ratio = (
        lookups["fault-indexed all (3402 entries)"][1]
        / lookups["fault-indexed singles (324 entries)"][1]
    )
    print(f"  3402-entry / 324-entry lookup time: {ratio:.2f}x (O(1): about 1)")

    mazes = [(name, load_bundled(name)) for name in maze_names()]
    tables = {
        "handwritten": bundled_table("handwritten"),
        "generated-agnostic (cost)": agnostic,
        "generated-agnostic (walls)": walls,
        "generated-indexed": indexed,
    }
    reports: dict[str, Any] = {}
    print("coverage (78 fault sets, flat; walls: 4 bundled mazes, every free cell and heading)")
    print(
        f"  {'table':28} {'covered':>16} {'optimal':>8} {'mean+':>7} {'max+':>7} "
        f"{'wall gaps':>10} {'report s':>9}"
    )
    for name, table in tables.items():
        start = time.perf_counter()
        report = coverage_report(table, mazes=mazes, label=name)
        elapsed = time.perf_counter() - start
        t = report.totals()
        guarded = coverage_report(table, mode="guarded", label=name).totals()
        reports[name] = {
            "flat": t,
            "guarded": guarded,
            "report_seconds": elapsed,
            "bytes": len(dump_table(table).encode()),
            "entries": len(table.entries),
            "candidates": sum(len(e.candidates) for e in table.entries),
        }
        print(
            f"  {name:28} {t['covered']:>5}/{t['replaceable']} {100 * t['coverage']:5.1f}% "
            f"{100 * t['optimal_share']:7.1f}% {100 * t['mean_excess']:6.1f}% "
            f"{100 * t['max_excess']:6.1f}% {100 * t['wall_uncovered_share']:9.2f}% "
            f"{elapsed:9.2f}"
        )
    print(
        "  (guarded recursion, free space: "
        + ", ".join(
            f"{n} {100 * r['guarded']['coverage']:.1f}% covered, "
            f"{100 * r['guarded']['optimal_share']:.1f}% optimal"
            for n, r in reports.items()
        )
        + ")"
    )

    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text(
        json.dumps(
            {
                "machine": {
                    "python": platform.python_version(),
                    "processor": platform.processor(),
                    "system": platform.system(),
                },
                "repeats": repeats,
                "generation_seconds": {
                    "fault-indexed": t_indexed,
                    "fault-agnostic-cost": t_agnostic,
                    "fault-agnostic-walls": t_walls,
                    "exact-optimum-all-pairs": t_optimum,
                },
                "indexed_target_met": t_indexed < 10,
                "lookup_ns": {name: {"entries": n, "ns": ns} for name, (n, ns) in lookups.items()},
                "coverage": reports,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
