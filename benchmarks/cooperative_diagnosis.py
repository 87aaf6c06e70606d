"""Cooperative diagnosis (issue 24 item 5): actions to isolate a single wheel fault's class at 1%
odometry noise, the robot alone against the robot watched by two teammates.

Target (issue 24): with two observing teammates, at least 30% fewer actions to isolate than
alone; wrong isolations at most 1%.

Setting, per mission (the four bundled mazes and their routes, every single wheel fault of the
four-wheel robot, the default ``stall`` behaviour, seeds ``0 .. --seeds - 1``):

- the robot's own reading: odometry noise 1% (``ObservationModel(0.01)``, bump switch on),
  stream ``[seed, 24]`` as in the simulator;
- the team: two observers (``Observer``, odometry noise ``--observer-noise``, default 1%, streams
  ``[seed, 24, 1]`` and ``[seed, 24, 2]``, Chebyshev range ``--range`` cells, default 3) that
  follow the robot: observer ``i`` stands where the robot truly was ``i`` commands earlier (the
  start pose before that). A command is observed only when both its start and true end cells are
  in range;
- *passive*: the robot commands the fault-free plan of the route (A*, no faults known), open loop
  (no replanning: this isolates what the readings tell, not how the repair goes); *active*: after
  the first surprise, while no class is isolated, the probes of active diagnosis
  (``isolating_probe`` over the hypotheses still in the running, ``FaultBelief.contenders``; the
  plan's next action when no probe splits them). The probe planner counts the readings the
  probe will get as the belief counts them: the robot's own at 1% noise (a reading one
  perturbation from a rival's prediction only contradicts it, the confirmation rule wants a
  second) and each teammate's that will see the motion (``watchers``, where they stand:
  ``following``). ``--planner blind`` plans as before this counting (every reading exact, the
  robot alone), the peer to compare with in one session;
- the true outcome and the robot's own reading: the mission's ``Simulator`` with the fault hidden
  (it performs ``Domain.effective`` of the command, stops a motion that sweeps a wall at the start:
  a bump, and reads the odometry from its own stream);
- a *surprise*: the robot's own reading differs from the commanded motion's end, or it bumped;
  *actions to isolate*: commands after the surprise command until ``FaultBelief.isolated(0.01)``
  names a class (the definition of the mission rows' ``isolation_actions``), infinite when the
  commands run out first (60 commands at most).

Reported per mode: missions with a surprise, the share isolated, median actions to isolate with
its bootstrap interval (non-isolated missions count as infinite), the reduction ``1 -
median(team) / median(alone)`` and the reduction of the mean over the missions isolated in both
arms, each with its paired bootstrap interval (``selfrepair.stats.paired_cut_interval``: the
pairs resampled together), and the wrong-isolation rate.

Usage: ``python benchmarks/cooperative_diagnosis.py [--seeds N] [--range R] [--noise P]
[--observer-noise P] [--routes N] [--modes passive active] [--planner counting|blind]``
(prints the load at the end; ``--routes N``: the first N routes of each maze).
Results go to ``benchmarks/results/cooperative_diagnosis.json``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from selfrepair.diagnosis import (
    FaultBelief,
    ObservationModel,
    ProbePlanner,
    fault_model,
    isolating_probe,
)
from selfrepair.diagnosis.cooperative import (
    Observer,
    ObserverView,
    SensingRange,
    following,
    observer_streams,
    team_observations,
)
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.stats import Interval, bootstrap_interval, paired_cut_interval
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names

RESULTS = Path(__file__).resolve().parent / "results"
NOISE = 0.01
CONFIDENCE = 0.01
MAX_COMMANDS = 60


def _mission(
    maze: Any, start: Pose, actions: tuple[Any, ...], faults: frozenset[Any], seed: int,
    observers: tuple[Observer, ...], active: bool, noise: float, counting: bool = True,
) -> tuple[float, bool | None] | None:  # fmt: skip
    """Actions to isolate (``inf``: never) and whether the isolated class holds the truth;
    ``None`` when no command surprised the robot."""
    model = fault_model(FOUR_WHEEL)
    truth = model.class_of[model.sets.index(faults)]
    schedule = FaultSchedule.permanent(faults, detection=Detection.HIDDEN)
    sim = Simulator(FOUR_WHEEL, maze, start, schedule, seed,
                    observation=ObservationModel(noise, bumps=True))  # fmt: skip
    belief = FaultBelief(model, maze.free_grid(2))
    planner = ProbePlanner(model, belief.grid, noise=noise if counting else 0.0)
    streams = observer_streams(seed, observers)
    history = [start]
    surprise: int | None = None
    after = 0
    queue = list(actions)
    probing: list[Any] = []
    for step in range(MAX_COMMANDS):
        pose = sim.pose
        if active and surprise is not None and not probing:
            mask = belief.contenders(CONFIDENCE)
            watchers = tuple(zip(observers, following(history, len(observers)), strict=True))
            probe = isolating_probe(belief, pose, mask, planner=planner,
                                    watchers=watchers if counting else ())  # fmt: skip
            probing = list(probe.actions) if probe is not None else []
        if probing:
            action = probing.pop(0)
        elif queue:
            action = queue.pop(0)
        else:
            break
        outcome = sim.advance(action)
        mine = sim.observe(step, action, pose, outcome)
        belief.update(mine)
        end = sim.pose
        behind = following(history, len(observers))
        for seen in team_observations(step, action, pose, end, False, observers, behind, streams,
                                      performed=sim.last_action, domain=FOUR_WHEEL):  # fmt: skip
            belief.update(seen)
        history.append(end)
        if surprise is None:
            if mine.end == FOUR_WHEEL.apply(mine.start, action) and outcome is Outcome.MOVED:
                continue
            surprise = step
        else:
            after += 1
        found = belief.isolated(CONFIDENCE)
        if found is not None:
            return float(after), found == truth
    return None if surprise is None else (math.inf, None)


def run(
    seeds: int, sensing: int, noise: float, observer_noise: float,
    modes: tuple[str, ...] = ("passive", "active"), counting: bool = True,
    routes: int | None = None,
) -> dict[str, Any]:  # fmt: skip
    """Every mission of the module docstring, alone and with two observers, per mode
    (``counting``: the probe planner counts the readings as the belief will, the teammates'
    included; else it plans as if every reading were exact and the robot alone)."""
    team = tuple(Observer(f"t{i}", observer_noise, SensingRange(sensing)) for i in (1, 2))
    wheel_team = tuple(
        Observer(f"t{i}", observer_noise, SensingRange(sensing), ObserverView.WHEELS)
        for i in (1, 2)
    )
    arms = (("alone", ()), ("team", team), ("wheels", wheel_team))
    singles = [s for s in FOUR_WHEEL.fault_sets if len(s) == 1]
    out: dict[str, Any] = {"noise": noise, "observer_noise": observer_noise, "range": sensing,
                           "metric": "chebyshev", "seeds": seeds, "routes_per_maze": routes,
                           "planner": "counting" if counting else "blind"}  # fmt: skip
    for mode in modes:
        counts: dict[str, list[float]] = {label: [] for label, _ in arms}
        wrong = {label: [0, 0] for label, _ in arms}
        missions = 0
        for name in maze_names():
            maze = load_bundled(name)
            for route in bundled_routes(name)[:routes]:
                result = plan(PlanningProblem(maze, route.start, route.goal))
                for faults in singles:
                    for seed in range(seeds):
                        missions += 1
                        pair = []
                        for label, observers in arms:
                            got = _mission(maze, route.start, result.actions, faults, seed,
                                           observers, mode == "active", noise,
                                           counting)  # fmt: skip
                            if got is None:  # no surprise (the same own readings in both arms)
                                break
                            n, right = got
                            pair.append(n)
                            if right is not None:
                                wrong[label][0] += int(not right)
                                wrong[label][1] += 1
                        if len(pair) == len(arms):
                            for (label, _), n in zip(arms, pair, strict=True):
                                counts[label].append(n)
        out[mode] = {
            "pose": _summary(missions, counts["alone"], counts["team"], wrong, "team"),
            "wheels": _summary(missions, counts["alone"], counts["wheels"], wrong, "wheels"),
        }
    return out


def _verdict(reduction: float, low: float, high: float, target: float) -> str:
    """``met`` when the median cut and its whole paired interval reach ``target``, ``not met``
    when the whole interval falls short, else ``inconclusive`` (the median alone says nothing
    the interval does not bear out)."""
    if reduction >= target and low >= target:
        return "met"
    if high < target or not math.isfinite(reduction):
        return "not met"
    return "inconclusive"


def _ends(cut: Interval | None) -> tuple[float, float, float]:
    """Estimate, low and high of a paired cut (``nan`` when undefined)."""
    return (math.nan,) * 3 if cut is None else (cut.estimate, cut.low, cut.high)


def _summary(
    missions: int, alone: list[float], together: list[float], wrong: dict[str, list[int]],
    label: str,
) -> dict[str, Any]:  # fmt: skip
    """The alone arm against the team arm ``label`` (paired: the same missions)."""
    a, t = np.array(alone), np.array(together)
    med_a, med_t = float(np.median(a)), float(np.median(t))
    median_cut = paired_cut_interval(alone, together, "median")
    reduction, low, high = _ends(median_cut)

    def interval(values: np.ndarray) -> list[float] | None:
        finite = [float(v) for v in values if math.isfinite(v)]
        if len(finite) < len(values) / 2:
            return None
        capped = [float(v) if math.isfinite(v) else float(MAX_COMMANDS) for v in values]
        iv = bootstrap_interval(capped)
        return None if iv is None else [iv.low, iv.high]

    both = np.isfinite(a) & np.isfinite(t)  # paired mean cut, missions isolated in both arms
    mean_cut, mean_low, mean_high = _ends(
        paired_cut_interval([float(v) for v in a[both]], [float(v) for v in t[both]], "mean")
    )

    def mean_interval(values: np.ndarray) -> list[float] | None:
        iv = bootstrap_interval([float(v) for v in values if math.isfinite(v)], statistic="mean")
        return None if iv is None else [iv.low, iv.high]

    return {
        "missions": missions,
        "surprised": len(a),
        "isolated_alone": float(np.isfinite(a).mean()),
        "isolated_team": float(np.isfinite(t).mean()),
        "median_alone": med_a, "median_alone_interval": interval(a),
        "median_team": med_t, "median_team_interval": interval(t),
        "mean_isolated_alone": float(a[np.isfinite(a)].mean()),
        "mean_isolated_team": float(t[np.isfinite(t)].mean()),
        "reduction": reduction, "reduction_interval": [float(low), float(high)],
        "target_30pct": _verdict(reduction, float(low), float(high), 0.30),
        "paired_isolated_both": int(both.sum()),
        "mean_reduction_paired": mean_cut, "mean_reduction_paired_interval": [mean_low, mean_high],
        "mean_target_30pct": _verdict(mean_cut, mean_low, mean_high, 0.30),
        "mean_isolated_interval_alone": mean_interval(a),
        "mean_isolated_interval_team": mean_interval(t),
        "wrong_alone": wrong["alone"][0] / max(1, wrong["alone"][1]),
        "wrong_team": wrong[label][0] / max(1, wrong[label][1]),
        "wrong_counts_alone": wrong["alone"], "wrong_counts_team": wrong[label],
        "wrong_target_1pct": "met"
        if max(wrong["alone"][0] / max(1, wrong["alone"][1]),
               wrong[label][0] / max(1, wrong[label][1])) <= 0.01
        else "not met",
    }  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--range", type=int, default=3, dest="sensing")
    parser.add_argument("--noise", type=float, default=NOISE, help="the robot's own odometry")
    parser.add_argument("--observer-noise", type=float, default=None, help="default: --noise")
    parser.add_argument("--routes", type=int, default=None, help="first N routes per maze")
    parser.add_argument("--modes", nargs="+", choices=("passive", "active"),
                        default=["passive", "active"])  # fmt: skip
    parser.add_argument(
        "--planner", choices=("counting", "blind"), default="counting",
        help="blind: the probe planner of before, as if every reading were exact and alone",
    )  # fmt: skip
    args = parser.parse_args(argv)
    observer = args.noise if args.observer_noise is None else args.observer_noise
    counting = args.planner == "counting"
    report = run(args.seeds, args.sensing, args.noise, observer, tuple(args.modes), counting,
                 args.routes)  # fmt: skip
    loadavg = Path("/proc/loadavg")
    report["load"] = loadavg.read_text().split()[:3] if loadavg.exists() else None
    print(json.dumps(report, indent=1))
    RESULTS.mkdir(exist_ok=True)
    suffix = "" if args.noise == NOISE and observer == NOISE else f"-{args.noise:g}-{observer:g}"
    suffix += "" if counting else "-blind"
    suffix += "" if args.routes is None else f"-routes{args.routes}"
    (RESULTS / f"cooperative_diagnosis{suffix}.json").write_text(
        json.dumps(report, indent=1) + "\n"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
