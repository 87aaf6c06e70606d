"""Equal footing (issue 25): the compiled mission loop against the Python loop, measured side by
side on the same missions.

1. ``selfrepair experiment paper --jobs 1`` with ``--footing python`` and ``--footing auto``
   (the compiled loop for every mission it takes), each into a fresh database, in CPU seconds of
   the process (user + system), gross and net of the command's fixed cost (the same command on
   the complete database, which skips every mission); the rows of both are compared mission by
   mission (every column but the timings and ``footing``). Target: compiled >= 10x the Python
   loop's missions/s.
2. One more compiled run under ``py-spy`` (when installed): the share of samples whose leaf frame
   is a call of a numba kernel (the mission kernel, the look-up hash, the planner kernels).
   Target >= 60%.
3. From the two databases: per bundled maze, whole-plan rewriting's repair compute per mission
   against the replanner's on the same mission (same route and fault set), the paired median of
   the ratio with its paired percentile-bootstrap interval (``selfrepair.stats.bootstrap_interval``
   over the per-mission ratios), under each footing. Target <= 1/10 under the compiled footing.
   Both sides time the same kind of work: ``repair_compute_ns`` is the mission's whole repair
   compute on its path (for rewriting, every rewrite of the plan the mission makes, look-ups,
   splices and walks included; for the replanner, every replan the mission makes), each repair one
   call from the same driver, timed alike.
4. A warm hit inside the loop: ``N`` look-ups through the mission kernel's look-up code timed in
   one call (:func:`selfrepair.execution.compiled.kernel.warm_hits`), per hit, next to ``N``
   ``dict.get`` calls of Python timed alike. Target <= 50 ns.

Run: ``.venv/bin/python benchmarks/mission_loop.py`` (a few minutes). Writes
``benchmarks/results/mission_loop.json``.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any

from _common import ROOT, median, run_child, write_report

CLI = "import sys; from selfrepair.cli import main; sys.exit(main(sys.argv[1:]))"
KERNEL_FILES = {
    "execution/compiled/driver.py": r"\bk\.run_kernel\(",
    "execution/compiled/arrays.py": r"\bk\.hash_put\(",
    "search/_kernels.py": None,  # lines that call a search kernel (found below)
}
TIMING = ("_ns", "compute_per_action", "worker_seconds", "finished_at")


def sweep(footing: str, folder: Path, tag: str, experiment: str) -> dict[str, Any]:
    db = folder / f"{tag}.sqlite"
    command = ["-c", CLI, "experiment", experiment, "--jobs", "1", "--db", str(db)]
    command += ["--footing", footing]
    cpu, wall, out = run_child(command)
    fixed_cpu, _, _ = run_child(command)
    return {"db": db, "cpu_s": cpu, "wall_s": wall, "fixed_cpu_s": fixed_cpu, "stdout": out}


def rows(db: Path) -> dict[str, dict[str, Any]]:
    from selfrepair.experiment.store import ResultStore

    with ResultStore(db) as store:
        return {str(r["key"]): dict(r) for r in store.rows()}


def same_rows(a: dict[str, dict[str, Any]], b: dict[str, dict[str, Any]]) -> tuple[int, int]:
    """Missions whose non-timing columns (``footing`` aside) agree, of all."""
    agree = 0
    for key, row in a.items():
        other = b.get(key, {})
        cols = [c for c in row if c != "footing" and not any(t in c for t in TIMING)]
        agree += all(row[c] == other.get(c) for c in cols)
    return agree, len(a)


def kernel_lines() -> dict[str, set[int]]:
    """Per file, the lines that call a compiled kernel (a leaf frame there is compiled code)."""
    out: dict[str, set[int]] = {}
    src = ROOT / "src" / "selfrepair"
    for name, pattern in KERNEL_FILES.items():
        text = (src / name).read_text(encoding="utf-8")
        if pattern is None:
            names = re.findall(r"@(?:njit\(cache=True[^)]*\)|_search_kernel)\ndef (\w+)", text)
            pattern = r"\b(" + "|".join(n for n in names if n not in {"_less"}) + r")\("
        regex = re.compile(pattern)
        out[name] = {
            i
            for i, line in enumerate(text.splitlines(), start=1)
            if regex.search(line) and not line.lstrip().startswith("def ")
        }
    return out


def profile(folder: Path, experiment: str, rate: int) -> dict[str, Any] | None:
    spy = shutil.which("py-spy") or str(Path(sys.executable).with_name("py-spy"))
    if not Path(spy).exists():
        print("py-spy is not installed: no profile (pip install py-spy)")
        return None
    raw = folder / "profile.txt"
    command = [spy, "record", "-r", str(rate), "-f", "raw", "-o", str(raw), "--"]
    command += [sys.executable, "-c", CLI, "experiment", experiment, "--jobs", "1"]
    subprocess.run([*command, "--db", str(folder / "profiled.sqlite")], check=True,
                   capture_output=True)  # fmt: skip
    lines = kernel_lines()
    totals: Counter[str] = Counter()
    sweep_total = sweep_compiled = 0
    for record in raw.read_text(encoding="utf-8").splitlines():
        stack, _, count_text = record.rpartition(" ")
        count = int(count_text)
        frames = stack.split(";")
        leaf = frames[-1]
        compiled = False
        for name, at in lines.items():
            match = re.search(re.escape(name) + r":(\d+)\)$", leaf)
            if match and int(match.group(1)) in at:
                compiled = True
                totals[f"compiled ({name})"] += count
        if not compiled:
            where = re.search(r"\(([^:]*selfrepair/[^:]+):\d+\)$", leaf)
            totals[where.group(1).split("selfrepair/")[-1] if where else "other"] += count
        if any("run_missions (" in f for f in frames):
            sweep_total += count
            sweep_compiled += count if compiled else 0
    total = sum(totals.values())
    share = sum(v for k, v in totals.items() if k.startswith("compiled")) / total
    return {
        "samples": total,
        "rate_hz": rate,
        "compiled_share": share,
        "compiled_share_of_sweep": sweep_compiled / sweep_total if sweep_total else None,
        "top": {k: v / total for k, v in totals.most_common(12)},
    }


def paired_ratios(table: dict[str, dict[str, Any]]) -> dict[str, list[float]]:
    """Per maze: rewriting's repair compute over the replanner's on the same (route, faults),
    one ratio per rewriting mission (every rewriting variant)."""
    replan: dict[tuple[Any, ...], float] = {}
    rewrite: dict[tuple[Any, ...], list[float]] = defaultdict(list)
    for row in table.values():
        key = (row["maze"], row["start"], row["goal"], row["faults"])
        if row["strategy"] == "replan" and row["clearance_weight"] == "0":
            replan[key] = float(row["repair_compute_ns"])
        elif (
            row["strategy"] == "replacement"
            and int(row.get("rewrite") or 0)
            and row["clearance_weight"] == "0"
        ):
            rewrite[key].append(float(row["repair_compute_ns"]))
    per_maze: dict[str, list[float]] = defaultdict(list)
    for key, values in rewrite.items():
        if replan.get(key):
            per_maze[key[0]].extend(v / replan[key] for v in values)
    return per_maze


def rewrite_ratios(table: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per maze: the paired median of :func:`paired_ratios` with its 95% percentile-bootstrap
    interval and range."""
    return ratio_summary(paired_ratios(table))


