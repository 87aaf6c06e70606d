"""Why physics missions touch walls: every contact episode, and turns in place after other actions.

Two measurements (deterministic; MuJoCo, the default robot and tracker):

``missions``
    The physics experiment's missions in one bundled maze (``--maze``, its four routes, the 12
    paper fault sets, one ``--strategy``, robot model ``--robot``). For every action during which
    the robot touched a wall: the action's wheel commands, the 10 ms control updates with a
    contact, the geoms that touched, and how far the robot stood from its cell centre (cm) and
    from its lattice heading (degrees) when the action began. Then, per action, its end error
    (cells) over every time a mission ran it.
``sequence``
    Every turn in place that ``selfrepair physics fidelity`` confirms (from rest, within 0.05
    cells and 3 degrees), run on an open floor from the origin after each of a few other actions
    (``FFFF``, ``BBBB``, ``SFFS``, ``FBFB``, ``BFBF`` and itself, as ``selfrepair physics
    fidelity --in-sequence`` does for every action): its end error there. Fidelity measures an
    action from rest; in a mission it starts where the last one left the robot and its wheels.

``response``
    What a controller for a turn on a diagonal pair would be built from: the pair's two wheels
    driven at ``m + a/2`` and ``m - a/2`` wheel speeds (signs of a clockwise turn: the left
    wheel forward, the right one backward; the other two braked), the wheel ramps as in
    :class:`~selfrepair.physics.world.PhysicsWorld`, from rest at the origin of an open floor
    for 2 s: the robot centre's mean velocity (cells/s, in the robot's frame: forward, right)
    from 0.6 s on, per unit of ``a = m / 4``, for the front-left/rear-right and the
    rear-left/front-right pair and mean wheel speeds ``m`` from 0.5 to 2.5.

Writes ``benchmarks/results/physics_contacts.json``.

Usage: ``python benchmarks/physics_contacts.py [--maze M] [--strategy S] [--robot R]
[--workers N] [--no-missions] [--no-sequence] [--no-response]``.
"""

from __future__ import annotations

import argparse
import math
import statistics
from collections import Counter, defaultdict
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from _common import write_report
from selfrepair.execution.executor import run_mission
from selfrepair.experiment.faultsets import PAPER_FAULT_SETS
from selfrepair.experiment.physics import physics_mission_spec
from selfrepair.geometry import Pose
from selfrepair.physics.fidelity import PREDECESSORS, measure, measure_in_sequence
from selfrepair.physics.model import ORIGIN
from selfrepair.physics.simulator import PhysicsSimulator
from selfrepair.physics.tracker import ContinuousPose, wrap
from selfrepair.physics.world import PhysicsWorld, lattice_pose
from selfrepair.robots.four_wheel import parse_action
from selfrepair.world.bundled import bundled_routes
from selfrepair.world.maze import Maze


def _offset(pose: ContinuousPose, cell: float) -> tuple[float, float]:
    """How far ``pose`` is from the nearest cell centre (cm) and lattice heading (degrees)."""
    dx, dy = pose.x - round(pose.x), pose.y - round(pose.y)
    deg = math.degrees(pose.yaw)
    return math.hypot(dx, dy) * cell * 100, abs((deg + 45) % 90 - 45)


def _signed(pose: ContinuousPose, lattice: Pose, cell: float) -> tuple[float, float, float]:
    """``pose`` against the lattice pose ``lattice``: along and across its heading (cm, forward
    and right positive) and in heading (degrees, clockwise positive)."""
    t = lattice_pose(lattice)
    dx, dy = pose.x - t.x, pose.y - t.y
    c, s = math.cos(t.yaw), math.sin(t.yaw)
    along, right = c * dx + s * dy, s * dx - c * dy
    return along * cell * 100, right * cell * 100, -math.degrees(wrap(pose.yaw - t.yaw))


def _surroundings(maze: Maze, pose: Pose) -> tuple[str, str]:
    """Which of the front, right, back and left neighbours of ``pose`` are walls (``FRBL``
    letters), and what that makes the cell: ``corridor`` (walls on two opposite sides: a
    one-cell corridor), ``corner`` (two adjacent sides), ``dead end`` (three), ``side`` (one),
    ``open`` (none)."""
    fx, fy = pose.heading.vector
    rx, ry = pose.heading.right
    around = ((fx, fy, "F"), (rx, ry, "R"), (-fx, -fy, "B"), (-rx, -ry, "L"))
    walls = "".join(n for dx, dy, n in around if not maze.is_free(pose.x + dx, pose.y + dy))
    kinds = {0: "open", 1: "side", 3: "dead end", 4: "closed"}
    kind = kinds.get(len(walls)) or ("corridor" if walls in ("FB", "RL") else "corner")
    return walls, kind


