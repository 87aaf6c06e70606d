"""Start-up benchmark: how long quick commands take from a cold process, against ``python -c pass``.

Each command runs as a fresh process (the installed ``selfrepair`` script next to this
interpreter), ``--repeats`` times, interleaved with the others so that machine noise hits all of
them alike; the table reports the median wall time of each and its ratio to the median of
``python -c pass`` measured in the same run. The commands:

* ``selfrepair --help`` and ``selfrepair actions``: must import no heavy library (numba,
  pydantic, joblib, matplotlib; ``tests/test_cli_shape.py`` checks that);
* ``selfrepair plan narrow-short ...`` on the smallest bundled maze, with the default backend
  (numba kernels loaded from the on-disk cache; the load is part of a cold start) and with
  ``--backend python``.

Results go to ``benchmarks/results/startup.json``.

Run: ``.venv/bin/python benchmarks/startup.py`` (about a minute).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "benchmarks" / "results" / "startup.json"
PLAN = ["plan", "narrow-short", "--start", "1,1,E", "--goal", "13,13"]


def selfrepair_command() -> list[str]:
    """The installed console script next to this interpreter (or an equivalent ``-c``)."""
    script = Path(sys.executable).parent / "selfrepair"
    if script.exists():
        return [str(script)]
    return [sys.executable, "-c", "from selfrepair.cli import run; run()"]


def commands() -> dict[str, list[str]]:
    cli = selfrepair_command()
    return {
        "python -c pass": [sys.executable, "-c", "pass"],
        "selfrepair --help": [*cli, "--help"],
        "selfrepair actions": [*cli, "actions"],
        "selfrepair plan (smallest maze)": [*cli, *PLAN],
        "selfrepair plan --backend python": [*cli, *PLAN, "--backend", "python"],
    }


def wall_time(argv: list[str]) -> float:
    """Seconds from start to exit of one process (output discarded; it must succeed)."""
    t0 = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=True)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n", 1)[0])
    parser.add_argument("--repeats", type=int, default=15, help="runs of each command")
    parser.add_argument("--out", type=Path, default=OUT, help="JSON file to write")
    args = parser.parse_args()
    argvs = commands()
    for argv in argvs.values():  # once each, untimed: the OS file cache and numba's disk cache
        wall_time(argv)
    times: dict[str, list[float]] = {name: [] for name in argvs}
    for _ in range(args.repeats):
        for name, argv in argvs.items():
            times[name].append(wall_time(argv))
    base = statistics.median(times["python -c pass"])
    rows: dict[str, dict[str, Any]] = {}
    for name, values in times.items():
        median = statistics.median(values)
        rows[name] = {
            "median_ms": round(median * 1000, 1),
            "min_ms": round(min(values) * 1000, 1),
            "max_ms": round(max(values) * 1000, 1),
            "ratio_to_python": round(median / base, 1),
            "argv": argvs[name][1:] if name != "python -c pass" else ["-c", "pass"],
        }
    report = {
        "benchmark": "startup",
        "when": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": {
            "python": platform.python_version(),
            "cpu_count": os.cpu_count(),
            "platform": platform.platform(),
            "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        },
        "repeats": args.repeats,
        "commands": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    print(f"{'command':36} {'median ms':>10} {'min ms':>8} {'x python':>9}")
    for name, row in rows.items():
        print(
            f"{name:36} {row['median_ms']:10.1f} {row['min_ms']:8.1f} "
            f"{row['ratio_to_python']:9.1f}"
        )
    print(f"medians of {args.repeats} interleaved runs; wrote {args.out}")


if __name__ == "__main__":
    main()
