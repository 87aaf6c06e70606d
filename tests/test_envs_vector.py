"""The vector environment (``FaultyMazeVectorEnv``): the same transitions as ``FaultyMazeEnv``.

The oracle is Gymnasium's own ``SyncVectorEnv`` over ``FaultyMazeEnv``: fed the same seeds, resets
and actions, it must give the same observations, rewards, terminations, truncations and info step
for step, in every autoreset mode (a Hypothesis property over random tasks, fault schedules and
action sequences). Beside it: the interpreted kernel against the compiled one, the kernel's
intermittent-fault draws against numpy's generator, what ``gymnasium.utils.env_checker`` checks
of a single environment that applies to a vector one (spaces, seeding, determinism, no reused
arrays), registration with ``gymnasium.make_vec``, and the errors.

Like tests/test_envs.py these import Gymnasium unconditionally (``make test`` installs it); the
numba tests carry the ``fast`` extra's mark.
"""

from __future__ import annotations

import itertools
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv
from gymnasium.vector.utils import batch_space
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.envs import (
    ENV_ID,
    HIDDEN_ENV_ID,
    FaultSpec,
    FaultyMazeEnv,
    MazeGenerator,
    Rewards,
)
from selfrepair.envs import _vector_kernels as kernels
from selfrepair.envs.vector import OUTCOME_NAMES, FaultyMazeVectorEnv
from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Clock, Detection, FaultEvent, FaultSchedule, Persistence
from selfrepair.geometry import Heading
from selfrepair.robots.registry import get_domain

MODES = tuple(AutoresetMode)
SEEN = [Detection.NOW, Detection.ON_USE]
"""The detection modes in which the robot is told of its faults (the vector env's)."""
CORNER = {"maze": "narrow-short", "start": "1,1,E", "goal": "2,1"}
"""A narrow-short mission whose goal is the cell ahead of the start."""

_PER_STEP = ("outcome", "pose", "ticks")


def _pair(n: int, mode: AutoresetMode, backend: str = "auto", **kwargs: Any) -> tuple[Any, Any]:
    sync = SyncVectorEnv([lambda: FaultyMazeEnv(**kwargs) for _ in range(n)], autoreset_mode=mode)
    vec = FaultyMazeVectorEnv(n, autoreset_mode=mode, backend=backend, **kwargs)
    return sync, vec


def _same_obs(expected: dict[str, Any], got: dict[str, Any]) -> None:
    assert expected.keys() == got.keys()
    for key, value in expected.items():
        assert type(got[key]) is type(value), key
        assert np.asarray(got[key]).dtype == np.asarray(value).dtype, key
        np.testing.assert_array_equal(got[key], value, err_msg=key)


def _same_info(expected: dict[str, Any], got: dict[str, Any], vec: FaultyMazeVectorEnv) -> None:
    """The vector info says what the SyncVectorEnv info says (per-step keys decoded)."""
    letters = "".join(h.name for h in Heading)
    for key in _PER_STEP:
        np.testing.assert_array_equal(got[f"_{key}"], expected[f"_{key}"], err_msg=key)
    for i in np.flatnonzero(expected["_outcome"]).tolist():
        assert OUTCOME_NAMES[got["outcome"][i]] == expected["outcome"][i]
        x, y, h = got["pose"][i].tolist()
        assert f"{x},{y},{letters[h]}" == expected["pose"][i]
        assert got["ticks"][i] == expected["ticks"][i]
    for key in ("maze", "start", "goal", "faults", "schedule", "detection", "fault_seed",
                "np_random_seed", "max_steps"):  # fmt: skip
        assert (key in got) == (key in expected), key
        if key in expected:
            np.testing.assert_array_equal(got[f"_{key}"], expected[f"_{key}"], err_msg=key)
            mask = expected[f"_{key}"]
            assert got[key][mask].tolist() == expected[key][mask].tolist(), key


def _same_reset(expected: tuple[Any, ...], got: tuple[Any, ...], vec: FaultyMazeVectorEnv) -> None:
    _same_obs(expected[0], got[0])
    _same_info(expected[1], got[1], vec)


def _same_step(expected: tuple[Any, ...], got: tuple[Any, ...], vec: FaultyMazeVectorEnv) -> None:
    _same_obs(expected[0], got[0])
    for want, have in zip(expected[1:4], got[1:4], strict=True):
        assert have.dtype == want.dtype
        np.testing.assert_array_equal(have, want)
    want_info, info = expected[4], got[4]
    _same_info(want_info, info, vec)
    assert ("final_obs" in info) == ("final_obs" in want_info)
    if "final_obs" in want_info:
        np.testing.assert_array_equal(info["_final_obs"], want_info["_final_obs"])
        for i in np.flatnonzero(want_info["_final_obs"]).tolist():
            _same_obs(want_info["final_obs"][i], info["final_obs"][i])
        _same_info(want_info["final_info"], info["final_info"], vec)


