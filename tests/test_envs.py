"""The Gymnasium environment ``selfrepair/FaultyMaze-v0``: Gymnasium's own checker (warnings are
errors), seeding, rewards, termination, truncation, the guide's hints, rendering, the flattening
wrapper, vector environments, scenario draws and the simulator's swept cells.

These tests import Gymnasium unconditionally: without the ``gym`` extra they fail, they are never
skipped (``make test`` installs the extra).
"""

from __future__ import annotations

import itertools
import warnings
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from selfrepair.envs import ENV_ID, FaultSpec, FaultyMazeEnv, MazeGenerator, Rewards
from selfrepair.envs.render import FREE_RGB, ROBOT_RGB
from selfrepair.envs.scenarios import draw_schedule, maze_sources
from selfrepair.errors import InputError, ProblemError
from selfrepair.execution.faults import Detection, FaultEvent, FaultSchedule, Persistence
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.replacement import flat_replacement
from selfrepair.robots.registry import get_domain, load_plugin
from selfrepair.world.maze import save_maze
from selfrepair.world.mazegen import generate_maze

OMNI = Path(__file__).resolve().parent.parent / "examples" / "omni"

CORNER = {"maze": "narrow-short", "start": "1,1,E", "goal": "13,13"}
"""A narrow-short mission whose first move, forward to 2,1, is free; backward hits the wall."""


def _strict_make(**kwargs: Any) -> gym.Env[Any, Any]:
    return gym.make(ENV_ID, **kwargs)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"domain": "four-wheel"},
        {"domain": "three-action"},
        {"domain": "omni"},
        {"domain": "omni", "table": str(OMNI / "table-indexed.json"), "guide": True},
        {"domain": "four-wheel", "guide": True},
        {"domain": "three-action", "guide": True, "mazes": "wide-short"},
        {
            "mazes": MazeGenerator(21, 21, corridor=2, braid=0.5),
            "faults": FaultSpec(
                persistence=(Persistence.TRANSIENT, Persistence.INTERMITTENT),
                detection=(Detection.ON_USE,),
                at=(0, 5),
            ),
            "view_radius": 2,
        },
    ],
    ids=[
        "four-wheel",
        "three-action",
        "omni-generated-table",
        "omni-guide",
        "four-wheel-guide",
        "three-action-guide",
        "generated-mazes",
    ],
)
def test_check_env_passes_with_warnings_as_errors(kwargs: dict[str, Any]) -> None:
    """The four-wheel robot, the paper's three-action robot and the example robot of
    docs/extending.md (examples/omni), which the library does not ship."""
    if kwargs.get("domain") == "omni":
        load_plugin(OMNI / "robot.py")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = _strict_make(**kwargs)
        check_env(env.unwrapped)
        env.close()


def test_registered_id_and_module_prefix() -> None:
    env = gym.make("selfrepair.envs:selfrepair/FaultyMaze-v0", domain="three-action")
    assert env.unwrapped.spec is not None and env.unwrapped.spec.id == ENV_ID
    assert env.action_space == gym.spaces.Discrete(3)
    assert gym.make(ENV_ID).action_space == gym.spaces.Discrete(81)


def test_observation_spaces_follow_the_domain() -> None:
    env = FaultyMazeEnv(domain="three-action", view_radius=4)
    space = env.observation_space
    assert isinstance(space, gym.spaces.Dict)
    assert space["window"].shape == (9, 9)
    assert space["faults"] == gym.spaces.MultiBinary(3)
    assert space["goal"].high.tolist() == [60, 60]  # wide-long is 61x61


def test_reset_seed_fixes_the_episode() -> None:
    env = FaultyMazeEnv()
    keys = ("maze", "start", "goal", "faults", "fault_seed", "schedule")
    first = env.reset(seed=11)
    again = env.reset(seed=11)
    other = env.reset(seed=12)
    assert [first[1][k] for k in keys] == [again[1][k] for k in keys]
    assert [first[1][k] for k in keys] != [other[1][k] for k in keys]
    assert first[1]["np_random_seed"] == 11
    assert all(np.array_equal(first[0][k], again[0][k]) for k in first[0])


