"""Environment steps per second of ``selfrepair/FaultyMaze-v0`` on one core, against Gymnasium's
own CartPole-v1 and FrozenLake-v1 measured in the same run.

Each figure is the median over ``--repeats`` runs of ``--steps`` steps with uniformly random actions
(drawn beforehand, seeded); episodes that end are reset inside the timed loop, so resets count.
Two clocks: steps per second of this process's CPU time (``time.process_time``: what one core
delivers, little affected by other processes on a shared machine) and of wall-clock time. The
rows are measured in turn, round after round, so a change of machine load hits all of them alike.
Rows:

``raw``
    :class:`~selfrepair.envs.env.FaultyMazeEnv` itself, four-wheel robot, bundled mazes and routes,
    one single or double fault per episode, no rendering, no guide. The issue's target: at least
    20,000 steps/s.
``make``
    The same through ``gymnasium.make`` (Gymnasium adds its order-enforcing and passive-checker
    wrappers).
``three-action``
    ``raw`` for the three-action robot.
``sync-vector``
    ``gymnasium.vector.SyncVectorEnv`` of 4 environments; steps/s counts sub-environment steps.
``guided-replacement``
    Steps of the replacement baseline policy with ``guide=True`` (the planner's work per episode and
    the hints in ``info`` included): what imitation learning from the guide costs.
``CartPole-v1``, ``FrozenLake-v1``, ``CartPole sync-vector``
    Gymnasium's environments through ``gymnasium.make`` (and 4 CartPoles in a SyncVectorEnv), the
    peers.

The process is pinned to one CPU (``--cpu``, default the first allowed) where the OS allows it.
Writes ``benchmarks/results/gym_env.json``.

Usage: ``python benchmarks/gym_env.py [--steps N] [--repeats R] [--cpu C]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from selfrepair.envs import ENV_ID, FaultyMazeEnv
from selfrepair.envs.evaluate import run_episode
from selfrepair.envs.policies import make_policy

ROOT = Path(__file__).resolve().parents[1]
TARGET = 20_000


Rate = tuple[float, float]
"""Steps per CPU second and per wall-clock second."""


class Clock:
    """Both clocks, started on creation."""

    def __init__(self) -> None:
        self.cpu, self.wall = time.process_time(), time.perf_counter()

    def rates(self, steps: int) -> Rate:
        """``steps`` per CPU second and per wall second since creation."""
        cpu, wall = time.process_time() - self.cpu, time.perf_counter() - self.wall
        return steps / cpu, steps / wall


def steps_per_second(env: Any, steps: int, seed: int) -> Rate:
    """Random steps of a single environment (resets included)."""
    count = int(env.action_space.n)
    actions = np.random.default_rng(seed).integers(count, size=steps).tolist()
    env.reset(seed=seed)
    step, reset = env.step, env.reset
    clock = Clock()
    for action in actions:
        _, _, terminated, truncated, _ = step(action)
        if terminated or truncated:
            reset()
    return clock.rates(steps)


def vector_steps_per_second(env_id: str, num_envs: int, steps: int, seed: int) -> Rate:
    """Sub-environment steps per second of a SyncVectorEnv (autoreset inside)."""
    vec = gym.vector.SyncVectorEnv([lambda: gym.make(env_id) for _ in range(num_envs)])
    vec.reset(seed=seed)
    rounds = steps // num_envs
    count = int(vec.single_action_space.n)
    actions = np.random.default_rng(seed).integers(count, size=(rounds, num_envs))
    clock = Clock()
    for row in actions:
        vec.step(row)
    rates = clock.rates(rounds * num_envs)
    vec.close()
    return rates


def guided_steps_per_second(steps: int, seed: int) -> Rate:
    """Steps of the replacement policy, guide on, whole episodes until ``steps`` are done."""
    env = FaultyMazeEnv(guide=True)
    policy = make_policy("replacement")
    done = 0
    episode = seed
    clock = Clock()
    while done < steps:
        done += run_episode(env, policy, episode).steps
        episode += 1
    return clock.rates(done)


def measure(repeats: int, rows: dict[str, Callable[[int], Rate]]) -> dict[str, Rate]:
    """Per row, the median of each clock's rate over ``repeats`` rounds (rows in turn)."""
    samples: dict[str, list[Rate]] = {name: [] for name in rows}
    for seed in range(repeats):
        for name, run in rows.items():
            samples[name].append(run(seed))
    return {
        name: (
            statistics.median(cpu for cpu, _ in got),
            statistics.median(wall for _, wall in got),
        )
        for name, got in samples.items()
    }