def _known_texts(sync: SyncVectorEnv, vec: FaultyMazeVectorEnv) -> None:
    domain = vec.domain
    for i, env in enumerate(sync.envs):
        assert domain.format_faults(vec.known(i)) == domain.format_faults(env.unwrapped.known)


_FAULTS = st.builds(
    FaultSpec,
    persistence=st.lists(
        st.sampled_from(list(Persistence)), min_size=1, max_size=3, unique=True
    ).map(tuple),
    detection=st.lists(st.sampled_from(SEEN), min_size=1, max_size=2, unique=True).map(tuple)
    | st.just((Detection.HIDDEN,)),
    at=st.tuples(st.just(0), st.integers(0, 6)),
    duration=st.tuples(st.just(1), st.integers(1, 8)),
    probability=st.tuples(st.floats(0.0, 0.5), st.floats(0.5, 1.0)),
)
_TASKS = st.fixed_dictionaries(
    {
        "domain": st.sampled_from(["four-wheel", "three-action"]),
        "mazes": st.sampled_from(
            ["bundled", "narrow-short", ("wide-short", MazeGenerator(7, 9, braid=0.5))]
        ),
        "routes": st.sampled_from(["bundled", "random"]),
        "faults": _FAULTS,
        "max_steps": st.integers(2, 25),
        "view_radius": st.integers(0, 4),
    }
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    task=_TASKS,
    n=st.integers(1, 4),
    mode=st.sampled_from(MODES),
    seed=st.integers(0, 2**31),
    data=st.data(),
)
def test_same_transitions_as_the_single_environment(
    task: dict[str, Any], n: int, mode: AutoresetMode, seed: int, data: st.DataObject
) -> None:
    domain = get_domain(task["domain"])
    if task["faults"].hidden:  # the partially observable variant, under any behaviour model
        names = [None, *domain.behaviour_names()]
        task = {**task, "behaviour": data.draw(st.sampled_from(names), label="behaviour")}
    sync, vec = _pair(n, mode, **task)
    count = len(domain.actions)
    _same_reset(sync.reset(seed=seed), vec.reset(seed=seed), vec)
    ended = np.zeros(n, dtype=np.bool_)
    for _ in range(data.draw(st.integers(1, 40), label="steps")):
        event = data.draw(st.sampled_from(["step"] * 8 + ["reset", "options"]), label="event")
        if event == "reset":
            again = data.draw(st.none() | st.integers(0, 2**31), label="reset seed")
            _same_reset(sync.reset(seed=again), vec.reset(seed=again), vec)
            ended[:] = False
        elif event == "options" or (mode is AutoresetMode.DISABLED and ended.any()):
            options: dict[str, Any] = dict(CORNER) if event == "options" else {}
            if ended.any():
                options["reset_mask"] = ended.copy()
            _same_reset(sync.reset(options=dict(options)), vec.reset(options=dict(options)), vec)
            ended[options.get("reset_mask", np.ones(n, dtype=np.bool_))] = False
        else:
            actions = np.array(
                data.draw(st.lists(st.integers(0, count - 1), min_size=n, max_size=n)),
                dtype=np.int64,
            )
            expected, got = sync.step(actions), vec.step(actions)
            _same_step(expected, got, vec)
            assert got[0] in vec.observation_space
            ended = expected[2] | expected[3]
        _known_texts(sync, vec)


def test_reaching_the_goal_terminates_with_the_bonus_then_autoresets() -> None:
    """Hand-made: three-action robot, goal one cell ahead, no fault; forward (action F)."""
    faults = FaultSpec(sets=("",))
    sync, vec = _pair(2, AutoresetMode.NEXT_STEP, domain="three-action", faults=faults)
    forward = get_domain("three-action").actions.index("F")
    _same_reset(sync.reset(seed=1, options=CORNER), vec.reset(seed=1, options=CORNER), vec)
    step = vec.step(np.array([forward, forward]))
    _same_step(sync.step(np.array([forward, forward])), step, vec)
    assert step[2].tolist() == [True, True] and step[1].tolist() == [99.0, 99.0]  # 100 - 1 tick
    step = vec.step(np.array([0, 0]))  # the next step resets: reward 0, flags false
    _same_step(sync.step(np.array([0, 0])), step, vec)
    assert step[1].tolist() == [0.0, 0.0] and step[4]["_maze"].all()
    assert OUTCOME_NAMES[step[4]["outcome"][0]] == ""