def test_window_heading_goal_and_fault_mask() -> None:
    env = FaultyMazeEnv(mazes="narrow-short")
    obs, info = env.reset(seed=0, options={**CORNER, "faults": "FL:F,RR:B"})
    maze = env.scenario.maze
    expected = np.zeros((7, 7), dtype=np.int8)
    for dy, dx in itertools.product(range(7), range(7)):
        expected[dy, dx] = maze.is_free(1 + dx - 3, 1 + dy - 3)
    assert np.array_equal(obs["window"], expected)
    assert obs["heading"] == int(Heading.E)
    assert obs["goal"].tolist() == [12, 12]
    domain = env.domain
    known = [domain.faults[i] for i in np.flatnonzero(obs["faults"])]
    assert domain.format_faults(known) == "FL:F,RR:B" == info["known_faults"]


def _step(env: FaultyMazeEnv, code: str) -> tuple[Any, float, bool, bool, dict[str, Any]]:
    index = env.action_index(env.domain.parse_action(code))
    obs, reward, terminated, truncated, info = env.step(index)
    return obs, float(reward), terminated, truncated, info


def test_rewards_for_a_move_a_blocked_command_and_a_failed_attempt() -> None:
    rewards = Rewards(goal_bonus=50.0, blocked_penalty=3.0, fault_penalty=5.0)
    env = FaultyMazeEnv(mazes="narrow-short", rewards=rewards)
    env.reset(seed=0, options={**CORNER, "faults": "RR:B"})
    _, reward, *_, info = _step(env, "FFFF")  # forward one cell, 1 tick
    assert (reward, info["outcome"], info["pose"]) == (-1.0, "moved", "2,1,E")
    _, reward, *_, info = _step(env, "SSBB")  # backward: RR:B forbids it
    assert (reward, info["outcome"], info["pose"]) == (-1.0 - 5.0, "failed-attempt", "2,1,E")
    _, reward, *_, info = _step(env, "SFSF")  # turn left in place (2 ticks): now facing N
    assert (reward, info["pose"]) == (-2.0, "2,1,N")
    _, reward, *_, info = _step(env, "FFFF")  # forward into the wall: refused
    assert (reward, info["outcome"], info["pose"]) == (-3.0, "collision", "2,1,N")
    assert env.steps == 4 and info["ticks"] == 1.0 + 1.0 + 2.0


def test_on_use_detection_reveals_a_fault_when_it_blocks() -> None:
    env = FaultyMazeEnv(mazes="narrow-short")
    domain = env.domain
    schedule = FaultSchedule.permanent(domain.parse_faults("FL:F"), detection=Detection.ON_USE)
    obs, info = env.reset(seed=0, options={**CORNER, "faults": schedule})
    assert not obs["faults"].any() and info["known_faults"] == ""
    obs, *_, info = _step(env, "FFFF")
    assert info["outcome"] == "failed-attempt" and info["known_faults"] == "FL:F"
    (fault,) = domain.parse_faults("FL:F")
    assert obs["faults"][domain.faults.index(fault)] == 1


def test_goal_terminates_with_the_bonus_and_the_limit_truncates() -> None:
    env = FaultyMazeEnv(mazes="narrow-short", max_steps=2)
    env.reset(seed=0, options={**CORNER, "goal": "2,1", "faults": ""})
    _, reward, terminated, truncated, _ = _step(env, "FFFF")
    assert (reward, terminated, truncated) == (-1.0 + 100.0, True, False)
    env.reset(seed=0, options={**CORNER, "faults": ""})
    assert _step(env, "SSSS")[2:4] == (False, False)
    assert _step(env, "SSSS")[2:4] == (False, True)


def test_reset_options_are_checked() -> None:
    env = FaultyMazeEnv()
    with pytest.raises(ProblemError, match="unknown reset option"):
        env.reset(options={"mazes": "narrow-short"})
    with pytest.raises(ProblemError, match="not a free cell"):
        env.reset(options={**CORNER, "start": "0,0,N"})
    with pytest.raises(InputError):
        env.reset(options={**CORNER, "faults": "XX:F"})
    with pytest.raises(ProblemError, match="reset"):
        FaultyMazeEnv().step(0)
    env.reset(seed=0)
    with pytest.raises(ProblemError, match="action index"):
        env.step(81)


