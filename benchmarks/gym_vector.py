"""Robot steps per second of the vector environment (``FaultyMazeVectorEnv``) on one core, against
the single environment (``FaultyMazeEnv``) measured side by side in the same run.

Each figure is the median over ``--repeats`` rounds; in a round every row runs once, in turn, so
a change of machine load hits all of them alike, and the ratio to the single environment is taken
within the round (then the median of the ratios). Actions are uniformly random (drawn
beforehand, seeded); episodes that end are reset inside the timed loop (the vector environment's
next-step autoreset; ``reset()`` for the single one). Two clocks, as in benchmarks/gym_env.py:
steps per second of this process's CPU time (what one core delivers) and of wall-clock time.
Rows:

``single``
    ``FaultyMazeEnv``, four-wheel robot, bundled mazes and routes, one single or double fault per
    episode (permanent, detected at once), no rendering, no guide: benchmarks/gym_env.py's ``raw``.
``vector``
    ``FaultyMazeVectorEnv`` with ``--robots`` robots (default 1,024), the same task; steps/s
    counts robot steps. The issue's targets: at least 1,000,000 steps/s on one core, and at least
    100 times ``single``.
``vector, all fault kinds``
    The same with faults drawn from every persistence (intermittent faults draw at every step)
    and both detection modes, starting within the first 20 steps.
``vector, hidden faults``
    ``vector`` with the faults hidden (``selfrepair/FaultyMazeHidden-v0``: forbidden commands
    perform ``Domain.effective``'s action, walls bump).

The numba kernels are compiled (or loaded from numba's cache) before timing. The process is
pinned to one CPU (``--cpu``, default the first allowed) where the OS allows it. Writes
``benchmarks/results/gym_vector.json``.

Usage: ``python benchmarks/gym_vector.py [--robots N] [--rounds R] [--steps S] [--repeats K]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from _common import write_report
from gym_env import Clock, Rate, pin, steps_per_second
from selfrepair.envs import FaultSpec, FaultyMazeEnv, FaultyMazeVectorEnv
from selfrepair.execution.faults import Detection, Persistence

TARGET_RATE = 1_000_000
TARGET_RATIO = 100.0
ALL_KINDS = FaultSpec(
    persistence=tuple(Persistence), detection=(Detection.NOW, Detection.ON_USE), at=(0, 20)
)


def vector_steps_per_second(vec: FaultyMazeVectorEnv, rounds: int, seed: int) -> Rate:
    """Robot steps per second of ``rounds`` random steps of every robot of ``vec``."""
    count = int(vec.single_action_space.n)
    actions = np.random.default_rng(seed).integers(count, size=(rounds, vec.num_envs))
    vec.reset(seed=seed)
    step = vec.step
    clock = Clock()
    for row in actions:
        step(row)
    return clock.rates(rounds * vec.num_envs)


def measure(repeats: int, rows: dict[str, Callable[[int], Rate]]) -> dict[str, list[Rate]]:
    """Every row's rates, ``repeats`` rounds of all rows in turn."""
    samples: dict[str, list[Rate]] = {name: [] for name in rows}
    for seed in range(repeats):
        for name, run in rows.items():
            samples[name].append(run(seed))
    return samples


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=1024, help="robots of the vector env")
    parser.add_argument("--rounds", type=int, default=500, help="vector steps per run")
    parser.add_argument("--steps", type=int, default=50_000, help="single-env steps per run")
    parser.add_argument("--repeats", type=int, default=5, help="rounds of all rows (median)")
    parser.add_argument("--cpu", type=int, default=None, help="CPU to pin to")
    args = parser.parse_args()
    pinned = pin(args.cpu)
    robots, rounds, steps = args.robots, args.rounds, args.steps
    vec = FaultyMazeVectorEnv(robots)
    mixed = FaultyMazeVectorEnv(robots, faults=ALL_KINDS)
    hidden = FaultyMazeVectorEnv(robots, faults=FaultSpec(detection=(Detection.HIDDEN,)))
    single = FaultyMazeEnv()
    # Warm up: the kernels (compiled or loaded from numba's cache), tables, free grids.
    vector_steps_per_second(vec, 20, 0)
    vector_steps_per_second(mixed, 20, 0)
    vector_steps_per_second(hidden, 20, 0)
    steps_per_second(single, 2_000, 0)
    t0 = time.perf_counter()
    samples = measure(
        args.repeats,
        {
            "single": lambda s: steps_per_second(single, steps, s),
            "vector": lambda s: vector_steps_per_second(vec, rounds, s),
            "vector, all fault kinds": lambda s: vector_steps_per_second(mixed, rounds, s),
            "vector, hidden faults": lambda s: vector_steps_per_second(hidden, rounds, s),
        },
    )
    elapsed = time.perf_counter() - t0
    median = {
        name: (statistics.median(c for c, _ in got), statistics.median(w for _, w in got))
        for name, got in samples.items()
    }
    ratios = {
        name: (
            statistics.median(v[0] / s[0] for v, s in zip(got, samples["single"], strict=True)),
            statistics.median(v[1] / s[1] for v, s in zip(got, samples["single"], strict=True)),
        )
        for name, got in samples.items()
    }
    print(
        f"robot steps per second ({pinned}; median of {args.repeats} rounds; vector: {robots} "
        f"robots x {rounds} steps, single: {steps} steps)"
    )
    print(f"{'':<26}{'CPU time':>13}{'vs single':>11}{'wall clock':>14}{'vs single':>11}")
    for name, (cpu, wall) in median.items():
        cpu_ratio, wall_ratio = ratios[name]
        print(f"{name:<26}{cpu:>11,.0f}/s{cpu_ratio:>10.1f}x{wall:>12,.0f}/s{wall_ratio:>10.1f}x")
    rate, ratio = median["vector"][0], ratios["vector"][0]
    verdict = "met" if rate >= TARGET_RATE else "NOT met"
    print(f"target >= {TARGET_RATE:,} steps/s on one core: {verdict} ({rate:,.0f}/s CPU time)")
    print(
        f"target >= {TARGET_RATIO:.0f}x the single environment: "
        f"{'met' if ratio >= TARGET_RATIO else 'NOT met'} ({ratio:.1f}x per CPU second)"
    )
    print(f"elapsed {elapsed:.1f}s")
    write_report(
        "gym_vector",
        {
            "gymnasium": gym.__version__,
            "pinned": pinned,
            "robots": robots,
            "rounds": rounds,
            "single_steps": steps,
            "repeats": args.repeats,
            "steps_per_cpu_second": {name: cpu for name, (cpu, _) in median.items()},
            "steps_per_wall_second": {name: wall for name, (_, wall) in median.items()},
            "ratio_to_single_cpu": {name: r for name, (r, _) in ratios.items()},
            "ratio_to_single_wall": {name: r for name, (_, r) in ratios.items()},
            "target_rate": TARGET_RATE,
            "target_ratio": TARGET_RATIO,
            "elapsed_s": elapsed,
        },
    )

if __name__ == "__main__":
    main()
