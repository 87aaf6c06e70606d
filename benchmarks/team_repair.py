"""Team repair latency: team replacement versus full re-allocation, measured in one run.

The bundled ``three-robots`` scenario (three robots, six items on wide-short; robot r2 is
immobilised three ticks after its first pick, so while it carries an item) runs with every team
strategy, ``--repeats`` times each after one warm-up run. The repair latency is what the engine
records for the first incident: from the incident until every robot whose plan changed has its
next drive placed in time (``time.perf_counter_ns``). Prints, per strategy, the median and the
spread of that latency, the items delivered, the makespan against the fault-free team plan, the
teammates disturbed and the drives planned inside the repair; then the ratio of the medians,
of the wall-clock latency and of the processor time of the same stretch (which other load on a
shared machine does not inflate).
Writes the figures to ``benchmarks/results/team_repair.json``.

Target (from the issue): team replacement delivers every task and replies faster than full
re-allocation (ratio of medians above 1).

Usage: ``python benchmarks/team_repair.py [--repeats N] [--scenario NAME_OR_FILE]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
from pathlib import Path

from selfrepair.team.engine import run_team
from selfrepair.team.result import TeamOptions
from selfrepair.team.scenario import resolve_scenario

VARIANTS = (
    ("team-replacement", "handwritten"),
    ("team-replacement", "generated"),
    ("reallocation", "handwritten"),
    ("alone", "handwritten"),
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21)
    parser.add_argument("--scenario", default="three-robots")
    args = parser.parse_args()
    scenario = resolve_scenario(args.scenario)
    baseline = run_team(scenario.without_faults(), TeamOptions(strategy="alone")).makespan
    print(f"{scenario.name}: fault-free makespan {baseline} ticks; {args.repeats} runs each")
    figures: dict[str, dict[str, object]] = {}
    for strategy, table in VARIANTS:
        options = TeamOptions(strategy=strategy, table=table)
        run_team(scenario, options)  # warm-up: kernels, lattices, tables stay out of the timings
        runs = [run_team(scenario, options) for _ in range(args.repeats)]
        last = runs[-1]
        first = [r.repairs[0].latency_ns / 1000 for r in runs if r.repairs]
        cpu = [r.repairs[0].cpu_ns / 1000 for r in runs if r.repairs]
        repair = last.repairs[0] if last.repairs else None
        figures[options.label] = {
            "delivered": len(last.delivered),
            "tasks": len(scenario.tasks),
            "makespan": float(last.makespan),
            "makespan_ratio": float(last.makespan / baseline) if last.all_delivered else None,
            "first_repair_median_us": statistics.median(first) if first else None,
            "first_repair_min_us": min(first) if first else None,
            "first_repair_max_us": max(first) if first else None,
            "first_repair_cpu_median_us": statistics.median(cpu) if cpu else None,
            "outcome": None
            if repair is None
            else f"{repair.outcome} by {repair.candidate or repair.source}",
            "disturbed": None if repair is None else len(repair.disturbed),
            "plans_in_repair": None if repair is None else repair.plans,
        }
        f = figures[options.label]
        median = f["first_repair_median_us"]
        print(
            f"{options.label:32s} delivered {f['delivered']}/{f['tasks']}"
            f"  makespan {f['makespan']:g}"
            f"  first repair median {median if median is None else round(median):>7} µs"
            f" (min {f['first_repair_min_us'] and round(f['first_repair_min_us'])},"
            f" max {f['first_repair_max_us'] and round(f['first_repair_max_us'])};"
            f" CPU median {round(f['first_repair_cpu_median_us'] or 0)})"
            f"  disturbed {f['disturbed']}  plannings {f['plans_in_repair']}  {f['outcome']}"
        )
    team = figures["team-replacement[handwritten]"]["first_repair_median_us"]
    realloc = figures["reallocation"]["first_repair_median_us"]
    assert isinstance(team, float | int) and isinstance(realloc, float | int)
    print(f"re-allocation / team replacement, median first-repair latency: {realloc / team:.1f}x")
    cpu_team = figures["team-replacement[handwritten]"]["first_repair_cpu_median_us"]
    cpu_realloc = figures["reallocation"]["first_repair_cpu_median_us"]
    assert isinstance(cpu_team, float | int) and isinstance(cpu_realloc, float | int)
    ratio = cpu_realloc / cpu_team
    print(f"re-allocation / team replacement, median first-repair CPU time: {ratio:.1f}x")
    out = Path(__file__).parent / "results" / "team_repair.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(
        json.dumps(
            {"machine": platform.platform(), "repeats": args.repeats, "figures": figures,
             "ratio_median": realloc / team, "ratio_cpu_median": cpu_realloc / cpu_team},
            indent=2,
        )
        + "\n",
        encoding="utf-8",
    )  # fmt: skip
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