def test_constructor_arguments_are_checked() -> None:
    with pytest.raises(ProblemError, match="view_radius"):
        FaultyMazeEnv(view_radius=33)
    with pytest.raises(ProblemError, match="render_mode"):
        FaultyMazeEnv(render_mode="human")
    with pytest.raises(ProblemError, match="three-action"):
        FaultyMazeEnv(domain="three-action", table="handwritten")
    with pytest.raises(InputError, match="domain"):
        FaultyMazeEnv(domain="no-such-robot")
    with pytest.raises(ProblemError, match="width"):
        MazeGenerator(2000, 25)


def test_guide_suggests_the_table_replacement_and_reaches_the_goal() -> None:
    env = FaultyMazeEnv(mazes="narrow-short", guide=True)
    _, info = env.reset(seed=0, options={**CORNER, "faults": "FL:B"})
    grid = env.scenario.maze.free_grid(4)
    hits = 0
    while True:
        if info["repair_source"] == "replacement":
            faulty = env.actions[info["faulty_action"]]
            found = flat_replacement(env.table, faulty, env.pose, env.known, grid)
            assert found is not None
            assert info["replacement"] == tuple(env.action_index(a) for a in found.actions)
            assert info["planned_action"] == info["replacement"][0]
            hits += 1
        _, _, terminated, truncated, info = env.step(info["planned_action"])
        if terminated or truncated:
            break
    assert terminated and hits >= 1


def test_guide_replans_after_the_robot_leaves_its_plan() -> None:
    env = FaultyMazeEnv(mazes="narrow-short", guide=True)
    _, info = env.reset(seed=0, options={**CORNER, "faults": ""})
    turn_left = env.action_index(env.domain.parse_action("SFSF"))
    assert info["planned_action"] not in (-1, turn_left)
    _, *_, info = _step(env, "SFSF")  # off the plan: turn left, now facing N
    assert info["planned_action"] != -1 and env.pose == Pose(1, 1, Heading.N)
    for _ in range(200):
        _, _, terminated, _, info = env.step(info["planned_action"])
        if terminated:
            break
    assert terminated


def test_render_modes() -> None:
    env = FaultyMazeEnv(mazes="narrow-short", render_mode="ansi")
    env.reset(seed=0, options={**CORNER, "faults": "FL:F"})
    text = env.render()
    assert isinstance(text, str)
    lines = text.splitlines()
    assert lines[1][1] == ">" and lines[13][13] == "G" and "known faults FL:F" in lines[-1]
    env = FaultyMazeEnv(mazes="narrow-short", render_mode="rgb_array", cell_pixels=4)
    env.reset(seed=0, options=CORNER)
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.shape == (60, 60, 3) and frame.dtype == np.uint8
    assert frame[6, 5].tolist() == list(ROBOT_RGB)  # inside cell 1,1 (pixels 4..7)
    assert frame[9, 5].tolist() == list(FREE_RGB)  # inside cell 1,2, free
    assert FaultyMazeEnv().render() is None


def test_flatten_observation_wrapper() -> None:
    env = gym.wrappers.FlattenObservation(gym.make(ENV_ID, domain="three-action"))
    obs, _ = env.reset(seed=3)
    assert obs.shape == (gym.spaces.flatdim(env.unwrapped.observation_space),)
    env.action_space.seed(3)
    for _ in range(30):
        obs, *_ = env.step(env.action_space.sample())
        assert obs in env.observation_space


def _run_vector(seed: int, steps: int) -> tuple[list[Any], int]:
    vec = gym.vector.SyncVectorEnv(
        [lambda: gym.make(ENV_ID, mazes="narrow-short", max_steps=25) for _ in range(3)]
    )
    vec.action_space.seed(seed)
    obs, _ = vec.reset(seed=seed)
    trail = [obs["window"].copy()]
    ended = 0
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = vec.step(vec.action_space.sample())
        assert obs in vec.observation_space and reward.shape == (3,)
        ended += int(np.sum(terminated | truncated))
        trail.append(obs["window"].copy())
    vec.close()
    return trail, ended


