"""Missions per second of ``selfrepair experiment paper --jobs 1``, against the baseline commit.

Both versions run the same command with the same interpreter (the baseline commit, see
``benchmarks/_common.py``, with its ``src`` first on ``PYTHONPATH``), once unmeasured (so that
numba's cache is filled) and then alternately ``--repeats`` times, each into a fresh database. Each
run is followed by the same command on the now complete database, which skips every mission: its
CPU time is the command's fixed cost (imports, kernel loading, configuration, summary and
findings). Figures are CPU seconds of the process (user + system), so that other load on the
machine disturbs them less than wall time:

* gross missions/s: missions / CPU seconds of the whole command;
* net missions/s: missions / (CPU seconds of the whole command - its fixed cost).

Target (issue 12): at least 4x the baseline's missions/s (reported for both), medians over the
repeats.

Then one more run of the current version under ``py-spy`` (when installed) gives the share of
samples spent in the compiled search kernels (the leaf frame is a call of a numba kernel): target
at least 25% of all samples of the command. The share among the samples of the mission sweep only
(``run_missions``) is reported next to it.

Run: ``.venv/bin/python benchmarks/missions.py`` (several minutes). Writes
``benchmarks/results/missions.json``.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

from _common import ROOT, baseline_source, median, run_child, write_report

CLI = "import sys; from selfrepair.cli import main; sys.exit(main(sys.argv[1:]))"
KERNELS = ROOT / "src" / "selfrepair" / "search" / "_kernels.py"
CATEGORIES = (
    ("compiled search", None),
    ("planner (Python)", "plan (selfrepair/search/lattice.py"),
    ("replacement look-ups", "find_replacement ("),
    ("replacement look-ups", "flat_replacement ("),
    ("strategies (other)", "FunctionRepairer.repair ("),
    ("mission loop", "_loop (selfrepair/execution/executor.py"),
    ("metrics row", "mission_row ("),
    ("executor (other)", "run_mission ("),
    ("result store", "ResultStore.add ("),
    ("runner (other)", "execute_mission ("),
    ("sweep (other)", "run_missions ("),
)


def sweep(args: argparse.Namespace, src: Path | None, folder: Path, tag: str) -> dict[str, float]:
    """One full run and one all-skipped run of the experiment; CPU and wall seconds."""
    db = folder / f"{tag}.sqlite"
    command = ["-c", CLI, "experiment", args.experiment, "--jobs", "1", "--db", str(db)]
    cpu, wall, _ = run_child(command, src=src)
    fixed_cpu, fixed_wall, _ = run_child(command, src=src)
    db.unlink()
    return {"cpu_s": cpu, "wall_s": wall, "fixed_cpu_s": fixed_cpu, "fixed_wall_s": fixed_wall}


def count_missions(args: argparse.Namespace) -> int:
    code = (
        "import sys; from selfrepair.cli.experiments import resolve_experiment; "
        "from selfrepair.experiment.config import load_config; "
        "from selfrepair.experiment.missions import expand; "
        "print(len(expand(load_config(resolve_experiment(sys.argv[1])))))"
    )
    return int(run_child(["-c", code, args.experiment])[2].strip())


def kernel_lines() -> set[int]:
    """Lines of ``_kernels.py`` that call a compiled kernel (leaf frames there are compiled
    search)."""
    text = KERNELS.read_text(encoding="utf-8")
    names = re.findall(r"@njit\(cache=True[^)]*\)\ndef (\w+)", text)
    helpers = {"_less", "_push", "_pop"}  # inlined into the kernels, never called from Python
    calls = re.compile(r"\b(" + "|".join(n for n in names if n not in helpers) + r")\(")
    return {
        i
        for i, line in enumerate(text.splitlines(), start=1)
        if calls.search(line) and not line.lstrip().startswith("def ")
    }


def profile(args: argparse.Namespace, folder: Path) -> dict[str, Any] | None:
    """Sample one run with py-spy; shares of samples by category."""
    spy = shutil.which("py-spy") or str(Path(sys.executable).with_name("py-spy"))
    if not Path(spy).exists():
        print("py-spy is not installed: no profile (pip install py-spy)")
        return None
    raw = folder / "profile.txt"
    db = folder / "profiled.sqlite"
    command = [spy, "record", "-r", str(args.rate), "-f", "raw", "-o", str(raw), "--"]
    command += [sys.executable, "-c", CLI, "experiment", args.experiment, "--jobs", "1"]
    subprocess.run([*command, "--db", str(db)], check=True, capture_output=True)
    lines = kernel_lines()
    kernel_file = "search/_kernels.py:"
    totals: Counter[str] = Counter()
    sweep_total = sweep_kernel = 0
    for record in raw.read_text(encoding="utf-8").splitlines():
        stack, _, count_text = record.rpartition(" ")
        count = int(count_text)
        frames = stack.split(";")
        leaf = frames[-1]
        match = re.search(r":(\d+)\)$", leaf)
        compiled = kernel_file in leaf and match is not None and int(match.group(1)) in lines
        category = "compiled search" if compiled else "start-up, set-up and other"
        if not compiled:
            for frame in reversed(frames):
                hit = next((c for c, pat in CATEGORIES if pat and pat in frame), None)
                if hit:
                    category = hit
                    break
        totals[category] += count
        if any("run_missions (" in f for f in frames):
            sweep_total += count
            sweep_kernel += count if compiled else 0
    total = sum(totals.values())
    shares = {k: v / total for k, v in totals.most_common()}
    return {
        "samples": total,
        "rate_hz": args.rate,
        "compiled_search_share": shares.get("compiled search", 0.0),
        "compiled_search_share_of_sweep": sweep_kernel / sweep_total if sweep_total else None,
        "shares": shares,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--experiment", default="paper")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--rate", type=int, default=250, help="py-spy samples per second")
    parser.add_argument("--no-profile", action="store_true")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    missions = count_missions(args)
    old_src = baseline_source()
    runs: dict[str, list[dict[str, float]]] = {"baseline": [], "current": []}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for version, src in (("baseline", old_src), ("current", None)):
            sweep(args, src, folder, f"prime-{version}")  # fills numba's cache, warms the disk
        for i in range(args.repeats):
            for version, src in (("baseline", old_src), ("current", None)):
                run = sweep(args, src, folder, f"{version}-{i}")
                run["gross_missions_per_s"] = missions / run["cpu_s"]
                run["net_missions_per_s"] = missions / max(1e-9, run["cpu_s"] - run["fixed_cpu_s"])
                runs[version].append(run)
                print(
                    f"  {version:8} run {i + 1}: {run['cpu_s']:6.2f} s CPU "
                    f"(fixed {run['fixed_cpu_s']:.2f} s), {run['wall_s']:6.2f} s wall: "
                    f"{run['gross_missions_per_s']:6.1f} missions/s gross, "
                    f"{run['net_missions_per_s']:6.1f} net",
                    flush=True,
                )
        profiled = None if args.no_profile else profile(args, folder)
    summary = {
        version: {
            key: median([r[key] for r in rows])
            for key in ("cpu_s", "fixed_cpu_s", "gross_missions_per_s", "net_missions_per_s")
        }
        for version, rows in runs.items()
    }
    gross = summary["current"]["gross_missions_per_s"] / summary["baseline"]["gross_missions_per_s"]
    net = summary["current"]["net_missions_per_s"] / summary["baseline"]["net_missions_per_s"]
    report: dict[str, Any] = {
        "settings": {"experiment": args.experiment, "repeats": args.repeats, "missions": missions},
        "baseline_commit": old_src.parent.name,
        "runs": runs,
        "medians": summary,
        "speedup_gross": gross,
        "speedup_net": net,
        "target_speedup_at_least": 4.0,
        "profile": profiled,
        "target_compiled_share_at_least": 0.25,
    }
    print(
        f"{missions} missions, medians of {args.repeats}: baseline "
        f"{summary['baseline']['gross_missions_per_s']:.1f} missions/s gross "
        f"({summary['baseline']['net_missions_per_s']:.1f} net), current "
        f"{summary['current']['gross_missions_per_s']:.1f} "
        f"({summary['current']['net_missions_per_s']:.1f} net): speed-up {gross:.2f}x gross, "
        f"{net:.2f}x net (target >= 4)"
    )
    if profiled is not None:
        print(
            f"compiled search: {profiled['compiled_search_share']:.1%} of all samples "
            f"({profiled['compiled_search_share_of_sweep']:.1%} of the sweep's; target >= 25%)"
        )
        for name, share in profiled["shares"].items():
            print(f"  {share:6.1%}  {name}")
    print(f"wrote {write_report('missions', report, args.out)}")


if __name__ == "__main__":
    main()