def test_failed_attempts_reveal_faults_on_use() -> None:
    """A permanent fault detected on use: the first forbidden command fails (one tick, the
    penalty) and the fault shows in the observation from then on, as in the single env."""
    domain = get_domain("three-action")
    schedule = FaultSchedule.permanent(domain.parse_faults("F"), detection=Detection.ON_USE)
    options = {**CORNER, "faults": schedule}
    rewards = Rewards(fault_penalty=5.0)
    sync, vec = _pair(1, AutoresetMode.NEXT_STEP, domain="three-action", rewards=rewards)
    _same_reset(sync.reset(seed=0, options=options), vec.reset(seed=0, options=options), vec)
    forward = np.array([domain.actions.index("F")])
    expected, got = sync.step(forward), vec.step(forward)
    _same_step(expected, got, vec)
    assert OUTCOME_NAMES[got[4]["outcome"][0]] == "failed-attempt"
    assert got[1][0] == -6.0 and got[0]["faults"][0].tolist() == [1, 0, 0]
    assert domain.format_faults(vec.known(0)) == "F"


@pytest.mark.parametrize("clock", list(Clock))
def test_transient_and_intermittent_faults_on_both_clocks(clock: Clock) -> None:
    domain = get_domain("four-wheel")
    fl, fr = sorted(domain.parse_faults("FL:F,FR:S"))
    schedule = FaultSchedule(
        (
            FaultEvent(fl, 2, clock=clock, persistence=Persistence.TRANSIENT, duration=3),
            FaultEvent(fr, 1, clock=clock, persistence=Persistence.INTERMITTENT, probability=0.5),
        ),
        Detection.NOW,
    )
    options = {"maze": "wide-short", "faults": schedule}
    sync, vec = _pair(3, AutoresetMode.SAME_STEP, max_steps=15)
    _same_reset(sync.reset(seed=4, options=options), vec.reset(seed=4, options=options), vec)
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(40):
        actions = rng.integers(len(domain.actions), size=3)
        _same_step(sync.step(actions), got := vec.step(actions), vec)
        seen.update(map(tuple, got[0]["faults"].tolist()))
    assert len(seen) >= 3  # faults came and went


def _same_raw(expected: tuple[Any, ...], got: tuple[Any, ...]) -> None:
    """Two vector environments' results are equal, array for array."""
    assert len(expected) == len(got)
    _same_obs(expected[0], got[0])
    for want, have in zip(expected[1:-1], got[1:-1], strict=True):
        np.testing.assert_array_equal(have, want)
    want_info, info = expected[-1], got[-1]
    assert want_info.keys() == info.keys()
    for key, value in want_info.items():
        if key == "final_obs":
            for a, b in zip(value, info[key], strict=True):
                assert (a is None) == (b is None)
                if a is not None:
                    _same_obs(a, b)
        elif key == "final_info":
            assert value.keys() == info[key].keys()
            for name, array in value.items():
                np.testing.assert_array_equal(info[key][name], array)
        else:
            np.testing.assert_array_equal(info[key], value, err_msg=key)


@NUMBA
def test_the_compiled_kernel_agrees_with_the_interpreted_one() -> None:
    task = {
        "faults": FaultSpec(
            persistence=tuple(Persistence), detection=tuple(SEEN), at=(0, 4), duration=(1, 9)
        ),
        "mazes": ("bundled", MazeGenerator(11, 11)),
        "routes": "random",
        "max_steps": 30,
    }
    for mode in MODES:
        slow = FaultyMazeVectorEnv(6, backend="python", autoreset_mode=mode, **task)
        fast = FaultyMazeVectorEnv(6, backend="numba", autoreset_mode=mode, **task)
        _same_raw(slow.reset(seed=3), fast.reset(seed=3))
        rng = np.random.default_rng(1)
        for _ in range(120):
            ended = slow._ended.copy()
            if mode is AutoresetMode.DISABLED and ended.any():
                mask = {"reset_mask": ended}
                _same_raw(slow.reset(options=dict(mask)), fast.reset(options=dict(mask)))
            actions = rng.integers(81, size=6)
            _same_raw(slow.step(actions), fast.step(actions))
            np.testing.assert_array_equal(fast._state, slow._state)
            np.testing.assert_array_equal(fast._known, slow._known)