def ratio_summary(per_maze: dict[str, list[float]]) -> dict[str, dict[str, Any]]:
    """Per maze: the median of the paired ratios with its 95% percentile-bootstrap interval and
    range."""
    from selfrepair.stats import bootstrap_interval

    out: dict[str, dict[str, Any]] = {}
    for maze, r in sorted(per_maze.items()):
        ci = bootstrap_interval(r)
        assert ci is not None
        out[maze] = {"pairs": len(r), "median_ratio": median(r), "low": ci.low, "high": ci.high,
                     "level": ci.level, "min": min(r), "max": max(r)}  # fmt: skip
    return out


def warm_hit(n: int) -> dict[str, float]:
    """Per-hit time of ``n`` look-ups in one kernel call, and of ``n`` ``dict.get``."""
    import numpy as np

    import selfrepair as sr
    from selfrepair.execution.compiled import kernel as k
    from selfrepair.execution.compiled.arrays import compiled_lookups
    from selfrepair.execution.context import mission_context
    from selfrepair.execution.executor import run_mission

    robot = sr.get_domain("four-wheel")
    maze = sr.load_bundled("narrow-long")
    route = sr.bundled_routes("narrow-long")[0]
    faults = sr.FaultSchedule.permanent(robot.parse_faults("FL:F,RR:B"))
    spec = sr.MissionSpec(maze, route.start, route.goal, schedule=faults, strategy="replacement",
                          options=sr.StrategyOptions(table="generated-indexed"), domain=robot,
                          footing="compiled")  # fmt: skip
    result = run_mission(spec)  # fills the look-ups the mission meets
    hits = [r for r in result.repairs if r.repair.source == "replacement"]
    context = mission_context(spec, spec.options.resolved_table())
    lk = compiled_lookups(context, len(robot.actions))
    known = frozenset(robot.parse_faults("FL:F,RR:B"))
    sid = lk.sets[known, frozenset()]  # the look-ups under no guard set
    index = {id(a): i for i, a in enumerate(robot.actions)}
    action = index[id(hits[0].action)]
    poses = [r.pose for r in hits if index[id(r.action)] == action]
    xs = np.array([p.x for p in poses], dtype=np.int64)
    ys = np.array([p.y for p in poses], dtype=np.int64)
    hs = np.array([int(p.heading) for p in poses], dtype=np.int64)
    set_of = np.full(4, -1, dtype=np.int64)
    set_of[3] = sid
    st = np.zeros(k.S_SIZE, dtype=np.int64)
    par = np.zeros(k.P_SIZE, dtype=np.int64)
    par[k.P_NSLOTS], par[k.P_WIDTH] = lk.n_slots, maze.width
    args = (st, par, set_of, lk.lk, lk.codes, lk.ht, 3, action, xs, ys, hs)
    assert k.warm_hits(len(poses), *args) >= 0  # every pose answered: no exit
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter_ns()
        k.warm_hits(n, *args)
        best = min(best, (time.perf_counter_ns() - t0) / n)
    table = {i: i for i in range(64)}
    get = table.get
    best_dict = float("inf")
    for _ in range(5):
        t0 = time.perf_counter_ns()
        for i in range(n // 10):
            get(i & 63)
        best_dict = min(best_dict, (time.perf_counter_ns() - t0) / (n // 10))
    return {"hits": n, "poses": len(poses), "ns_per_hit": best, "dict_get_ns": best_dict}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--experiment", default="paper")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--rate", type=int, default=250)
    parser.add_argument("--hits", type=int, default=10_000_000)
    parser.add_argument("--no-profile", action="store_true")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    report: dict[str, Any] = {"settings": vars(args) | {"out": str(args.out)}}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        runs: dict[str, list[dict[str, Any]]] = {"python": [], "auto": []}
        for i in range(args.repeats):
            for footing in ("python", "auto"):
                run = sweep(footing, folder, f"{footing}-{i}", args.experiment)
                runs[footing].append(run)
                print(f"  {footing:6} run {i + 1}: {run['cpu_s']:.2f} s CPU "
                      f"(fixed {run['fixed_cpu_s']:.2f} s)", flush=True)  # fmt: skip
        tables = {f: rows(r[0]["db"]) for f, r in runs.items()}
        n = len(tables["python"])
        agree, total = same_rows(tables["python"], tables["auto"])
        footings = Counter(r["footing"] for r in tables["auto"].values())
        speed = {}
        for footing, rs in runs.items():
            speed[footing] = {
                "gross_missions_per_s": median([n / r["cpu_s"] for r in rs]),
                "net_missions_per_s": median([n / (r["cpu_s"] - r["fixed_cpu_s"]) for r in rs]),
                "cpu_s": median([r["cpu_s"] for r in rs]),
                "fixed_cpu_s": median([r["fixed_cpu_s"] for r in rs]),
            }
        report["missions"] = n
        report["footings_of_auto_run"] = dict(footings)
        report["same_non_timing_columns"] = f"{agree} of {total}"
        report["speed"] = speed
        for kind in ("gross", "net"):
            key = f"{kind}_missions_per_s"
            report[f"speedup_{kind}"] = speed["auto"][key] / speed["python"][key]
        report["rewrite_over_replan"] = {f: rewrite_ratios(t) for f, t in tables.items()}
        report["findings_stdout"] = {f: r[0]["stdout"] for f, r in runs.items()}
        report["profile"] = None if args.no_profile else profile(folder, args.experiment,
                                                                 args.rate)  # fmt: skip
    report["warm_hit"] = warm_hit(args.hits)
    print(f"{n} missions; compiled run footings {dict(footings)}; rows agree {agree}/{total}")
    for footing, s in report["speed"].items():
        print(f"  {footing:6} {s['gross_missions_per_s']:7.1f} missions/s gross "
              f"({s['net_missions_per_s']:.1f} net)")  # fmt: skip
    print(f"compiled / python: {report['speedup_gross']:.2f}x gross, "
          f"{report['speedup_net']:.2f}x net (target >= 10)")  # fmt: skip
    for footing, per_maze in report["rewrite_over_replan"].items():
        for maze, r in per_maze.items():
            verdict = "MET" if r["median_ratio"] <= 0.1 else "NOT MET"
            print(f"  rewrite / replan [{footing}] {maze}: median {r['median_ratio']:.3f} "
                  f"[{r['low']:.3f}, {r['high']:.3f}] over {r['pairs']} pairs "
                  f"(target <= 0.1 compiled: {verdict})")  # fmt: skip
    if report["profile"] is not None:
        p = report["profile"]
        print(f"compiled code: {p['compiled_share']:.1%} of samples (target >= 60%)")
        for name, share in p["top"].items():
            print(f"  {share:6.1%} {name}")
    w = report["warm_hit"]
    print(f"warm hit in the loop: {w['ns_per_hit']:.1f} ns per hit over {w['hits']} hits "
          f"(dict.get {w['dict_get_ns']:.1f} ns; target <= 50)")  # fmt: skip
    print(f"wrote {write_report('mission_loop', report, args.out)}")


if __name__ == "__main__":
    main()
