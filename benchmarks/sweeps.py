"""Parallel sweeps: missions per second with ``--jobs 2`` against ``--jobs 1``, measured in one run,
next to the machine's own two-process control figure.

Each measurement is a fresh Python process that expands the experiment (default: the bundled
``paper``, 2304 missions) and runs it into a new database with
:func:`selfrepair.experiment.runner.run_missions`: missions per second is the number of missions
over the sweep's wall time (``RunSummary.seconds``: from the first claim to the last stored
batch, worker start-up included; interpreter start, imports and expansion left out, as they are
the same for both). The *control* is the same for a fixed pure-Python loop: one process alone,
then two at once; its ratio (2 x one-process time / two-process time) is how much two processes
can gain on this machine at this moment (2.0 on two free cores, less when other work shares
them). Runs are interleaved (control, jobs 1, jobs 2, per repeat) so load changes hit all alike;
medians over the repeats are reported.

Target (issue 12): jobs-2 / jobs-1 at least 1.6 when two cores are free, i.e. when the control
is close to 2. ``efficiency`` = (jobs-2 / jobs-1) / control, the share of the machine's two-process
gain the sweep gets. The control's lone loop also reports the share of a core it got (CPU time
over wall time): well under 100% means other work was running and the figures say little about
two free cores. Each sweep also reports its CPU time per mission (driver and workers, from
/proc): the jobs-2 / jobs-1 ratio of that is what parallelism costs in start-up, warm-up and
transfer, and it is much less sensitive to other load than wall time. Writes
``benchmarks/results/sweeps.json``.

Usage: ``python benchmarks/sweeps.py [--experiment NAME|FILE.toml] [--repeats N] [--limit N]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "sweeps.json"

SWEEP = """
import json, sys
from pathlib import Path
from selfrepair.cli.experiments import resolve_experiment
from selfrepair.experiment.config import load_config
from selfrepair.experiment.missions import expand
from selfrepair.experiment.runner import run_missions
from selfrepair.experiment.store import ResultStore
spec, db, jobs, limit = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
missions = expand(load_config(resolve_experiment(spec)))
missions = missions[:limit] if limit else missions

def cpu_seconds():
    # CPU time of this process and of the workers it started: the living ones read from /proc
    # (loky's outlive the run), the ended ones from getrusage (forked ones end with the run);
    # None where /proc is missing
    import os, resource, time
    try:
        tick = os.sysconf("SC_CLK_TCK")
        ended = resource.getrusage(resource.RUSAGE_CHILDREN)
        total = time.process_time() + ended.ru_utime + ended.ru_stime
        for task in Path("/proc/self/task").iterdir():
            for child in (task / "children").read_text().split():
                fields = Path(f"/proc/{child}/stat").read_text().rsplit(")", 1)[1].split()
                total += (int(fields[11]) + int(fields[12])) / tick
        return total
    except OSError:
        return None

with ResultStore(db) as store:
    cpu0 = cpu_seconds()
    summary = run_missions(missions, store, jobs=jobs)
    cpu1 = cpu_seconds()
cpu = None if cpu0 is None or cpu1 is None else cpu1 - cpu0
print(json.dumps({"missions": summary.ran, "seconds": summary.seconds, "cpu": cpu}))
"""

LOOP = """
import time
t0, c0 = time.perf_counter(), time.process_time()
total = 0
for i in range(12_000_000):
    total += i % 7