@NUMBA
@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), index=st.integers(0, 63), step=st.integers(0, 2**32 - 1))
def test_the_kernel_draws_what_numpy_draws(seed: int, index: int, step: int) -> None:
    expected = np.random.default_rng([seed, index, step]).random()
    assert kernels.uniform_numba(seed, index, step) == expected


def _run(vec: FaultyMazeVectorEnv, seed: int, steps: int) -> list[Any]:
    out: list[Any] = [vec.reset(seed=seed)]
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        out.append(vec.step(rng.integers(len(vec.domain.actions), size=vec.num_envs)))
    return out


def test_env_checker_style_checks() -> None:
    """What gymnasium.utils.env_checker checks of one env, for the batch: spaces, seeded resets
    and steps are deterministic, returned arrays are fresh, observations lie in the space."""
    vec = FaultyMazeVectorEnv(5, domain="three-action")
    single = FaultyMazeEnv(domain="three-action")
    assert vec.single_observation_space == single.observation_space
    assert vec.single_action_space == single.action_space
    assert vec.observation_space == batch_space(single.observation_space, 5)
    assert vec.action_space == batch_space(single.action_space, 5)
    assert isinstance(vec.metadata["autoreset_mode"], AutoresetMode)
    first, second = _run(vec, 7, 60), _run(FaultyMazeVectorEnv(5, domain="three-action"), 7, 60)
    for a, b in zip(first, second, strict=True):
        _same_obs(a[0], b[0])
        if len(a) == 5:
            for x, y in zip(a[1:4], b[1:4], strict=True):
                np.testing.assert_array_equal(x, y)
    other = _run(vec, 8, 0)[0][0]
    assert any(not np.array_equal(other[k], first[0][0][k]) for k in other)  # seeds matter
    for a, b in itertools.pairwise(first):
        for key in a[0]:
            assert not np.shares_memory(a[0][key], b[0][key])
        assert b[0] in vec.observation_space
    obs, info = vec.reset(seed=[3, 1, 4, 1, 5])
    assert info["np_random_seed"].tolist() == [3, 1, 4, 1, 5]
    assert obs in vec.observation_space


def test_registered_for_make_vec() -> None:
    vec = gym.make_vec(ENV_ID, num_envs=3, vectorization_mode="vector_entry_point",
                       domain="three-action")  # fmt: skip
    assert isinstance(vec.unwrapped, FaultyMazeVectorEnv) and vec.num_envs == 3
    obs, _ = vec.reset(seed=0)
    assert obs["window"].shape == (3, 7, 7)
    assert isinstance(gym.make_vec(ENV_ID, num_envs=2).unwrapped, FaultyMazeVectorEnv)
    sync = gym.make_vec(ENV_ID, num_envs=2, vectorization_mode="sync")
    assert isinstance(sync, SyncVectorEnv)


def test_render_and_robot_state() -> None:
    vec = FaultyMazeVectorEnv(2, domain="three-action", render_mode="ansi")
    vec.reset(seed=0, options=CORNER)
    frames = vec.render()
    assert frames is not None and len(frames) == 2 and "known faults" in frames[0]
    single = FaultyMazeEnv(domain="three-action", render_mode="ansi")
    single.reset(seed=0, options=CORNER)
    assert frames[0] == single.render()
    assert vec.pose(1) == single.pose and vec.scenario(0).goal == (2, 1)
    rgb = FaultyMazeVectorEnv(1, render_mode="rgb_array")
    rgb.reset(seed=0)
    single = FaultyMazeEnv(render_mode="rgb_array")
    single.reset(seed=0)
    got = rgb.render()
    assert got is not None
    np.testing.assert_array_equal(got[0], single.render())
    assert FaultyMazeVectorEnv(1).render() is None


