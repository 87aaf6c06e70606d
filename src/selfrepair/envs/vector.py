"""``FaultyMazeVectorEnv``: N faulty robots in one Gymnasium ``VectorEnv``, one kernel call a step.

The same task as :class:`~selfrepair.envs.env.FaultyMazeEnv`, for RL code that needs millions of
steps: robot ``i`` of the batch sees exactly what a ``FaultyMazeEnv`` reset with the same seed and
given the same actions sees (observations, rewards, terminations, truncations; a property test
compares them step for step with ``gymnasium.vector.SyncVectorEnv`` over ``FaultyMazeEnv``). Its
episodes are drawn in Python by the single environment's own :mod:`~selfrepair.envs.scenarios`
from the robot's own ``np_random``; the steps run in :mod:`~selfrepair.envs._vector_kernels` over
integer tables made from the domain (:mod:`~selfrepair.envs.vector_tables`): the move table, the
actions each fault set leaves available and the faults a failed attempt reveals. Faults appear and
clear as the episode's fault schedule says (permanent, transient, intermittent; step or tick
clock), with detection ``now`` or ``on-use``, as in the simulator; or, in the partially observable
variant (detection ``hidden``, ``selfrepair/FaultyMazeHidden-v0``), the agent is told nothing of
its faults (no ``faults`` key) and the wheels do what ``Domain.effective`` says.

Spaces: ``single_observation_space`` and ``single_action_space`` are the single environment's;
``observation_space`` and ``action_space`` are Gymnasium's batches of them
(``gymnasium.vector.utils.batch_space``). ``reset(seed=s)`` seeds robot ``i`` with ``s + i`` (a list
gives one seed per robot), as ``SyncVectorEnv`` does. ``reset(options=...)`` takes the single
environment's options (applied to every robot reset) and ``reset_mask``.

Autoreset (``autoreset_mode``, in ``metadata["autoreset_mode"]``), Gymnasium 1.x's three modes:
``NEXT_STEP`` (the default, as in ``SyncVectorEnv``: the step after an episode ends resets that
robot, ignores its action and returns its first observation with reward 0 and both flags false),
``SAME_STEP`` (the ending step resets at once; the last observation and info are in
``info["final_obs"]`` and ``info["final_info"]``) and ``DISABLED`` (reset ended robots with
``reset(options={"reset_mask": mask})``; stepping one that is not reset is an error).

``info`` holds arrays over the robots, each key with its ``_key`` mask as Gymnasium's vector
environments do: ``outcome`` (codes into :data:`OUTCOME_NAMES`: the single environment's
``outcome`` text), ``pose`` (``(x, y, heading)`` rows) and ``ticks`` at every step, and for the
robots reset in the call the single environment's episode keys (``maze``, ``start``, ``goal``,
``faults``, ``schedule``, ``detection``, ``fault_seed``, ``np_random_seed``, ``max_steps``). The
known faults are the observation's ``faults`` (their text is :meth:`known_text`). There is no guide
(it plans in Python per robot). The info arrays are put together in
:mod:`~selfrepair.envs.vector_info`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from selfrepair.envs import _vector_kernels as kernels
from selfrepair.envs.env import Rewards
from selfrepair.envs.render import ansi_frame, check_cell_pixels, maze_frame, rgb_frame
from selfrepair.envs.scenarios import (
    BUNDLED,
    FaultSpec,
    MazeSpec,
    RouteChoice,
    Scenario,
    draw_scenario,
    maze_sources,
    with_options,
)
from selfrepair.envs.settings import check_behaviour, check_settings, observation_space
from selfrepair.envs.vector_info import (
    EPISODE_KEYS,
    Array,
    Episodes,
    batch_seeds,
    copy_obs,
    final_info,
    step_info,
)
from selfrepair.envs.vector_tables import FaultSets, GridStore, motion_tables
from selfrepair.errors import ProblemError, choice
from selfrepair.execution.faults import Clock, Detection, Persistence
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.registry import get_domain
from selfrepair.search.astar import BACKENDS

__all__ = ["MAX_EVENTS", "OUTCOME_NAMES", "FaultyMazeVectorEnv"]

OUTCOME_NAMES = kernels.OUTCOME_NAMES
"""``info["outcome"]`` code -> the single environment's outcome text (0: a reset)."""

MAX_EVENTS = 10
"""The most fault events one episode's schedule may have (the kernel tabulates every subset)."""

