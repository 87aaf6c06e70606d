"""Whole-plan rewriting against the compiled replanner (issue 25), two versions of the code side
by side: ``selfrepair experiment paper --jobs 1 --footing compiled`` run alternately (A B A B
...) on the ``src`` of each version, each run into a fresh database; per bundled maze, the paired
median of rewriting's repair compute per mission over the replanner's on the same mission (same
route and fault set) with its 95% percentile-bootstrap interval
(:func:`mission_loop.paired_ratios`), per run and pooled over the runs of a version. The load
average is recorded before and after each run. The rows of every run are compared with the first
run's, mission by mission, in every column but the timings and ``footing`` (a change that lowers
the compute must not change a plan).

Run: ``.venv/bin/python benchmarks/rewrite_ab.py --base 46a4db6 --rounds 2`` (the working tree's
``src`` is B; ``--base`` is A, checked out as a detached worktree in the temporary directory).
Writes ``benchmarks/results/rewrite_ab.json``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from collections import defaultdict
from pathlib import Path
from typing import Any

from _common import ROOT, baseline_source, run_child, write_report
from mission_loop import CLI, paired_ratios, ratio_summary, rows, same_rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--base", default="main", help="commit of version A")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--experiment", default="paper")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    sources = {"A": baseline_source(args.base), "B": ROOT / "src"}
    report: dict[str, Any] = {"settings": {**vars(args), "out": str(args.out)}, "runs": []}
    pooled: dict[str, dict[str, list[float]]] = defaultdict(lambda: defaultdict(list))
    first: dict[str, dict[str, Any]] | None = None
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.rounds):
            for name, src in sources.items():
                db = Path(tmp) / f"{name}-{i}.sqlite"
                command = ["-c", CLI, "experiment", args.experiment, "--jobs", "1"]
                command += ["--footing", "compiled", "--db", str(db)]
                load_before = os.getloadavg()
                cpu, wall, _ = run_child(command, src=src)
                load_after = os.getloadavg()
                table = rows(db)
                if first is None:
                    first = table
                agree, total = same_rows(first, table)
                per_maze = paired_ratios(table)  # paired within the run
                for maze, values in per_maze.items():
                    pooled[name][maze].extend(values)
                ratios = ratio_summary(per_maze)
                run = {
                    "version": name,
                    "round": i,
                    "src": str(src),
                    "cpu_s": cpu,
                    "wall_s": wall,
                    "load": [load_before[0], load_after[0]],
                    "rows_agree_with_first": f"{agree} of {total}",
                    "ratios": ratios,
                }
                report["runs"].append(run)
                print(f"{name} round {i + 1}: {cpu:.1f} s CPU, load {load_before[0]:.1f}-"
                      f"{load_after[0]:.1f}, rows agree {agree}/{total}", flush=True)  # fmt: skip
                for maze, r in ratios.items():
                    print(f"  {maze:12} {r['median_ratio']:.3f} [{r['low']:.3f}, "
                          f"{r['high']:.3f}]", flush=True)  # fmt: skip
    summary: dict[str, dict[str, Any]] = {}
    for name, per_maze in pooled.items():  # one pair per mission and run
        summary[name] = ratio_summary(per_maze)
    report["pooled"] = summary
    for name, per_maze in summary.items():
        print(f"{name} pooled over {args.rounds} runs ({sources[name]}):")
        for maze, r in per_maze.items():
            verdict = "MET" if r["median_ratio"] <= 0.1 else "NOT MET"
            print(f"  {maze:12} {r['median_ratio']:.3f} [{r['low']:.3f}, {r['high']:.3f}] "
                  f"over {r['pairs']} pairs (target <= 0.1: {verdict})")  # fmt: skip
    print(f"wrote {write_report('rewrite_ab', report, args.out)}")


if __name__ == "__main__":
    main()
