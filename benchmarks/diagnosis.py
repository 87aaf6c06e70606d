"""Diagnosis from observed motion (issue 24): the cost of a belief update, and what the
strategies for hidden faults achieve on the paper's mazes.

1. **Belief update** (target: at most 5 µs per observation with the four-wheel robot's 78 fault
   sets, 79 hypotheses with "none"): ``FaultBelief.update`` timed with ``timeit`` on a warm
   belief (its consistency sets computed), median of ``--repeats`` timings of ``--calls`` calls,
   for an exact and a noisy (1%) reading, in open space and next to a wall (where the motions
   the walls stop are tested in the grid), each also as a teammate's wheel-view reading
   (``wheels``: the pose and the actuators of the action performed, ``Observation.wheels``).
2. **Missions**: the four bundled mazes and their 16 routes, every single and double wheel fault
   (78 fault sets; ``--quick``: the paper's 12) present from the first step and hidden
   (detection ``hidden``, the default ``stall`` behaviour, bump switch on), odometry noise 0, 1%
   and 5%, for every strategy (``oracle`` once: noise does not reach it). Per strategy and noise:

   - *isolation*: among missions with a surprise, the share whose class was isolated within 3
     executed commands after the first surprise (single faults) or within 5 (double faults);
     the issue's targets, with active diagnosis: 95% and 90%;
   - *wrong isolations*: isolated classes that do not hold the true fault set (target at 1%
     noise: at most 1%);
   - *reach*: missions reaching the goal among those the oracle reaches (targets: 100% for the
     diagnosing strategies with exact observations, 90% for trial and error);
   - *ticks*: the median over those missions of the mission's ticks over the oracle's ticks on
     the same mission (target: at most 1.25), and the wall contacts (bumps) per mission.

Results go to ``benchmarks/results/diagnosis.json``.

Usage: ``python benchmarks/diagnosis.py [--quick] [--jobs N] [--calls N] [--repeats N]
[--strategies NAME ...] [--noises P ...] [--no-missions]``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import timeit
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

from selfrepair.diagnosis import FaultBelief, Observation, ObservationModel, fault_model
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.faultsets import PAPER_FAULT_SETS
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyName
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names
from selfrepair.world.maze import parse_maze

RESULTS = Path(__file__).resolve().parent / "results"
DIAGNOSING = (
    StrategyName.DIAGNOSE,
    StrategyName.CONFORMANT,
    StrategyName.ACTIVE_DIAGNOSIS,
    StrategyName.TRIAL_AND_ERROR,
)
NOISES = (0.0, 0.01, 0.05)
WITHIN = {1: 3, 2: 5}
"""Commands after the first surprise within which a single (double) fault counts as isolated."""


def update_cost(calls: int, repeats: int) -> dict[str, float]:
    """Median microseconds per ``FaultBelief.update`` (see the module docstring)."""
    model = fault_model(FOUR_WHEEL)
    assert model.size == 79
    room = parse_maze("\n".join(["." * 9] * 9) + "\n", name="open")
    walled = parse_maze("#####\n##.##\n##.##\n##.##\n#####\n", name="corridor")
    out: dict[str, float] = {}
    faults = FOUR_WHEEL.parse_faults("FL:F")
    action = parse_action("FFFF")
    for where, maze, start in (
        ("open", room, Pose(4, 4, Heading.N)),
        ("wall", walled, Pose(2, 3, Heading.N)),
    ):
        performed = FOUR_WHEEL.effective(action, faults)
        end = FOUR_WHEEL.apply(start, performed)
        if not maze.free_grid(2).all_free(FOUR_WHEEL.footprint(start, performed)):
            end = start
        for noise, wheels in ((0.0, False), (0.01, False), (0.0, True), (0.01, True)):
            belief = FaultBelief(model, maze.free_grid(2))
            observation = Observation(
                0, action, start, end, end == start, False, noise,
                source="t1" if wheels else "self", wheels=performed if wheels else None,
            )  # fmt: skip
            belief.update(observation)  # warm: the consistency set is kept
            times = timeit.repeat(
                lambda b=belief, o=observation: b.update(o), number=calls, repeat=repeats
            )
            label = f"{where}, noise {noise:g}" + (", wheels" if wheels else "")
            out[label] = statistics.median(times) / calls * 1e6
    return out


def _one(job: tuple[str, int, str, str, float]) -> dict[str, Any]:
    maze_name, route_index, faults, strategy, noise = job
    route = bundled_routes(maze_name)[route_index]
    schedule = FaultSchedule.permanent(FOUR_WHEEL.parse_faults(faults), detection=Detection.HIDDEN)
    spec = MissionSpec(
        load_bundled(maze_name), route.start, route.goal, schedule=schedule, strategy=strategy,
        seed=route_index, observation=ObservationModel(noise, bumps=True),
    )  # fmt: skip
    row = mission_row(run_mission(spec))
    keep = ("reached", "ticks_float", "bumps", "surprise_step", "isolation_actions",
            "isolated_right", "probes")  # fmt: skip
    return {"maze": maze_name, "route": route_index, "faults": faults, "strategy": strategy,
            "noise": noise, **{k: row[k] for k in keep}}  # fmt: skip


def missions(
    quick: bool,
    jobs: int,
    strategies: tuple[StrategyName, ...] = DIAGNOSING,
    noises: tuple[float, ...] = NOISES,
) -> list[dict[str, Any]]:
    """Run every mission of the module docstring's part 2 (``strategies`` and ``noises``: a
    subset; the oracle always runs, reach and ticks are against it)."""
    sets = (
        list(PAPER_FAULT_SETS)
        if quick
        else [FOUR_WHEEL.format_faults(s) for s in FOUR_WHEEL.fault_sets]
    )
    work = []
    for maze_name in maze_names():
        for route_index in range(len(bundled_routes(maze_name))):
            for faults in sets:
                work.append((maze_name, route_index, faults, StrategyName.ORACLE.value, 0.0))
                for strategy in strategies:
                    for noise in noises:
                        work.append((maze_name, route_index, faults, strategy.value, noise))
    if jobs > 1:
        with ProcessPoolExecutor(jobs) as pool:
            return list(pool.map(_one, work, chunksize=16))
    return [_one(job) for job in work]


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The figures of the module docstring's part 2, per strategy and noise."""
    oracle = {(r["maze"], r["route"], r["faults"]): r for r in rows if r["strategy"] == "oracle"}
    groups: dict[tuple[str, float], list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        if r["strategy"] != "oracle":
            groups[(r["strategy"], r["noise"])].append(r)
    out: dict[str, Any] = {
        "oracle": {
            "missions": len(oracle),
            "reached": sum(r["reached"] for r in oracle.values()),
            "bumps_per_mission": statistics.fmean(r["bumps"] for r in oracle.values()),
        }
    }
    for (strategy, noise), members in sorted(groups.items()):
        entry: dict[str, Any] = {}
        for size in (1, 2):
            surprised = [
                r for r in members
                if r["surprise_step"] is not None and r["faults"].count(",") + 1 == size
            ]  # fmt: skip
            within = [
                r for r in surprised
                if r["isolation_actions"] is not None and r["isolation_actions"] <= WITHIN[size]
            ]  # fmt: skip
            isolated = [r for r in surprised if r["isolated_right"] is not None]
            wrong = [r for r in isolated if r["isolated_right"] == 0]
            share = len(within) / len(surprised) if surprised else None
            entry[f"{'single' if size == 1 else 'double'}"] = {
                "surprised": len(surprised),
                f"isolated_within_{WITHIN[size]}": share,
                "isolated_ever": len(isolated) / len(surprised) if surprised else None,
                "wrong_isolations": len(wrong) / len(isolated) if isolated else None,
            }
        paired = [(r, oracle[(r["maze"], r["route"], r["faults"])]) for r in members]
        base = [(r, o) for r, o in paired if o["reached"]]
        reached = [(r, o) for r, o in base if r["reached"]]
        entry["reach_of_oracle"] = len(reached) / len(base) if base else None
        entry["median_ticks_over_oracle"] = (
            statistics.median(r["ticks_float"] / o["ticks_float"] for r, o in reached)
            if reached
            else None
        )
        entry["bumps_per_mission"] = statistics.fmean(r["bumps"] for r in members)
        entry["probes_per_mission"] = statistics.fmean(r["probes"] or 0 for r in members)
        out[f"{strategy} noise {noise:g}"] = entry
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the paper's 12 fault sets only")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--calls", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--no-missions", action="store_true", help="the update cost only")
    parser.add_argument(
        "--strategies", nargs="+", default=[s.value for s in DIAGNOSING], help="a subset"
    )
    parser.add_argument("--noises", nargs="+", type=float, default=list(NOISES), help="a subset")
    args = parser.parse_args(argv)
    cost = update_cost(args.calls, args.repeats)
    print("belief update, µs per observation (79 hypotheses; target 5):")
    for what, us in cost.items():
        print(f"  {what:<28} {us:6.2f}  {'met' if us <= 5 else 'NOT MET'}")
    report: dict[str, Any] = {"update_us": cost}
    if not args.no_missions:
        chosen = tuple(StrategyName(s) for s in args.strategies)
        rows = missions(args.quick, args.jobs, chosen, tuple(args.noises))
        summary = summarise(rows)
        report["missions"] = len(rows)
        report["summary"] = summary
        print(json.dumps(summary, indent=1))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "diagnosis.json").write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