def test_sync_vector_env_steps_resets_and_is_seeded() -> None:
    trail, ended = _run_vector(seed=5, steps=60)
    assert trail[0].shape == (3, 7, 7)
    assert ended >= 6  # every sub-environment truncated at 25 steps, twice
    again, _ = _run_vector(seed=5, steps=60)
    assert all(np.array_equal(a, b) for a, b in zip(trail, again, strict=True))


def test_make_vec_with_the_flattening_wrapper() -> None:
    vec = gym.make_vec(
        ENV_ID,
        num_envs=2,
        vectorization_mode="sync",
        wrappers=[gym.wrappers.FlattenObservation],
        domain="three-action",
    )
    obs, _ = vec.reset(seed=0)
    assert obs.ndim == 2 and obs.shape[0] == 2
    obs, *_ = vec.step(np.array([0, 1]))
    assert obs in vec.observation_space
    vec.close()


@pytest.mark.parametrize("name", ["four-wheel", "three-action"])
def test_simulated_motion_equals_the_domain(name: str) -> None:
    """The simulator moves by the move table (no motion of its own): every action from every
    heading, at shifted cells, ends and sweeps where ``Domain.step`` says."""
    domain = get_domain(name)
    maze = generate_maze(21, 21, seed=1)
    free = [(x, y) for y in range(maze.height) for x in range(maze.width) if maze.is_free(x, y)]
    for action, heading, (x, y) in itertools.product(domain.actions, Heading, free[::40]):
        pose = Pose(x, y, heading)
        outcome = Simulator(domain, maze, pose, FaultSchedule()).execute(action)
        end, swept, _ = domain.step(pose, action)
        assert outcome.swept == tuple(swept)
        if outcome.status is Outcome.MOVED:
            assert outcome.end == end
        else:
            assert outcome.status is Outcome.COLLISION and outcome.end == pose


def test_maze_sources_generator_file_and_bundled(tmp_path: Path) -> None:
    path = tmp_path / "m.maze"
    save_maze(generate_maze(11, 11, seed=3), path)
    env = FaultyMazeEnv(mazes=[str(path), MazeGenerator(15, 15)], routes="random")
    labels = {env.reset(seed=s)[1]["maze"] for s in range(12)}
    assert "m" in labels and any(label.startswith("gen15x15") for label in labels)
    assert [s.label for s in maze_sources("bundled")] == [
        "narrow-short", "wide-short", "narrow-long", "wide-long"
    ]  # fmt: skip
    with pytest.raises(InputError, match="unknown maze"):
        maze_sources("no-such-maze")


def test_fault_spec_draws() -> None:
    domain = get_domain("four-wheel")
    spec = FaultSpec(
        sets=("FL:F,RL:F",),
        persistence=(Persistence.TRANSIENT,),
        detection=(Detection.ON_USE,),
        at=(2, 4),
        duration=(3, 3),
    )
    schedule = draw_schedule(domain, spec, np.random.default_rng(0))
    assert schedule.detection is Detection.ON_USE
    assert domain.format_faults(schedule.all_faults()) == "FL:F,RL:F"
    assert all(
        e.persistence is Persistence.TRANSIENT and 2 <= e.at <= 4 and e.duration == 3
        for e in schedule.events
    )
    spec = FaultSpec(sets=("FR:S",), persistence=("intermittent",), probability=(0.5, 0.5))
    event = draw_schedule(domain, spec, np.random.default_rng(0)).events[0]
    assert event == FaultEvent(event.fault, 0, persistence=Persistence.INTERMITTENT,
                               probability=0.5)  # fmt: skip
    with pytest.raises(ProblemError):
        FaultSpec(sets=())
    with pytest.raises(ProblemError):
        FaultSpec(at=(3, 1))
