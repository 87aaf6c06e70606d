"""What the benchmark scripts share: medians, CPU time of child processes, the baseline checkout
and the JSON report.

The performance targets are ratios measured in one run against a peer measured side by side. For
the mission-loop targets the peer is the code at :data:`BASELINE_COMMIT` (the version the
performance issue measured): :func:`baseline_source` checks it out once as a detached git worktree
in the temporary directory and the scripts run it with the same interpreter, putting its ``src``
first on ``PYTHONPATH``.
"""

from __future__ import annotations

import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"
BASELINE_COMMIT = "743cfa9"
"""The code the performance issue (issue 12) measured."""
BEFORE_COMMIT = "b407647"
"""``main`` just before the speed-ups of issue 12 landed: the current experiment design (cold and
warm runs per mission, mission-level metrics), so a ratio against it is one on equal work."""


def baseline_source(commit: str = BASELINE_COMMIT) -> Path:
    """The ``src`` folder of ``commit`` in a detached worktree (made on first use)."""
    where = Path(tempfile.gettempdir()) / f"selfrepair-baseline-{commit}"
    if not (where / "src" / "selfrepair").is_dir():
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), commit],
            check=True,
            capture_output=True,
        )
    return where / "src"


def run_child(
    args: Sequence[str], *, src: Path | None = None, env: dict[str, str] | None = None
) -> tuple[float, float, str]:
    """Run ``python args...`` (with ``src`` first on the path when given); returns its CPU
    seconds (user + system, children included), wall seconds and standard output."""
    child_env = {**os.environ, **(env or {})}
    if src is not None:
        child_env["PYTHONPATH"] = str(src)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, *args], env=child_env, capture_output=True, text=True, check=False
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed:\n{out.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, out.stdout


def median(values: Sequence[float]) -> float:
    return float(statistics.median(values))


def machine() -> dict[str, Any]:
    """Where the figures were measured (they are only comparable within one run)."""
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    return {
        "python": platform.python_version(),
        "cpu_count": os.cpu_count(),
        "platform": platform.platform(),
        "load_average": load,
    }


def write_report(name: str, report: dict[str, Any], out: Path | None = None) -> Path:
    """Write ``report`` (with the time and machine added) as ``benchmarks/results/NAME.json``."""
    path = out or RESULTS / f"{name}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    full = {
        "benchmark": name,
        "when": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": machine(),
        **report,
    }
    path.write_text(json.dumps(full, indent=2) + "\n", encoding="utf-8")
    return path