print(time.perf_counter() - t0, time.process_time() - c0)
"""


def sweep(spec: str, jobs: int, limit: int) -> tuple[float, float | None]:
    """Missions per second of one sweep in a fresh process, and its CPU seconds per mission
    (driver and workers; ``None`` without /proc)."""
    with tempfile.TemporaryDirectory() as folder:
        db = str(Path(folder) / "bench.sqlite")
        out = subprocess.run(
            [sys.executable, "-c", SWEEP, spec, db, str(jobs), str(limit)],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    result = json.loads(out)
    missions = float(result["missions"])
    cpu = None if result["cpu"] is None else float(result["cpu"]) / missions
    return missions / float(result["seconds"]), cpu


def control() -> tuple[float, float]:
    """2 x (one loop alone) / (two loops at once, the slower of the two); and the share of a
    core the lone loop got (CPU time / wall time: 1.0 when a core was free)."""
    wall, cpu = (
        float(v)
        for v in subprocess.run(
            [sys.executable, "-c", LOOP], check=True, capture_output=True, text=True
        ).stdout.split()
    )
    procs = [
        subprocess.Popen([sys.executable, "-c", LOOP], stdout=subprocess.PIPE, text=True)
        for _ in range(2)
    ]
    both = max(float(p.communicate()[0].split()[0]) for p in procs)
    return 2 * wall / both, cpu / wall


def load_average() -> float | None:
    try:
        return float(Path("/proc/loadavg").read_text().split()[0])
    except OSError:
        return None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--experiment", default="paper")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--limit", type=int, default=0, help="only the first N missions")
    args = parser.parse_args()
    rows = []
    for repeat in range(args.repeats):
        gain, share = control()
        row = {"load_before": load_average(), "control": gain, "core_share": share}
        row["jobs1"], row["cpu_per_mission_jobs1"] = sweep(args.experiment, 1, args.limit)
        row["jobs2"], row["cpu_per_mission_jobs2"] = sweep(args.experiment, 2, args.limit)
        row["ratio"] = row["jobs2"] / row["jobs1"]
        if row["cpu_per_mission_jobs1"] and row["cpu_per_mission_jobs2"]:
            row["cpu_ratio"] = row["cpu_per_mission_jobs2"] / row["cpu_per_mission_jobs1"]
        rows.append(row)
        print(
            f"repeat {repeat + 1}: load {row['load_before']}, control {row['control']:.2f} "
            f"(a lone process got {row['core_share']:.0%} of a core), "
            f"jobs 1 {row['jobs1']:.0f}/s, jobs 2 {row['jobs2']:.0f}/s, "
            f"ratio {row['ratio']:.2f}; CPU per mission jobs 2 / jobs 1 "
            f"{row.get('cpu_ratio', float('nan')):.2f}",
            flush=True,
        )
    names = ("control", "core_share", "jobs1", "jobs2")
    med = {k: statistics.median(float(r[k]) for r in rows) for k in names}
    ratio = statistics.median(float(r["ratio"]) for r in rows)
    cpu_ratios = [float(r["cpu_ratio"]) for r in rows if "cpu_ratio" in r]
    cpu_ratio = statistics.median(cpu_ratios) if cpu_ratios else None
    summary = {
        "experiment": args.experiment,
        "limit": args.limit,
        "repeats": args.repeats,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "median_control": med["control"],
        "median_core_share": med["core_share"],
        "median_jobs1_missions_per_s": med["jobs1"],
        "median_jobs2_missions_per_s": med["jobs2"],
        "median_ratio": ratio,
        "efficiency": ratio / med["control"],
        "median_cpu_ratio": cpu_ratio,
        "target_ratio": 1.6,
        "rows": rows,
        "measured_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    print(
        f"median over {args.repeats}: jobs 1 {med['jobs1']:.0f} missions/s, jobs 2 "
        f"{med['jobs2']:.0f} missions/s, ratio {ratio:.2f} (target >= 1.6 on two free cores); "
        f"machine's two-process control {med['control']:.2f} (a lone process got "
        f"{med['core_share']:.0%} of a core); efficiency "
        f"{ratio / med['control']:.2f}"
    )
    if cpu_ratio is not None:
        print(
            f"CPU time per mission, jobs 2 / jobs 1: {cpu_ratio:.2f} (what the second process "
            "costs in start-up, warm-up and transfer, whatever the load)"
        )
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(summary, indent=2) + "\n")


if __name__ == "__main__":
    main()