def test_misuse_is_a_problem_error() -> None:
    vec = FaultyMazeVectorEnv(2, max_steps=1, autoreset_mode="Disabled")
    with pytest.raises(ProblemError, match="reset"):
        vec.step(np.array([0, 0]))
    vec.reset(seed=0)
    with pytest.raises(ProblemError, match="action indices"):
        vec.step(np.array([0, 81]))
    vec.step(np.array([0, 0]))  # max_steps 1: both truncated
    with pytest.raises(ProblemError, match="autoreset is disabled"):
        vec.step(np.array([0, 0]))
    vec.reset(options={"reset_mask": np.array([True, True])})
    vec.step(np.array([0, 0]))
    for bad in (
        {"guide": True}, {"backend": "gpu"}, {"view_radius": 40}, {"max_steps": 0},
        {"behaviour": "stall"},
    ):  # fmt: skip
        with pytest.raises(ProblemError):
            FaultyMazeVectorEnv(2, **bad)
    schedule = FaultSchedule.permanent(get_domain("four-wheel").parse_faults("FL:F"),
                                       detection=Detection.HIDDEN)  # fmt: skip
    with pytest.raises(ProblemError, match="tells the robot its faults"):
        FaultyMazeVectorEnv(1).reset(options={"faults": schedule})
    with pytest.raises(ProblemError, match="hidden"):
        FaultSpec(detection=(Detection.HIDDEN, Detection.NOW))
    with pytest.raises(ProblemError, match="seeds"):
        FaultyMazeVectorEnv(2).reset(seed=[1])
    with pytest.raises(ProblemError, match="reset_mask"):
        FaultyMazeVectorEnv(2).reset(options={"reset_mask": np.array([True, False])})


HIDDEN = FaultSpec(detection=(Detection.HIDDEN,))


def test_hidden_faults_single_env_passes_the_checker_and_shows_no_faults() -> None:
    """The partially observable variant: Gymnasium's checker passes, the observation has no
    fault flags, a fault-set reset option is hidden too."""
    from gymnasium.utils.env_checker import check_env

    env = gym.make(HIDDEN_ENV_ID, behaviour="reverse")
    check_env(env.unwrapped, skip_render_check=True)
    obs, info = env.reset(seed=0, options={"faults": "FL:F"})
    assert "faults" not in obs and "faults" not in env.observation_space.spaces
    assert info["detection"] == "hidden"
    assert FaultyMazeEnv(faults=HIDDEN).observation_space == env.observation_space
    with pytest.raises(ProblemError, match="hidden"):
        FaultyMazeEnv(behaviour="stall")
    with pytest.raises(ProblemError, match="unknown fault behaviour"):
        FaultyMazeEnv(faults=HIDDEN, behaviour="no-such-model")


def test_hidden_faults_bump_into_walls_in_both_envs() -> None:
    """Hand-made: three-action robot (no fault-behaviour model), faults hidden, facing the wall
    north of 1,1: forward is a bump (one tick and the blocked penalty, no move); its fault F
    makes forward fail (one tick and the fault penalty) and names nothing."""
    options = {"maze": "narrow-short", "start": "1,1,N", "goal": "2,1", "faults": ""}
    sync, vec = _pair(1, AutoresetMode.NEXT_STEP, domain="three-action", faults=HIDDEN)
    _same_reset(sync.reset(seed=0, options=options), vec.reset(seed=0, options=options), vec)
    forward = np.array([get_domain("three-action").actions.index("F")])
    _same_step(sync.step(forward), got := vec.step(forward), vec)
    assert OUTCOME_NAMES[got[4]["outcome"][0]] == "bumped"
    assert got[1][0] == -2.0 and got[4]["ticks"][0] == 1.0
    assert got[4]["pose"][0].tolist() == [1, 1, int(Heading.N)]
    options = {**options, "start": "1,1,E", "faults": "F"}
    _same_reset(sync.reset(options=options), vec.reset(options=options), vec)
    _same_step(sync.step(forward), got := vec.step(forward), vec)
    assert OUTCOME_NAMES[got[4]["outcome"][0]] == "failed-attempt" and not vec.known(0)


def test_hidden_faults_perform_the_effective_action() -> None:
    """Four-wheel robot, FL:F hidden: each forbidden command moves as Domain.effective says, in
    every fault-behaviour model, in both environments."""
    domain = get_domain("four-wheel")
    faults = domain.parse_faults("FL:F")
    options = {"maze": "wide-long", "faults": "FL:F"}
    forbidden = [i for i, a in enumerate(domain.actions) if not domain.available(a, faults)]
    for behaviour in domain.behaviour_names():
        sync, vec = _pair(2, AutoresetMode.NEXT_STEP, faults=HIDDEN, behaviour=behaviour)
        _same_reset(sync.reset(seed=5, options=options), vec.reset(seed=5, options=options), vec)
        moved = 0
        for index in forbidden[:12]:
            before = vec.pose(0)
            actions = np.array([index, index])
            _same_step(sync.step(actions), got := vec.step(actions), vec)
            performed = domain.effective(domain.actions[index], faults, behaviour)
            if OUTCOME_NAMES[got[4]["outcome"][0]] == "moved":
                moved += 1
                assert vec.pose(0) == domain.apply(before, performed)
        assert moved > 0