def mission_contacts(job: tuple[str, int, str, str, str]) -> dict[str, Any]:
    """One mission in physics with every contact episode (see the module docstring)."""
    maze, route, faults, strategy, robot = job
    spec = physics_mission_spec(maze, route, faults, strategy, robot)
    world = PhysicsWorld(spec.maze, spec.start)
    mj = world.mj
    names = [
        mj.mj_id2name(world.model, mj.mjtObj.mjOBJ_GEOM, i) or "" for i in range(world.model.ngeom)
    ]
    walls = {i for i, n in enumerate(names) if n.startswith("wall")}
    current: list[Any] = [None]
    episodes: dict[int, dict[str, Any]] = {}

    def observe(w: PhysicsWorld) -> None:
        touched = set()
        for k in range(w.data.ncon):
            g1, g2 = int(w.data.contact.geom1[k]), int(w.data.contact.geom2[k])
            if g1 in walls or g2 in walls:
                touched.add(names[g2] if g1 in walls else names[g1])
        if touched and current[0] is not None:
            index, start, lattice, speed = current[0]
            e = episodes.setdefault(index, {
                "updates": 0, "geoms": set(), "start": start, "lattice": lattice, "speed": speed,
            })  # fmt: skip
            e["updates"] += 1
            e["geoms"] |= touched

    world.observer = observe
    sims: list[PhysicsSimulator] = []

    def make(s: Any) -> PhysicsSimulator:
        sim = PhysicsSimulator(
            s.domain, s.maze, s.start, s.schedule, s.seed, world=s.world,
            behaviour=s.behaviour, physics=world,
        )  # fmt: skip
        advance = sim.advance

        def traced(action: object) -> Any:
            v = world.data.qvel
            speed = (math.hypot(v[0], v[1]) * 100, math.degrees(v[5]))
            current[0] = (len(sim.physics_steps), world.pose(), sim.pose, speed)
            return advance(action)

        sim.advance = traced  # type: ignore[method-assign]
        sims.append(sim)
        return sim

    lattice = run_mission(spec)
    result = run_mission(spec, simulator=make)
    steps = sims[0].physics_steps
    out = []
    for index, e in sorted(episodes.items()):
        if index >= len(steps):
            continue
        off, deg = _offset(e["start"], world.params.cell)
        along, across, heading = _signed(e["start"], e["lattice"], world.params.cell)
        walls, kind = _surroundings(spec.maze, e["lattice"])
        out.append({
            "action": str(steps[index].action), "updates": e["updates"],
            "before": str(steps[index - 1].action) if index else "",
            "geoms": sorted(e["geoms"]), "start_offset_cm": off, "start_heading_deg": deg,
            "start_along_cm": along, "start_across_cm": across, "start_yaw_deg": heading,
            "start_speed_cm_s": e["speed"][0], "start_yaw_rate_deg_s": e["speed"][1],
            "walls": walls, "cell": kind, "end_error": steps[index].position_error,
        })  # fmt: skip
    return {
        "mission": list(job), "lattice_reached": lattice.reached, "reached": result.reached,
        "episodes": out,
        "steps": [(str(s.action), s.position_error) for s in steps],
    }  # fmt: skip


def missions(maze: str, strategy: str, robot: str, workers: int) -> dict[str, Any]:
    jobs = [
        (maze, route, faults, strategy, robot)
        for route in range(len(bundled_routes(maze)))
        for faults in PAPER_FAULT_SETS
    ]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        done = list(pool.map(mission_contacts, jobs, chunksize=2))
    completed = [d for d in done if d["lattice_reached"]]
    clean = sum(1 for d in completed if d["reached"] and not d["episodes"])
    episodes = [e for d in done for e in d["episodes"]]
    by_action = Counter(e["action"] for e in episodes)
    offsets = [e["start_offset_cm"] for e in episodes]
    errors: dict[str, list[float]] = defaultdict(list)
    for d in done:
        for action, error in d["steps"]:
            errors[action].append(error)
    print(f"{maze}, {strategy}, {robot}: {clean} of {len(completed)} missions without a contact")
    print(f"{len(episodes)} actions with a contact: {dict(by_action.most_common())}")
    if offsets:
        print(
            f"  the robot's distance from its cell centre when they began: median "
            f"{statistics.median(offsets):.1f} cm, {sum(o > 4.8 for o in offsets)} over 4.8 cm"
        )
    pairs = Counter(f"{e['before']} -> {e['action']}" for e in episodes)
    print(f"  after which action: {dict(pairs.most_common(12))}")
    print(f"  the robot's cell: {dict(Counter(e['cell'] for e in episodes).most_common())}")
    for e in episodes:
        print(
            f"    {e['before']:>4} -> {e['action']}: {e['updates']:3d} updates, start "
            f"along {e['start_along_cm']:+.1f} cm, across {e['start_across_cm']:+.1f} cm, "
            f"yaw {e['start_yaw_deg']:+.1f} deg, speed {e['start_speed_cm_s']:.1f} cm/s "
            f"{e['start_yaw_rate_deg_s']:+.0f} deg/s, walls {e['walls'] or '-'} "
            f"({e['cell']}), end error {e['end_error']:.3f}, {','.join(e['geoms'])}"
        )
    print("end error per action in these missions (cells): runs, median, max, over 0.05")
    table = {}
    for action, v in sorted(errors.items(), key=lambda kv: -max(kv[1])):
        row = {"runs": len(v), "median": statistics.median(v), "max": max(v),
               "over": sum(x > 0.05 for x in v)}  # fmt: skip
        table[action] = row
        print(f"  {action}: {row['runs']}, {row['median']:.3f}, {row['max']:.3f}, {row['over']}")
    return {"missions": len(done), "completed": len(completed), "without_contact": clean,
            "episodes": episodes, "by_action": dict(by_action), "end_errors": table,
            "runs": [{"mission": d["mission"], "reached": d["reached"],
                      "contacts": sum(e["updates"] for e in d["episodes"]),
                      "actions": [a for a, _ in d["steps"]]} for d in done]}  # fmt: skip


