"""Physics steps per second on one core, headless, with the timestep stated.

Rows, each the median over ``--repeats`` runs, per CPU second of this process
(``time.process_time``: what one core delivers, little affected by other processes) and per
wall-clock second:

``mj_step``
    ``mujoco.mj_step`` on the robot in a bundled maze (narrow-long's walls: 100-odd boxes) spinning
    in place with ``FBFB``, ``--steps`` steps in one call: the simulator alone.
``open-loop``
    :meth:`PhysicsWorld.run <selfrepair.physics.world.PhysicsWorld.run>` of ``FFFF`` and ``FBFB``
    in turn, open loop (the control loop's Python per 10 ms update included).
``tracked``
    The same under the tracker (its law evaluated at 100 Hz).
``mission``
    A whole physics mission (wide-short, route r1, replacement, no fault): physics steps of the
    mission per second, the planner and the lattice bookkeeping included.

The issue's target: at least 10,000 physics steps per second per core headless (timestep
2 ms: 5,000 steps are 10 simulated seconds). The process is pinned to one CPU (``--cpu``) where the
OS allows it. Writes ``benchmarks/results/physics.json``.

Usage: ``python benchmarks/physics.py [--steps N] [--repeats R] [--cpu C]``.
"""

from __future__ import annotations

import argparse
import os
import time
from collections.abc import Callable
from fractions import Fraction
from typing import Any

from _common import median, write_report
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.physics.mission import run_physics_mission
from selfrepair.physics.model import DEFAULT_PARAMS
from selfrepair.physics.simulator import lattice_motion
from selfrepair.physics.world import PhysicsWorld
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action
from selfrepair.world.bundled import bundled_routes, load_bundled

TARGET = 10_000


def _rate(run: Callable[[], int], repeats: int) -> tuple[float, float]:
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        steps = run()
        cpu.append(steps / max(time.process_time() - c0, 1e-9))
        wall.append(steps / max(time.perf_counter() - w0, 1e-9))
    return median(cpu), median(wall)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--cpu", type=int, default=None)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        cpu = args.cpu if args.cpu is not None else min(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpu})
    maze = load_bundled("narrow-long")
    free = maze.free_cells()[0]
    world = PhysicsWorld(maze, Pose(free[0], free[1], Heading.N))
    mj = world.mj

    def raw() -> int:
        world.data.ctrl[:] = [10.0, -10.0, 10.0, -10.0]
        mj.mj_step(world.model, world.data, args.steps)
        return args.steps

    actions = [parse_action("FFFF"), parse_action("FBFB")]

    def actions_run(tracked: bool) -> Callable[[], int]:
        def run() -> int:
            done = 0
            while done < args.steps:
                for action in actions:
                    motion = lattice_motion(FOUR_WHEEL, action) if tracked else None
                    commands = tuple(int(w) for w in action.wheels)
                    done += world.run(commands, Fraction(1), motion=motion).steps  # type: ignore[arg-type]
            return done

        return run

    wide = load_bundled("wide-short")
    route = bundled_routes("wide-short")[0]
    spec = MissionSpec(wide, route.start, route.goal, strategy="replacement")

    def mission() -> int:
        return run_physics_mission(spec).outcome.physics_steps

    rows: dict[str, Any] = {}
    for name, run in (
        ("mj_step", raw),
        ("open-loop", actions_run(False)),
        ("tracked", actions_run(True)),
        ("mission", mission),
    ):
        cpu_rate, wall_rate = _rate(run, args.repeats)
        rows[name] = {"steps_per_cpu_s": round(cpu_rate), "steps_per_wall_s": round(wall_rate)}
        print(f"{name:10s} {cpu_rate:12,.0f} steps/CPU-s {wall_rate:12,.0f} steps/wall-s")
    report = {
        "timestep_s": DEFAULT_PARAMS.timestep,
        "control_hz": 1 / (DEFAULT_PARAMS.timestep * DEFAULT_PARAMS.control_every),
        "target_steps_per_s": TARGET,
        "meets_target": all(r["steps_per_cpu_s"] >= TARGET for r in rows.values()),
        "rows": rows,
    }
    path = write_report("physics", report)
    print(f"timestep {DEFAULT_PARAMS.timestep} s; wrote {path}")


if __name__ == "__main__":
    main()
