"""LPG-adapt repair time on the bundled mazes, next to plain LPG and the lattice planner.

For each bundled maze and route, and each of a few single faults, the robot follows its healthy
lattice plan up to the first step the fault forbids; there the fault becomes known and the rest of
the plan has to be repaired. Three repairs of the same situation are timed:

* ``adapt``: :func:`selfrepair.baselines.lpg.lpg_adapt_repair` with the remaining plan;
* ``lpg``: :func:`selfrepair.baselines.lpg.lpg_plan`, LPG from scratch (its local search);
* ``lpg-bf``: the same with ``-onlybestfirst`` (LPG's best-first search, no local search);
* ``A*``: :func:`selfrepair.search.lattice.plan`, the exact lattice replan (the library's own).

For the LPG calls the table shows the status, the LPG process time (``lpg s``, as UP measured it)
and the whole call (``wall s``: export, UP problem, PDDL writing, LPG, parsing, re-simulation);
for every solved repair, its duration over the optimal one (``/opt``). The first LPG call of a
process also pays about 1 s of imports (unified-planning, scipy); a warm-up call on a tiny maze
takes it out of the figures. LPG is randomised: ``--seed`` is passed to it and printed.

Usage: ``python benchmarks/lpg.py [--time-limit S] [--routes N] [--faults FL:F,FR:B,...]``.
Writes the rows to ``benchmarks/results/lpg.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from dataclasses import replace
from pathlib import Path

from selfrepair.baselines.lpg import LpgResult, lpg_adapt_repair, lpg_available, lpg_plan
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names
from selfrepair.world.maze import parse_maze

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_FAULTS = "FL:F,FR:B,RL:S,RR:F"
BEST_FIRST = {"-onlybestfirst": ""}
VARIANTS = ("adapt", "lpg", "lpg-bf")


def situation(
    healthy: PlanningProblem, fault: four_wheel.Fault
) -> tuple[PlanningProblem, tuple[four_wheel.Action, ...], int] | None:
    """Where the fault bites: the problem from the pose before the first forbidden step (with the
    fault known), the rest of the plan, and the step index; ``None`` if no step is forbidden."""
    result = plan(healthy)
    faults = frozenset({fault})
    for index, action in enumerate(result.actions):
        if not four_wheel.available(action, faults):
            now = replace(healthy, start=result.poses[index], faults=faults)
            return now, result.actions[index:], index
    return None


def row(
    maze: str, route: str, fault: four_wheel.Fault, time_limit: float, seed: int
) -> dict[str, object] | None:
    routes = {r.name: r for r in bundled_routes(maze)}
    healthy = PlanningProblem(load_bundled(maze), routes[route].start, routes[route].goal)
    found = situation(healthy, fault)
    if found is None:
        return None
    now, remaining, index = found
    t0 = time.perf_counter_ns()
    optimal = plan(now)
    lattice_s = (time.perf_counter_ns() - t0) / 1e9
    adapt = lpg_adapt_repair(now, remaining, time_limit_s=time_limit, seed=seed)
    scratch = lpg_plan(now, time_limit_s=time_limit, seed=seed)
    best_first = lpg_plan(now, time_limit_s=time_limit, seed=seed, options=BEST_FIRST)

    def figures(result: LpgResult) -> dict[str, object]:
        solved = result.status.value == "solved"
        return {
            "status": result.status.value,
            "lpg_s": result.lpg_time_s,
            "wall_s": result.wall_time_ns / 1e9,
            "over_optimal": float(result.duration / optimal.duration) if solved else None,
            "message": result.message,
        }

    return {
        "maze": maze,
        "route": route,
        "fault": str(fault),
        "step": index,
        "remaining": len(remaining),
        "forbidden": sum(not four_wheel.available(a, now.faults) for a in remaining),
        "lattice_s": lattice_s,
        "optimal_ticks": str(optimal.duration),
        "adapt": figures(adapt),
        "lpg": figures(scratch),
        "lpg-bf": figures(best_first),
    }


def show(r: dict[str, object]) -> str:
    def cell(f: dict[str, object]) -> str:
        lpg_s = "-" if f["lpg_s"] is None else f"{f['lpg_s']:.2f}"
        over = "" if f["over_optimal"] is None else f" x{f['over_optimal']:.2f}"
        return f"{f['status']:>8} {lpg_s:>6} {f['wall_s']:>6.2f}{over:<6}"

    cells = "  ".join(cell(r[v]) for v in VARIANTS)  # type: ignore[arg-type]
    return (
        f"{r['maze']:<13}{r['route']:<4}{r['fault']:<6}{r['step']:>4}{r['remaining']:>5}"
        f"{r['forbidden']:>4}  {cells}  {r['lattice_s'] * 1e3:>8.2f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--time-limit", type=float, default=20.0, help="seconds per LPG call")
    parser.add_argument("--routes", type=int, default=2, help="routes per maze (of 4)")
    parser.add_argument("--faults", default=DEFAULT_FAULTS, help="single faults to inject")
    parser.add_argument("--seed", type=int, default=0, help="LPG's seed")
    args = parser.parse_args()
    if not lpg_available():
        raise SystemExit("needs the pddl extra: pip install 'selfrepair[pddl]'")
    faults = [four_wheel.parse_fault(f) for f in args.faults.split(",")]

    t0 = time.perf_counter()
    warm = PlanningProblem(parse_maze("...\n...\n"), Pose(0, 0, Heading.E), (2, 1))
    lpg_plan(warm, time_limit_s=5)
    print(f"warm-up (imports and first LPG call): {time.perf_counter() - t0:.2f} s")
    print(f"time limit {args.time_limit:g} s per LPG call, seed {args.seed}")
    heads = "  ".join(f"{v:>8} {'lpg s':>6} {'wall s':>6}{'':<6}" for v in VARIANTS)
    print(
        f"{'maze':<13}{'rt':<4}{'fault':<6}{'step':>4}{'rest':>5}{'bad':>4}  {heads}  {'A* ms':>8}"
    )
    rows = []
    for maze in maze_names():
        for route in [r.name for r in bundled_routes(maze)][: args.routes]:
            for fault in faults:
                r = row(maze, route, fault, args.time_limit, args.seed)
                if r is not None:
                    rows.append(r)
                    print(show(r), flush=True)
    summarise(rows)
    out = ROOT / "benchmarks/results/lpg.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    meta = {"python": platform.python_version(), "machine": platform.machine()}
    out.write_text(json.dumps({"meta": meta, "args": vars(args), "rows": rows}, indent=2) + "\n")
    print(f"wrote {out}")


def summarise(rows: list[dict[str, object]]) -> None:
    """Per maze and variant: solved out of tried, median LPG time of the solved ones, and that
    median over the lattice planner's median replan time measured on the same situations."""
    print()
    heads = "  ".join(f"{v + ' ok':>9} {'med s':>6} {'/A*':>7}" for v in VARIANTS)
    print(f"{'maze':<13}{'n':>3}  {heads}  {'A* med ms':>9}")
    for maze in maze_names():
        mine = [r for r in rows if r["maze"] == maze]
        if not mine:
            continue
        lattice = statistics.median(r["lattice_s"] for r in mine)  # type: ignore[misc]
        parts = []
        for variant in VARIANTS:
            ok = [r[variant] for r in mine if r[variant]["status"] == "solved"]  # type: ignore[index]
            if ok:
                med = statistics.median(f["lpg_s"] for f in ok)
                parts.append(f"{len(ok):>9} {med:>6.2f} {med / lattice:>6,.0f}x")
            else:
                parts.append(f"{0:>9} {'-':>6} {'-':>7}")
        print(f"{maze:<13}{len(mine):>3}  {'  '.join(parts)}  {lattice * 1e3:>9.2f}")


if __name__ == "__main__":
    main()