def sequence() -> dict[str, Any]:
    """Every turn in place that fidelity confirms from rest, run after each of the in-sequence
    predecessors and itself (:func:`selfrepair.physics.fidelity.measure_in_sequence`)."""
    rest = measure(faulty=False)
    turns = [
        parse_action(r.action) for r in rest.rows if r.confirmed and r.motion.startswith("turn")
    ]
    report = measure_in_sequence(actions=turns, predecessors=PREDECESSORS, from_rest=rest)
    print(f"{len(report.rows)} confirmed turns in place, end error (cells) after: "
          f"{', '.join((*PREDECESSORS, 'itself'))}")  # fmt: skip
    done = {}
    for row in sorted(report.rows, key=lambda r: -r.worst_position):
        done[row.action] = {first: p for first, p, _ in row.after}
        print(f"  {row.action}: " + ", ".join(f"{p:.3f}" for _, p, _ in row.after)
              + f"  max {row.worst_position:.3f}")  # fmt: skip
    held = sum(r.worst_position <= 0.05 for r in report.rows)
    print(f"{held} of {len(report.rows)} stay within 0.05 cells after every one")
    return {"turns": done, "held": held}


def _velocity(speeds: tuple[float, float, float, float]) -> tuple[float, float]:
    """The robot centre's mean velocity (forward, right; cells/s, robot frame) from 0.6 s to 2 s
    with the four wheels ramped to ``speeds`` (units of the wheel speed) from rest."""
    world = PhysicsWorld(None, ORIGIN)
    p, data = world.params, world.data
    every, total, done = p.control_every, round(2.0 / p.timestep), 0
    step = p.wheel_accel * every * p.timestep / p.wheel_radius
    seen: list[tuple[float, float]] = []
    while done < total:
        data.ctrl[:] = [
            min(max(s * p.wheel_omega, c - step), c + step)
            for s, c in zip(speeds, data.ctrl, strict=True)
        ]
        world.mj.mj_step(world.model, data, every)
        done += every
        if done * p.timestep > 0.6:
            yaw = world.pose().yaw
            vx, vy = data.qvel[0] / p.cell, data.qvel[1] / p.cell
            seen.append((
                math.cos(yaw) * vx + math.sin(yaw) * vy, math.sin(yaw) * vx - math.cos(yaw) * vy
            ))  # fmt: skip
    return statistics.fmean(v[0] for v in seen), statistics.fmean(v[1] for v in seen)


def response() -> dict[str, Any]:
    """The diagonal pairs' translation per unit of speed difference (see the module docstring)."""
    out: dict[str, Any] = {}
    print("diagonal pair, mean wheel speed m: centre velocity per unit of a (forward, right)")
    for m in (0.5, 1.0, 1.5, 2.0, 2.5):
        a = m / 4
        pairs = {
            "FL/RR": (m + a / 2, 0.0, 0.0, -(m - a / 2)),
            "RL/FR": (0.0, -(m - a / 2), m + a / 2, 0.0),
        }
        for name, speeds in pairs.items():
            forward, right = _velocity(speeds)
            out[f"{name} m={m}"] = {"forward": forward / a, "right": right / a}
            print(f"  {name} m={m}: ({forward / a:+.3f}, {right / a:+.3f})")
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--maze", default="narrow-short")
    parser.add_argument("--strategy", default="replacement")
    parser.add_argument("--robot", default="four-wheel-confirmed")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--no-missions", action="store_true")
    parser.add_argument("--no-sequence", action="store_true")
    parser.add_argument("--no-response", action="store_true")
    args = parser.parse_args()
    report: dict[str, Any] = {"maze": args.maze, "strategy": args.strategy, "robot": args.robot}
    if not args.no_missions:
        report["missions"] = missions(args.maze, args.strategy, args.robot, args.workers)
    if not args.no_sequence:
        report["sequence"] = sequence()
    if not args.no_response:
        report["response"] = response()
    write_report("physics_contacts", report)


if __name__ == "__main__":
    main()
