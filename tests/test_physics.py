"""selfrepair.physics: the MJCF model, the tracker, the fidelity report, the identified domain and
missions in MuJoCo (the ``physics`` extra; under SELFREPAIR_REQUIRE_EXTRAS=1 a missing mujoco
fails these tests instead of skipping them)."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")  # headless rendering, before mujoco is imported

import itertools
import json
import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from extras import needs_extra
from selfrepair.cli import main
from selfrepair.errors import InputError, ProblemError
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.stepper import Stepper
from selfrepair.geometry import Heading, Pose
from selfrepair.physics.identified import load_identified
from selfrepair.physics.model import ORIGIN, RobotParams, WallBox, heading_yaw, mjcf, wall_boxes
from selfrepair.physics.simulator import lattice_motion
from selfrepair.physics.tracker import (
    ContinuousPose,
    LatticeMotion,
    _side,
    balanced_drive,
    reference,
)
from selfrepair.physics.world import lattice_pose, snap
from selfrepair.robots.domain import check_domain
from selfrepair.robots.four_wheel import ACTIONS, FOUR_WHEEL, parse_action
from selfrepair.world.maze import Maze, parse_maze

PHYSICS = needs_extra("mujoco", "imageio", extra="physics")

OPEN = parse_maze("......\n......\n......\n......\n......\n......\n", name="open")


# --- the model, without MuJoCo --------------------------------------------------------------


def test_only_the_chassis_and_the_tyres_touch_walls_and_only_the_wheel_spheres_the_floor() -> None:
    import xml.etree.ElementTree as ET

    params = RobotParams()
    root = ET.fromstring(mjcf(parse_maze("###\n#.#\n###\n"), params))
    geoms = {g.get("name"): g for g in root.iter("geom")}

    def bits(name: str) -> tuple[int, int]:
        g = geoms[name]
        return int(g.get("contype", "1")), int(g.get("conaffinity", "1"))

    def collide(a: str, b: str) -> bool:
        (ta, aa), (tb, ab) = bits(a), bits(b)
        return bool(ta & ab or tb & aa)

    for wheel in ("FL", "FR", "RL", "RR"):
        assert collide(wheel, "floor") and not collide(wheel, "wall0")  # the sphere rolls
        assert collide(f"{wheel}_tyre", "wall0") and not collide(f"{wheel}_tyre", "floor")
    assert collide("chassis", "wall0") and not collide("wall0", "floor")
    # what touches a wall reaches sideways no further than the tyres' outer faces
    assert params.wheel_y + params.wheel_half_width == pytest.approx(0.145)


def test_a_turn_in_place_drives_a_diagonal_pair_within_its_commands() -> None:
    turn = LatticeMotion(0, 0, 1)  # clockwise: the left side forward, the right backward
    assert balanced_drive((1, 1, 1, -1), turn) == (1, 0, 0, -1)  # FFFB: FL with RR
    assert balanced_drive((0, -1, 1, -1), turn) == (0, -1, 1, 0)  # SBFB: FR with RL
    assert balanced_drive((1, -1, 1, -1), turn) == (1, -1, 1, -1)  # all four: as commanded
    assert balanced_drive((1, -1, 0, 0), turn) == (1, -1, 0, 0)  # no diagonal pair
    assert balanced_drive((1, 1, 1, -1), LatticeMotion(1, 0, 0)) == (1, 1, 1, -1)
    for commands in itertools.product((1, 0, -1), repeat=4):
        for motion in (turn, LatticeMotion(0, 0, -1)):
            drive = balanced_drive(commands, motion)  # type: ignore[arg-type]
            assert all(d in (0, c) for d, c in zip(drive, commands, strict=True))


def test_wall_boxes_merge_each_rows_runs_and_add_the_border() -> None:
    maze = Maze(np.array([[True, True, False, True], [False, False, False, False]]))
    boxes = wall_boxes(maze, 1.0)
    assert boxes[:2] == (WallBox(0.5, 0.0, 1.0, 0.5), WallBox(3.0, 0.0, 0.5, 0.5))
    assert len(boxes) == 2 + 4
    north, south, west, east = boxes[2:]
    assert (north.y, south.y, west.x, east.x) == (1.0, -2.0, -1.0, 4.0)
    assert north.half_x == 3.0  # the border spans the grid and the corners


def test_params_refuse_a_robot_that_does_not_fit_in_a_cell() -> None:
    with pytest.raises(ProblemError, match="does not fit"):
        RobotParams(cell=0.3)
    with pytest.raises(ProblemError, match="friction"):
        RobotParams(friction=0)


def test_snap_inverts_lattice_pose_for_every_heading() -> None:
    for heading in Heading:
        pose = Pose(3, 5, heading)
        assert snap(lattice_pose(pose)) == pose
    assert heading_yaw(Heading.E) == 0.0
    assert snap(ContinuousPose(2.4, -0.6, math.radians(80))) == Pose(2, 1, Heading.N)


def test_reference_ends_at_the_lattice_end_pose_for_every_action() -> None:
    for heading in Heading:
        start = Pose(0, 0, heading)
        for action in ACTIONS:
            end, _, _ = reference(lattice_pose(start), lattice_motion(FOUR_WHEEL, action), 1.0)
            want = lattice_pose(FOUR_WHEEL.apply(start, action))
            assert math.hypot(end.x - want.x, end.y - want.y) < 1e-9, (heading, action)
            assert abs(math.remainder(end.yaw - want.yaw, 2 * math.pi)) < 1e-9


@given(
    st.sampled_from((-1, 0, 1)),
    st.sampled_from((-1, 0, 1)),
    st.floats(-5, 5, allow_nan=False),
)
def test_the_tracker_keeps_every_wheel_within_its_commands_sign(
    front: int, rear: int, speed: float
) -> None:
    a, b = _side(front, rear, speed, 3.0)
    for command, wheel in ((front, a), (rear, b)):
        assert wheel * command >= 0 and (command != 0 or wheel == 0)
        assert abs(wheel) <= 3.0


def test_bundled_identified_domain_keeps_what_snaps_and_drops_pivots_on_a_stopped_side() -> None:
    domain = load_identified()
    check_domain(domain)
    kept = {a.code for a in domain.actions}
    assert "FSSS" not in kept and "SSSF" not in kept  # pivots about a braked side
    assert {"FFFF", "FBFB", "SFFF", "SSSS", "BBBB"} <= kept
    for action in domain.actions[:10]:
        if domain.motion_class(action) == FOUR_WHEEL.motion_class(action):
            assert domain.apply(Pose(2, 2, Heading.E), action) == FOUR_WHEEL.apply(
                Pose(2, 2, Heading.E), action
            )
    assert domain.waits[0] == parse_action("SSSS")


def test_stepper_relocalise_drops_the_queue() -> None:
    stepper = Stepper.__new__(Stepper)
    from collections import deque

    stepper.queue = deque([(parse_action("FFFF"), None)])
    stepper.stopped, stepper.failure = True, None
    stepper.relocalise()
    assert not stepper.queue and not stepper.stopped


# --- MuJoCo ---------------------------------------------------------------------------------


@PHYSICS
def test_straight_and_spin_are_confirmed_and_a_pivot_on_a_stopped_side_is_not() -> None:
    from selfrepair.physics.fidelity import measure

    report = measure(actions=[parse_action(c) for c in ("FFFF", "FBFB", "FSSS")])
    rows = {r.action: r for r in report.rows}
    assert rows["FFFF"].confirmed and rows["FBFB"].confirmed
    assert rows["FFFF"].snapped == (1, 0, 0) and rows["FFFF"].swept == ((0, 0), (1, 0))
    assert not rows["FSSS"].confirmed and rows["FSSS"].snapped is None
    assert rows["FSSS"].tracked_position > 0.3  # its centre swings about the braked wheels
    assert report.summary()["nominal"]["tracked_confirmed"] == 2


@PHYSICS
def test_the_motor_controllers_ramp_each_wheel_at_most_wheel_accel() -> None:
    from selfrepair.physics.world import PhysicsWorld

    params = RobotParams()
    seen: list[list[float]] = [[0.0] * 4]
    world = PhysicsWorld(None, ORIGIN, params, observer=lambda w: seen.append(list(w.data.ctrl)))
    world.run((1, 1, 1, 1), Fraction(1))  # open loop: the command is full speed from the start
    step = params.wheel_accel * params.control_every * params.timestep / params.wheel_radius
    assert seen[1] == pytest.approx([step] * 4)  # not the full 10 rad/s at once
    jumps = [
        abs(b - a)
        for before, after in itertools.pairwise(seen)
        for a, b in zip(before, after, strict=True)
    ]
    assert max(jumps) <= step + 1e-9 and seen[-1] == pytest.approx([params.wheel_omega] * 4)
    with pytest.raises(ProblemError, match="wheel_accel"):
        RobotParams(wheel_accel=0.0)


@PHYSICS
def test_a_three_wheel_turn_turns_in_place_on_its_diagonal_pair() -> None:
    from selfrepair.physics.fidelity import measure

    (row,) = measure(actions=[parse_action("FFFB")], faulty=False).rows
    assert row.confirmed and row.tracked_position < 0.02  # it drifted 0.2 cells on three wheels


@PHYSICS
def test_a_diagonal_pair_turn_confirmed_from_rest_drifts_after_another_action() -> None:
    # docs/physics.md ("Fidelity in sequence"): fidelity measures FFFB from rest 0.000 cells
    # off, but after SFFS it ends 0.19 cells off; BFFF, driven on the other diagonal, holds.
    from selfrepair.physics.fidelity import measure_in_sequence

    report = measure_in_sequence(
        actions=[parse_action("FFFB"), parse_action("BFFF")], predecessors=("SFFS",)
    )
    fffb, bfff = report.rows
    assert [first for first, _, _ in fffb.after] == ["SFFS", "FFFB"]
    (_, after_arc, _), (_, after_itself, _) = fffb.after
    assert fffb.from_rest and not fffb.holds and 0.1 < after_arc < 0.3 and after_itself < 0.01
    assert bfff.from_rest and bfff.holds and bfff.worst_position < 0.05
    summary = report.summary()
    assert summary["all"] == {**summary["turn"]}
    assert (summary["all"]["from_rest"], summary["all"]["in_sequence"]) == (2, 1)


@PHYSICS
def test_physics_fidelity_cli_prints_the_in_sequence_table(monkeypatch, capsys) -> None:
    import selfrepair.physics.fidelity as fidelity

    few = [parse_action("FFFF"), parse_action("FSSS")]
    measure, in_sequence = fidelity.measure, fidelity.measure_in_sequence
    monkeypatch.setattr(fidelity, "measure", lambda **kw: measure(actions=few, **kw))
    monkeypatch.setattr(
        fidelity, "measure_in_sequence", lambda **kw: in_sequence(actions=few, **kw)
    )
    assert main(["physics", "fidelity", "--nominal", "--in-sequence"]) == 0
    out = capsys.readouterr().out
    assert "in sequence (after FFFF, BBBB, SFFS, FBFB, BFBF and itself)" in out
    assert "| all | 2 | 1 | 1 |" in out and "| FSSS | turn-right | no | no |" in out


@PHYSICS
def test_open_loop_ffff_drives_about_one_cell_north() -> None:
    from selfrepair.physics.world import PhysicsWorld

    world = PhysicsWorld(None, ORIGIN)
    end = world.run((1, 1, 1, 1), Fraction(1)).end
    assert 0.7 < end.y < 1.0 and abs(end.x) < 0.01 and abs(end.yaw - math.pi / 2) < 0.01


@PHYSICS
def test_a_physics_mission_reaches_the_goal_without_touching_a_wall() -> None:
    from selfrepair.execution.executor import run_mission
    from selfrepair.physics.mission import run_physics_mission
    from selfrepair.world.bundled import bundled_routes, load_bundled

    maze = load_bundled("wide-short")
    route = bundled_routes("wide-short")[0]
    spec = MissionSpec(maze, route.start, route.goal, strategy="replacement")
    done = run_physics_mission(spec)
    lattice = run_mission(spec)
    assert done.result.reached and done.outcome.wall_contacts == 0
    assert done.outcome.final_error < 0.1
    assert [s.action for s in done.result.steps] == [s.action for s in lattice.steps]
    assert done.outcome.physics_steps == round(float(lattice.ticks) / 0.002)


@PHYSICS
def test_an_open_loop_mission_is_relocalised_and_replanned() -> None:
    from selfrepair.physics.mission import run_physics_mission

    spec = MissionSpec(OPEN, Pose(0, 5, Heading.N), (5, 0), strategy="replan")
    done = run_physics_mission(spec, tracked=False)
    assert done.outcome.deviations > 0  # open loop, the lattice's motions do not hold
    executed = done.result.steps
    for before, after in itertools.pairwise(executed):
        assert after.start == before.end  # the loop continued from the localised pose
    deviated = {s.step for s in done.steps if s.snapped != s.lattice_end}
    replans = {r.step for r in done.result.repairs}
    assert all(step + 1 in replans for step in deviated if step + 1 < len(executed))


@PHYSICS
def test_physics_run_cli_renders_a_gif_and_writes_json(tmp_path, capsys) -> None:
    maze = tmp_path / "m.maze"
    maze.write_text("....\n....\n", encoding="utf-8")
    gif = tmp_path / "run.gif"
    code = main(["physics", "run", str(maze), "--start", "0,1,E", "--goal", "2,1",
                 "--video", str(gif), "--json", "--no-warm-up"])  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["reached"] and out["wall_contacts"] == 0
    import imageio.v2 as iio

    frames = iio.mimread(gif)
    assert len(frames) >= 10 and frames[0].shape[:2] == (360, 480)
    assert np.ptp(np.asarray(frames[0])) > 0  # a picture, not a blank frame


def test_physics_run_cli_refuses_a_bad_video_name(tmp_path, capsys) -> None:
    maze = tmp_path / "m.maze"
    maze.write_text("....\n", encoding="utf-8")
    code = main(["physics", "run", str(maze), "--start", "0,0,E", "--goal", "2,0",
                 "--video", str(tmp_path / "x.txt")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and ".gif or .mp4" in err


@PHYSICS
@pytest.mark.slow
def test_the_bundled_identified_domain_is_what_fidelity_measures_now() -> None:
    from importlib import resources

    from selfrepair.physics.fidelity import measure, measure_in_sequence

    bundled = json.loads(
        resources.files("selfrepair")
        .joinpath("data", "physics", "four-wheel-physics.json")
        .read_text("utf-8")
    )
    report = measure(faulty=False)
    sequence = measure_in_sequence(from_rest=report)
    assert json.loads(json.dumps(report.identified(sequence=sequence))) == bundled


@PHYSICS
def test_faulty_rows_carry_the_performed_actions_measurement() -> None:
    from selfrepair.physics.fidelity import faulty_rows, measure

    report = measure(actions=[parse_action(c) for c in ("SFFF", "FFFF")], faulty=False)
    sfff, ffff = report.rows
    rows = {
        (r.action, r.faults, r.behaviour): r for r in faulty_rows(FOUR_WHEEL, list(report.rows))
    }
    stalled = rows[("FFFF", "FL:F", "stall")]  # the front-left wheel stops: SFFF is performed
    assert stalled.executed == "SFFF" and stalled.motion == "forward"
    assert (stalled.tracked_position, stalled.snapped) == (sfff.tracked_position, sfff.snapped)
    stuck_on = rows[("SFFF", "FL:S", "stall")]  # it cannot stop: it runs forward, FFFF
    assert stuck_on.executed == "FFFF" and stuck_on.confirmed == ffff.confirmed
    assert ("FFFF", "FL:F", "reverse") not in rows  # BFFF was not measured
    assert all(r.executed in ("SFFF", "FFFF") and r.action != r.executed for r in rows.values())


@PHYSICS
def test_physics_experiment_compares_the_footings_per_strategy() -> None:
    from selfrepair.experiment.physics import footing_summary, physics_experiment

    rows = physics_experiment(("wide-short",), ("replacement",), ("FL:F",))
    assert [(r.route, r.faults, r.strategy) for r in rows] == [
        (f"r{i}", "FL:F", "replacement") for i in range(1, 5)
    ]
    summary = footing_summary(rows)["replacement"]
    assert summary["missions"] == 4 and summary["lattice_reached"] == 4
    assert summary["both_reached"] == sum(r.physics_reached for r in rows)


def test_physics_experiment_refuses_an_unknown_strategy(capsys) -> None:
    code = main(["physics", "experiment", "--strategy", "teleport"])
    err = capsys.readouterr().err
    assert code == 2 and "teleport" in err and err.count("\n") == 1


@PHYSICS
def test_a_robots_own_mjcf_runs_and_a_model_without_a_robot_is_refused() -> None:
    from selfrepair.physics.model import mjcf
    from selfrepair.physics.world import PhysicsWorld

    slippery = mjcf(OPEN).replace('friction="0.8 0 0"', 'friction="0.2 0 0"')
    assert slippery != mjcf(OPEN)
    world = PhysicsWorld(OPEN, Pose(0, 5, Heading.N), xml=slippery)
    end = world.run((1, -1, 1, -1), Fraction(1)).end  # FBFB spins less on a slippery floor
    grippy = PhysicsWorld(OPEN, Pose(0, 5, Heading.N)).run((1, -1, 1, -1), Fraction(1)).end
    assert abs(end.yaw - math.pi / 2) != abs(grippy.yaw - math.pi / 2)
    with pytest.raises(ProblemError, match="robot"):
        PhysicsWorld(OPEN, xml="<mujoco><worldbody/></mujoco>")


@PHYSICS
@needs_extra("gymnasium", extra="gym")
def test_the_physics_gym_variant_steps_in_mujoco_with_a_continuous_pose() -> None:
    import gymnasium as gym

    from selfrepair.envs import PHYSICS_ENV_ID

    env = gym.make(PHYSICS_ENV_ID, mazes="wide-short")
    observation, _ = env.reset(seed=1, options={"start": "1,1,E", "goal": "3,1", "faults": ""})
    assert env.observation_space.contains(observation)
    assert np.allclose(observation["pose"], (1.0, 1.0, math.pi / 2))
    forward = FOUR_WHEEL.actions.index(parse_action("FFFF"))
    observation, reward, terminated, _, info = env.step(forward)
    x, y, heading = observation["pose"]
    assert info["pose"] == "2,1,E" and abs(x - 2) < 0.05 and abs(y - 1) < 0.05
    assert abs(heading - math.pi / 2) < math.radians(3) and info["wall_contacts"] == 0
    assert float(reward) == -1.0 and not terminated
    env.close()


def test_the_confirmed_only_domain_keeps_the_confirmed_actions_and_every_basic_motion() -> None:
    from selfrepair.physics.identified import CONFIRMED_NAME

    domain = load_identified(name=CONFIRMED_NAME, confirmed_only=True)
    check_domain(domain)
    kept = {a.code for a in domain.actions}
    # the single-axle turns drift; FFFB turns in place on its diagonal pair (balanced_drive)
    assert len(kept) == 65 and "FBSS" not in kept and {"FFFB", "FSSB"} <= kept
    assert kept < {a.code for a in load_identified().actions}
    for fault in FOUR_WHEEL.faults:  # every single fault leaves a way to turn and drive
        motions = {domain.motion_class(a) for a in domain.actions if domain.available(a, {fault})}
        assert {"forward", "backward", "turn-left", "turn-right"} <= motions, fault


def test_physics_experiment_refuses_an_unknown_robot_model(capsys) -> None:
    code = main(["physics", "experiment", "--robot", "hovercraft"])
    err = capsys.readouterr().err
    assert code == 2 and "four-wheel-confirmed" in err and err.count("\n") == 1


def test_the_in_sequence_domain_keeps_only_what_holds_after_other_actions() -> None:
    from selfrepair.physics.identified import CONFIRMED_NAME, IN_SEQUENCE_NAME

    domain = load_identified(name=IN_SEQUENCE_NAME, in_sequence_only=True)
    check_domain(domain)
    kept = {a.code for a in domain.actions}
    confirmed = {a.code for a in load_identified(name=CONFIRMED_NAME, confirmed_only=True).actions}
    # docs/physics.md ("Fidelity in sequence"): 40 of the 65 confirmed from rest hold
    assert len(kept) == 40 and kept < confirmed and domain.name == IN_SEQUENCE_NAME
    assert {"FFFB", "FSFB", "FBFB", "BFBF", "FFSS", "SSSS"}.isdisjoint(kept)
    assert {"FFFF", "BBBB", "BFFF", "FFSB", "FFFS"} <= kept
    for fault in FOUR_WHEEL.faults:  # every single fault leaves a way to turn and drive
        motions = {domain.motion_class(a) for a in domain.actions if domain.available(a, {fault})}
        assert {"forward", "backward", "turn-left", "turn-right"} <= motions, fault


def test_an_identified_file_without_in_sequence_marks_is_refused_for_that_robot() -> None:
    from selfrepair.physics.identified import identified_domain

    data = {"actions": [{"action": "FFFF", "forward": 1, "lateral": 0, "rotation": 0,
                         "swept": [[0, 0], [1, 0]], "confirmed": True}]}  # fmt: skip
    assert len(identified_domain(data, confirmed_only=True).actions) == 1
    with pytest.raises(InputError, match="marked in_sequence"):
        identified_domain(data, in_sequence_only=True)
    # an action that holds in sequence but is not confirmed from rest is not kept
    data["actions"] += [{"action": "BBBB", "forward": -1, "lateral": 0, "rotation": 0,
                         "swept": [[0, 0], [-1, 0]], "confirmed": False, "in_sequence": True}]
    data["actions"][0]["in_sequence"] = True  # fmt: skip
    kept = identified_domain(data, in_sequence_only=True).actions
    assert [a.code for a in kept] == ["FFFF"]


@PHYSICS
def test_the_identified_file_marks_what_holds_in_sequence_as_the_bundled_one_does() -> None:
    from selfrepair.physics.fidelity import measure, measure_in_sequence

    few = [parse_action("FFFB"), parse_action("BFFF")]
    report = measure(actions=few, faulty=False)
    sequence = measure_in_sequence(actions=few, predecessors=("SFFS",), from_rest=report)
    data = report.identified(sequence=sequence)
    marks = {e["action"]: e["in_sequence"] for e in data["actions"]}
    assert marks == {"FFFB": False, "BFFF": True}
    assert data["in_sequence_after"] == ["SFFS", "itself"]
    bundled = {a.code for a in load_identified(in_sequence_only=True).actions}
    assert "FFFB" not in bundled and "BFFF" in bundled


@PHYSICS
def test_a_physics_mission_with_the_in_sequence_robot_plans_only_its_actions() -> None:
    from selfrepair.experiment.physics import physics_mission_spec
    from selfrepair.physics.identified import IN_SEQUENCE_NAME
    from selfrepair.physics.mission import run_physics_mission

    spec = physics_mission_spec("wide-short", 0, "FL:F", "replacement", IN_SEQUENCE_NAME)
    done = run_physics_mission(spec)
    kept = set(spec.domain.actions)
    assert done.outcome.reached and done.outcome.wall_contacts == 0
    assert done.steps and all(step.action in kept for step in done.steps)