_KINDS = {
    Persistence.PERMANENT: kernels.PERMANENT,
    Persistence.TRANSIENT: kernels.TRANSIENT,
    Persistence.INTERMITTENT: kernels.INTERMITTENT,
}
_S = kernels  # column names below
Bools = npt.NDArray[np.bool_]


class FaultyMazeVectorEnv(VectorEnv[dict[str, Array], Array, Array]):
    """See the module docstring. ``num_envs`` robots; the keywords ``domain``, ``mazes``,
    ``routes``, ``faults``, ``rewards``, ``max_steps``, ``view_radius``, ``render_mode`` and
    ``cell_pixels`` and ``behaviour`` mean what they mean for
    :class:`~selfrepair.envs.env.FaultyMazeEnv`.
    ``autoreset_mode``: an :class:`~gymnasium.vector.AutoresetMode` or its value.
    ``backend``: ``"numba"`` (the compiled kernel, the ``fast`` extra), ``"python"`` (the same
    kernel interpreted: the reference, slow) or ``"auto"`` (numba when installed)."""

    metadata = {  # noqa: RUF012 (Gymnasium's)
        "render_modes": ["ansi", "rgb_array"],
        "render_fps": 8,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        *,
        domain: str | SomeDomain = "four-wheel",
        mazes: MazeSpec | Sequence[MazeSpec] = BUNDLED,
        routes: str = RouteChoice.BUNDLED,
        faults: FaultSpec | None = None,
        rewards: Rewards | None = None,
        max_steps: int | None = None,
        view_radius: int = 3,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        backend: str = "auto",
        render_mode: str | None = None,
        cell_pixels: int = 8,
        behaviour: str | None = None,
        guide: bool = False,
    ) -> None:
        if guide:
            raise ProblemError(
                "the vector environment has no guide (it plans in Python, robot by robot); use "
                "gymnasium.vector.SyncVectorEnv over FaultyMazeEnv(guide=True)"
            )
        if num_envs < 1:
            raise ProblemError(f"num_envs must be at least 1, got {num_envs}")
        check_settings(max_steps, view_radius, render_mode, self.metadata["render_modes"])
        self.num_envs = num_envs
        self.domain = get_domain(domain) if isinstance(domain, str) else domain
        self.sources = maze_sources(mazes)
        self.routes = choice(RouteChoice, routes, "route choice")
        self.faults = faults or FaultSpec()
        self.hidden = self.faults.hidden
        self.behaviour = check_behaviour(self.domain, self.hidden, behaviour)
        self._fault_sets = self.faults.fault_sets(self.domain)
        self.rewards = rewards or Rewards()
        self.max_steps = max_steps
        self.view_radius = view_radius
        self.render_mode = render_mode
        self.cell_pixels = check_cell_pixels(cell_pixels)
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        self.backend = choice_backend(backend)
        self.single_observation_space = observation_space(
            self.domain, self.sources, view_radius, self.hidden
        )
        self.single_action_space = _discrete(len(self.domain.actions))
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self._motion = motion_tables(self.domain)
        self._sets = FaultSets(self.domain, self._motion.table, self.hidden, self.behaviour)
        margin = max(view_radius, self._motion.reach, 1)
        fixed = tuple(s.maze for s in self.sources if s.maze is not None)
        generated = [s.generator for s in self.sources if s.generator is not None]
        region = max(((max(g.width, g.height) + 2 * margin) ** 2 for g in generated), default=0)
        self._grids = GridStore(fixed, num_envs, margin, region)
        n = num_envs
        self._state = np.zeros((n, kernels.STATE_COLUMNS), dtype=np.int64)
        self._known = np.zeros(n, dtype=np.uint64)
        self._elapsed = np.zeros(n, dtype=np.float64)
        self._current = np.zeros(n, dtype=np.int64)
        self._events = np.zeros((n, 0, kernels.EVENT_COLUMNS), dtype=np.int64)
        self._chance = np.zeros((n, 0), dtype=np.float64)
        self._subsets = np.zeros((n, 1), dtype=np.int64)
        self._draws = np.zeros((n, 0), dtype=np.float64)
        self._grow_events(min(max([len(s) for s in self._fault_sets] + [1]), MAX_EVENTS))
        r = self.rewards
        self._terms = np.array(
            (r.fault_penalty, r.blocked_penalty, r.goal_bonus, float(FAILED_ATTEMPT_TICKS)),
            dtype=np.float64,
        )
        self._scenarios: list[Scenario | None] = [None] * num_envs
        self._rngs: list[np.random.Generator | None] = [None] * num_envs
        self._seeds: list[int | None] = [None] * num_envs
        self._ended = np.zeros(num_envs, dtype=np.bool_)
        self._started = False
        self._all = np.arange(num_envs, dtype=np.int64)
        self._no_actions = np.zeros(num_envs, dtype=np.int64)
        self._intermittent = np.zeros(num_envs, dtype=np.bool_)
        self._outcome = np.zeros(num_envs, dtype=np.int8)
        self._obs = self._outputs()
        self._frames: list[npt.NDArray[np.uint8] | None] = [None] * num_envs
        self._no_faults = np.zeros((n, 0), dtype=np.int8)
        use_numba = self.backend == "numba"
        step = kernels.STEP_NUMBA if use_numba else kernels.STEP_PYTHON
        assert step is not None  # choice_backend refused numba without numba
        self._step = step
        self._draw = (
            kernels.intermittent_draws_numba if use_numba else kernels.intermittent_draws_numpy
        )

    def _grow_events(self, events: int) -> None:
        """Room for ``events`` schedule events per robot (the rows already loaded kept)."""
        n, have = self.num_envs, self._events.shape[1]
        grown_events = np.zeros((n, events, kernels.EVENT_COLUMNS), dtype=np.int64)
        grown_chance = np.zeros((n, events), dtype=np.float64)
        grown_subsets = np.zeros((n, 1 << events), dtype=np.int64)
        grown_events[:, :have] = self._events
        grown_chance[:, :have] = self._chance
        grown_subsets[:, : 1 << have] = self._subsets
        self._events, self._chance, self._subsets = grown_events, grown_chance, grown_subsets
        self._draws = np.zeros((n, events), dtype=np.float64)

    # --- the Gymnasium API --------------------------------------------------------------------

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[dict[str, Array], dict[str, object]]:
        """Reset every robot (or those of ``options["reset_mask"]``); ``seed``: ``None``, an int
        (robot ``i`` gets ``seed + i``) or one seed per robot."""
        seeds = batch_seeds(seed, self.num_envs)
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            which = self._all
        else:
            mask = np.asarray(mask)
            if mask.shape != (self.num_envs,) or mask.dtype != np.bool_ or not mask.any():
                raise ProblemError(
                    f"options['reset_mask'] must be a bool array of shape ({self.num_envs},) "
                    "with at least one True"
                )
            if not self._started:
                raise ProblemError("reset_mask needs a first reset() of every robot")
            which = np.flatnonzero(mask).astype(np.int64)
        infos = self._reset_robots(which, seeds, options)
        self._run(which, self._no_actions, *self._flags())
        self._started = True
        self._ended[which] = False
        return copy_obs(self._obs), self._info(which, infos)

    def step(
        self, actions: Array | Sequence[int]
    ) -> tuple[dict[str, Array], Array, Array, Array, dict[str, object]]:
        """One command per robot (action indices into ``domain.actions``)."""
        if not self._started:
            raise ProblemError("the environment has no episode yet: call reset() first")
        acts = np.asarray(actions, dtype=np.int64).reshape(-1)
        count = len(self.domain.actions)
        if acts.shape != (self.num_envs,) or acts.min() < 0 or acts.max() >= count:
            raise ProblemError(
                f"expected {self.num_envs} action indices from 0 to {count - 1}, got {actions!r}"
            )
        infos: Episodes = {}
        reset_now = np.zeros(0, dtype=np.int64)
        if self._ended.any():
            if self.autoreset_mode is AutoresetMode.DISABLED:
                robot = int(np.flatnonzero(self._ended)[0])
                raise ProblemError(
                    f"robot {robot}'s episode has ended and autoreset is disabled: reset it "
                    "with reset(options={'reset_mask': mask})"
                )
            reset_now = np.flatnonzero(self._ended).astype(np.int64)
            infos = self._reset_robots(reset_now, [None] * self.num_envs, {})
            self._ended[:] = False
        reward, terminated, truncated, outcome = self._flags()
        self._run(self._all, acts, reward, terminated, truncated, outcome)
        done = terminated | truncated
        info_robots = self._all
        final: dict[str, object] = {}
        if self.autoreset_mode is AutoresetMode.SAME_STEP and done.any():
            ended = np.flatnonzero(done).astype(np.int64)
            final = final_info(self._obs, self._outcome, self._state, self._elapsed, ended)
            infos = self._reset_robots(ended, [None] * self.num_envs, {})
            self._run(ended, acts, reward, terminated, truncated, outcome)
            reset_now = ended
        else:
            self._ended = done
        info = self._info(info_robots, infos, reset_now)
        info.update(final)
        return copy_obs(self._obs), reward, terminated, truncated, info

    def render(self) -> tuple[str | npt.NDArray[np.uint8], ...] | None:
        """Every robot's frame of ``render_mode`` (``None`` without a render mode)."""
        if self.render_mode is None:
            return None
        frames: list[str | npt.NDArray[np.uint8]] = []
        for i in range(self.num_envs):
            scenario, pose = self.scenario(i), self.pose(i)
            if self.render_mode == "ansi":
                status = f"step {int(self._state[i, _S._STEPS])}, known faults "
                frames.append(
                    ansi_frame(scenario.maze, pose, scenario.goal, (status + self.known_text(i),))
                )
            else:
                background = self._frames[i]
                if background is None:
                    background = maze_frame(scenario.maze, scenario.goal, self.cell_pixels)
                    self._frames[i] = background
                frames.append(rgb_frame(background, pose, self.cell_pixels))
        return tuple(frames)

    # --- robot state, read by tests and policies ----------------------------------------------

    def scenario(self, robot: int) -> Scenario:
        """Robot ``robot``'s current episode (maze, route, true fault schedule)."""
        scenario = self._scenarios[robot]
        if scenario is None:
            raise ProblemError("the environment has no episode yet: call reset() first")
        return scenario

    def pose(self, robot: int) -> Pose:
        """Robot ``robot``'s pose now."""
        row = self._state[robot]
        return Pose(int(row[_S._X]), int(row[_S._Y]), Heading(int(row[_S._HEAD])))

    def known(self, robot: int) -> frozenset[object]:
        """The faults robot ``robot`` knows now."""
        return self._sets.faults_of(int(self._known[robot]))

    def known_text(self, robot: int) -> str:
        """:meth:`known` in the domain's text, ``"none"`` when empty (the ansi status line)."""
        return self.domain.format_faults(self.known(robot)) or "none"

    # --- internals ------------------------------------------------------------------------------

    def _run(
        self, which: Array, actions: Array, reward: Array, terminated: Bools, truncated: Bools,
        outcome: npt.NDArray[np.int8],
    ) -> None:  # fmt: skip
        """One kernel call over robots ``which`` (intermittent draws first, when any); it
        updates the environment's own observation arrays, which the API returns copies of."""
        obs = self._obs
        if self._intermittent.any():
            self._draw(which, self._state, self._events, self._draws)
        sets, motion = self._sets, self._motion
        flags = obs.get("faults", self._no_faults)
        self._step(
            which, actions, self._state, self._known, self._elapsed, self._current,
            self._events, self._chance, self._draws, self._subsets,
            sets.set_bits, sets.avail, sets.blocking, sets.effective,
            motion.moves, motion.durations, motion.footprints, self._grids.grid, self._terms,
            self.view_radius, motion.failed_units,
            obs["window"], obs["heading"], obs["goal"], flags,
            reward, terminated, truncated, outcome,
        )  # fmt: skip
        self._outcome = outcome

    def _flags(self) -> tuple[Array, Bools, Bools, npt.NDArray[np.int8]]:
        n = self.num_envs
        return (
            np.zeros(n, dtype=np.float64),
            np.zeros(n, dtype=np.bool_),
            np.zeros(n, dtype=np.bool_),
            np.zeros(n, dtype=np.int8),
        )

    def _outputs(self) -> dict[str, Array]:
        n, side = self.num_envs, 2 * self.view_radius + 1
        obs: dict[str, Array] = {
            "window": np.empty((n, side, side), dtype=np.int8),
            "heading": np.empty(n, dtype=np.int64),
            "goal": np.empty((n, 2), dtype=np.int32),
        }
        if self.domain.faults and not self.hidden:
            obs["faults"] = np.empty((n, len(self.domain.faults)), dtype=np.int8)
        return obs

    def _reset_robots(
        self, which: Array, seeds: Sequence[int | None], options: dict[str, Any]
    ) -> Episodes:
        """Draw and load a new episode for each robot of ``which``; their episode info."""
        infos: Episodes = {key: [] for key in EPISODE_KEYS}
        for robot in which.tolist():
            seed = seeds[robot]
            rng = self._rngs[robot]
            if seed is not None or rng is None:
                rng, self._seeds[robot] = seeding.np_random(seed)
                self._rngs[robot] = rng
            scenario = draw_scenario(
                self.sources, self.routes, self.domain, self.faults, rng, self._fault_sets
            )
            if options:
                scenario = with_options(scenario, options, self.domain, rng, self.hidden)
            self._load(robot, scenario)
            schedule = scenario.schedule
            row = (
                scenario.maze_label, str(scenario.start), f"{scenario.goal[0]},{scenario.goal[1]}",
                self.domain.format_faults(schedule.all_faults()), schedule.describe(),
                schedule.detection.value, scenario.fault_seed, self._seeds[robot],
                int(self._state[robot, _S._LIMIT]),
            )  # fmt: skip
            for key, value in zip(EPISODE_KEYS, row, strict=True):
                infos[key].append(value)
        return infos

    def _info(
        self, which: Array, episodes: Episodes, reset: Array | None = None
    ) -> dict[str, object]:
        """The info of robots ``which`` and of the robots reset (see :func:`step_info`)."""
        return step_info(self._outcome, self._state, self._elapsed, which, episodes, reset)

    def _load(self, robot: int, scenario: Scenario) -> None:
        """Put ``scenario`` into robot ``robot``'s rows, pending its first observation."""
        maze, schedule = scenario.maze, scenario.schedule
        events = schedule.events
        if len(events) > MAX_EVENTS:
            raise ProblemError(
                f"the vector environment takes at most {MAX_EVENTS} fault events per episode, "
                f"got {len(events)}"
            )
        if len(events) > self._events.shape[1]:
            self._grow_events(len(events))
        if scenario.fault_seed >= 1 << 32:
            raise ProblemError(f"fault seeds must be below 2**32, got {scenario.fault_seed}")
        base, stride, rebuilt = self._grids.place(robot, maze)
        if rebuilt:  # every robot with a maze of its own moved in the buffer
            for other, held in enumerate(self._scenarios):
                if held is not None and other != robot:
                    self._state[other, _S._BASE] = self._grids.base_of(other, held.maze)
        row = self._state[robot]
        start, goal = scenario.start, scenario.goal
        unit = self._motion.table.unit
        row[:] = 0
        row[_S._X], row[_S._Y], row[_S._HEAD] = start.x, start.y, int(start.heading)
        row[_S._GX], row[_S._GY] = goal
        row[_S._LIMIT] = self.max_steps or 4 * maze.width * maze.height
        row[_S._BASE], row[_S._STRIDE] = base, stride
        row[_S._SENSES] = schedule.detection is Detection.NOW
        row[_S._PENDING] = 1
        row[_S._EVENTS] = len(events)
        row[_S._SEED] = scenario.fault_seed
        row[_S._HIDDEN] = schedule.detection is Detection.HIDDEN
        table = self._events[robot]
        table[:] = 0
        self._chance[robot] = 0.0
        for j, event in enumerate(events):
            scale = unit if event.clock is Clock.TICK else 1
            end = event.at + (event.duration or 0)
            table[j] = (0, event.at * scale, end * scale, _KINDS[event.persistence],
                        int(event.clock is Clock.TICK))  # fmt: skip
            self._chance[robot, j] = event.probability or 0.0
        faults = [event.fault for event in events]
        for m in range(1 << len(events)):
            chosen = frozenset(f for j, f in enumerate(faults) if m >> j & 1)
            self._subsets[robot, m] = self._sets.id_of(chosen)
        self._intermittent[robot] = any(e.persistence is Persistence.INTERMITTENT for e in events)
        self._elapsed[robot] = 0.0
        self._known[robot] = 0
        self._scenarios[robot] = scenario
        self._frames[robot] = None


def choice_backend(backend: str) -> str:
    """``"numba"`` or ``"python"`` for ``backend`` (one of ``auto``, ``numba``, ``python``);
    ``"numba"`` without numba is a :class:`ProblemError`."""
    if backend not in BACKENDS:
        raise ProblemError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if backend == "numba" and not kernels.NUMBA:
        raise ProblemError(
            "backend 'numba' requested but numba is not installed: pip install 'selfrepair[fast]'"
        )
    if backend == "auto":
        return "numba" if kernels.NUMBA else "python"
    return backend


def _discrete(n: int) -> Any:
    from gymnasium import spaces

    return spaces.Discrete(n)
