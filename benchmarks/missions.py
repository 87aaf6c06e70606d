"""Missions per second of ``selfrepair experiment paper --jobs 1``, against earlier commits.

Three versions run the same command with the same interpreter (each earlier commit, see
``benchmarks/_common.py``, with its ``src`` first on ``PYTHONPATH``), once unmeasured (so that
numba's cache is filled) and then in turn ``--repeats`` times, each into a fresh database:

* ``baseline``: the code issue 12 measured (:data:`BASELINE_COMMIT`), whose ``paper`` experiment
  ran each of its 2304 missions once;
* ``before``: the code just before these speed-ups (:data:`BEFORE_COMMIT`), with the same
  experiment design as the current code (3072 missions, each run cold after the derived-data
  caches are emptied and then once warm), so ``current / before`` is the speed-up on equal work;
* ``current``: this checkout.

Each version's missions are counted with its own code. Each
run is followed by the same command on the now complete database, which skips every mission: its
CPU time is the command's fixed cost (imports, kernel loading, configuration, summary and
findings). Figures are CPU seconds of the process (user + system), so that other load on the
machine disturbs them less than wall time:

* gross missions/s: missions / CPU seconds of the whole command;
* net missions/s: missions / (CPU seconds of the whole command - its fixed cost).

Target (issue 12): at least 4x the baseline's missions/s (reported for gross and net), medians
over the repeats.

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

from _common import (
    BASELINE_COMMIT,
    BEFORE_COMMIT,
    ROOT,
    baseline_source,
    median,
    run_child,
    write_report,
)

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


def count_missions(args: argparse.Namespace, src: Path | None) -> int:
    code = (
        "import sys; from selfrepair.cli.experiments import resolve_experiment; "
        "from selfrepair.experiment.config import load_config; "
        "from selfrepair.experiment.missions import expand; "
        "print(len(expand(load_config(resolve_experiment(sys.argv[1])))))"
    )
    return int(run_child(["-c", code, args.experiment], src=src)[2].strip())


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
    parser.add_argument(
        "--versions", default="baseline,before,current", help="which versions to run, in turn"
    )
    parser.add_argument("--no-prime", action="store_true", help="numba's caches are already full")
    parser.add_argument("--before", default=BEFORE_COMMIT, help="the commit run as 'before'")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    sources = {"baseline": BASELINE_COMMIT, "before": args.before, "current": None}
    versions: dict[str, Path | None] = {
        v: None if sources[v] is None else baseline_source(str(sources[v]))
        for v in args.versions.split(",")
    }
    missions = {v: count_missions(args, src) for v, src in versions.items()}
    runs: dict[str, list[dict[str, float]]] = {v: [] for v in versions}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for version, src in versions.items() if not args.no_prime else ():
            sweep(args, src, folder, f"prime-{version}")  # fills numba's cache, warms the disk
        for i in range(args.repeats):
            for version, src in versions.items():
                run = sweep(args, src, folder, f"{version}-{i}")
                n = missions[version]
                run["gross_missions_per_s"] = n / run["cpu_s"]
                run["net_missions_per_s"] = n / max(1e-9, run["cpu_s"] - run["fixed_cpu_s"])
                runs[version].append(run)
                print(
                    f"  {version:8} run {i + 1}: {n} missions, {run['cpu_s']:6.2f} s CPU "
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

    def ratio(peer: str, kind: str) -> float | None:
        key = f"{kind}_missions_per_s"
        if "current" not in summary or peer not in summary:
            return None
        return summary["current"][key] / summary[peer][key]

    report: dict[str, Any] = {
        "settings": {"experiment": args.experiment, "repeats": args.repeats, "missions": missions},
        "commits": {v: None if src is None else src.parent.name for v, src in versions.items()},
        "runs": runs,
        "medians": summary,
        "speedup_gross": ratio("baseline", "gross"),
        "speedup_net": ratio("baseline", "net"),
        "speedup_over_before_gross": ratio("before", "gross"),
        "speedup_over_before_net": ratio("before", "net"),
        "target_speedup_at_least": 4.0,
        "profile": profiled,
        "target_compiled_share_at_least": 0.25,
    }
    print(f"medians of {args.repeats}, missions/s gross (net of the fixed cost):")
    for version in versions:
        m = summary[version]
        print(
            f"  {version:8} {m['gross_missions_per_s']:7.1f} ({m['net_missions_per_s']:.1f})"
            f"  [{missions[version]} missions]"
        )
    for peer in ("baseline", "before"):
        gross, net = ratio(peer, "gross"), ratio(peer, "net")
        if gross is None or net is None:
            continue
        print(
            f"current / {peer}: {gross:.2f}x gross, {net:.2f}x net"
            + (" (target >= 4)" if peer == "baseline" else " (same work per mission)")
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
