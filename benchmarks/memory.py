"""Memory of one mission on a large maze: what a mission adds over the maze itself.

In a fresh process per measurement: import, load the compiled kernels on a tiny maze, generate a
``--size`` x ``--size`` maze (corridor 1, braid 0.1, seeded) and note the resident set (RSS); then
run one mission from near the top-left corner to near the bottom-right one with a permanent fault
detected at once (the initial plan does not know it, so the robot repairs along the way) and note
the peak RSS during the mission (Linux: ``VmHWM`` after resetting it through
``/proc/self/clear_refs``) and the peak of ``tracemalloc`` (which counts every allocation in full,
also pages never touched). The figure is peak RSS minus the RSS with the maze loaded.

Strategies measured: ``replacement`` (flat recursion, hand-written table; the target) and
``replan`` (the same mission without a table: what the planner alone needs). Target (issue 12): a
replacement mission on a 2048 x 2048 maze adds at most 50 MB over the maze itself.

Run: ``.venv/bin/python benchmarks/memory.py`` (a few minutes: generating the maze dominates).
Writes ``benchmarks/results/memory.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from _common import run_child, write_report

CHILD = r"""
import json, sys, time, tracemalloc
from pathlib import Path

def rss_kb(field):
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    return -1

def reset_peak():
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False

size, strategy, fault = int(sys.argv[1]), sys.argv[2], sys.argv[3]
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots import four_wheel
from selfrepair.search.warmup import ensure_warm
from selfrepair.world.mazegen import generate_maze

ensure_warm()
t0 = time.perf_counter()
maze = generate_maze(size, size, braid=0.1, seed=2048)
made = time.perf_counter() - t0
import numpy as np
ys, xs = np.nonzero(~maze.walls)
first, last = int(np.argmin(xs + ys)), int(np.argmax(xs + ys))
start, goal = Pose(int(xs[first]), int(ys[first]), Heading.E), (int(xs[last]), int(ys[last]))
del ys, xs
faults = four_wheel.parse_faults(fault)
spec = MissionSpec(
    maze, start, goal, schedule=FaultSchedule.permanent(faults), strategy=strategy,
    options=StrategyOptions(table="handwritten"), max_steps=50 * size * size,
)
import gc; gc.collect()
before = rss_kb("VmRSS")
reset = reset_peak()
tracemalloc.start()
t0 = time.perf_counter()
result = run_mission(spec)
seconds = time.perf_counter() - t0
traced_peak = tracemalloc.get_traced_memory()[1]
tracemalloc.stop()
peak = rss_kb("VmHWM")
print(json.dumps({
    "size": size, "strategy": strategy, "fault": fault, "maze_seconds": made,
    "rss_with_maze_mb": before / 1024, "peak_rss_mb": peak / 1024,
    "added_mb": (peak - before) / 1024, "peak_reset": reset,
    "tracemalloc_peak_mb": traced_peak / 2**20, "mission_seconds": seconds,
    "status": str(result.status), "steps": len(result.steps), "repairs": len(result.repairs),
    "initial_expansions": result.initial_plan.expansions,
}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--size", type=int, default=2048)
    parser.add_argument("--fault", default="FL:F")
    parser.add_argument("--strategies", default="replacement,replan")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if not sys.platform.startswith("linux"):
        sys.exit("this benchmark reads /proc/self/status (Linux only)")
    runs = []
    for strategy in args.strategies.split(","):
        _, _, out = run_child(["-c", CHILD, str(args.size), strategy, args.fault])
        run = json.loads(out.strip().splitlines()[-1])
        runs.append(run)
        print(
            f"{strategy:12} {args.size}x{args.size}: RSS with maze "
            f"{run['rss_with_maze_mb']:.0f} MB, mission adds {run['added_mb']:.1f} MB "
            "(tracemalloc peak "
            f"{run['tracemalloc_peak_mb']:.1f} MB); {run['status']} in {run['steps']} steps, "
            f"{run['repairs']} repairs, {run['mission_seconds']:.1f} s"
        )
    target = next((r for r in runs if r["strategy"] == "replacement"), None)
    report = {
        "settings": vars(args) | {"out": str(args.out)},
        "runs": runs,
        "target_added_mb_at_most": 50,
        "met": None if target is None else target["added_mb"] <= 50,
    }
    print(f"wrote {write_report('memory', report, args.out)}")


if __name__ == "__main__":
    main()