def pin(cpu: int | None) -> str:
    """Pin this process to one CPU where the OS allows; returns what was done."""
    if not hasattr(os, "sched_setaffinity"):
        return "not pinned (no sched_setaffinity)"
    allowed = sorted(os.sched_getaffinity(0))
    chosen = allowed[0] if cpu is None else cpu
    os.sched_setaffinity(0, {chosen})
    return f"pinned to CPU {chosen}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000, help="steps per run")
    parser.add_argument("--repeats", type=int, default=5, help="runs per row (median)")
    parser.add_argument("--cpu", type=int, default=None, help="CPU to pin to")
    args = parser.parse_args()
    pinned = pin(args.cpu)
    steps, repeats = args.steps, args.repeats
    # Warm up: tables, free grids, the planner's compiled kernels, Gymnasium's registry.
    guided_steps_per_second(200, 0)
    steps_per_second(FaultyMazeEnv(), 2_000, 0)
    t0 = time.perf_counter()
    rows = measure(
        repeats,
        {
            "raw": lambda s: steps_per_second(FaultyMazeEnv(), steps, s),
            "make": lambda s: steps_per_second(gym.make(ENV_ID), steps, s),
            "three-action": lambda s: steps_per_second(
                FaultyMazeEnv(domain="three-action"), steps, s
            ),
            "sync-vector": lambda s: vector_steps_per_second(ENV_ID, 4, steps, s),
            "guided-replacement": lambda s: guided_steps_per_second(steps // 5, s),
            "CartPole-v1": lambda s: steps_per_second(gym.make("CartPole-v1"), steps, s),
            "FrozenLake-v1": lambda s: steps_per_second(gym.make("FrozenLake-v1"), steps, s),
            "CartPole sync-vector": lambda s: vector_steps_per_second("CartPole-v1", 4, steps, s),
        },
    )
    elapsed = time.perf_counter() - t0
    print(f"selfrepair/FaultyMaze-v0 steps per second ({pinned}; median of {repeats} x {steps})")
    print(f"{'':<20}{'CPU time':>12}{'vs CartPole':>13}{'wall clock':>13}{'vs CartPole':>13}")
    cart_cpu, cart_wall = rows["CartPole-v1"]
    for name, (cpu, wall) in rows.items():
        print(
            f"{name:<20}{cpu:>10,.0f}/s{cpu / cart_cpu:>12.2f}x"
            f"{wall:>11,.0f}/s{wall / cart_wall:>12.2f}x"
        )
    raw_cpu, raw_wall = rows["raw"]
    verdict = "met" if raw_cpu >= TARGET else "NOT met"
    print(
        f"target raw >= {TARGET:,}/s on one core: {verdict} "
        f"({raw_cpu:,.0f}/s per CPU second, {raw_wall:,.0f}/s wall clock)"
    )
    print(f"elapsed {elapsed:.1f}s")
    out = ROOT / "benchmarks/results/gym_env.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "benchmark": "gym_env",
                "python": platform.python_version(),
                "machine": platform.machine(),
                "gymnasium": gym.__version__,
                "pinned": pinned,
                "steps": steps,
                "repeats": repeats,
                "steps_per_cpu_second": {name: cpu for name, (cpu, _) in rows.items()},
                "steps_per_wall_second": {name: wall for name, (_, wall) in rows.items()},
                "target": TARGET,
                "elapsed_s": elapsed,
            },
            indent=2,
        )
        + "\n",
        encoding="utf-8",
    )


if __name__ == "__main__":
    main()
