"""``selfrepair/FaultyMaze-v0``: a robot with faults driving through a maze, as a Gymnasium task.

The robot is any registered :class:`~selfrepair.robots.domain.Domain` (``domain=``, default
``four-wheel``); an action is an index into ``domain.actions``. Motion and faults are the project's
own world model: every command goes to a :class:`~selfrepair.execution.simulator.Simulator`, which
moves the robot by the domain's move table (:mod:`selfrepair.execution.moves`) and holds the true
faults of the episode's :class:`~selfrepair.execution.faults.FaultSchedule`.
The agent sees only what the executor would:

``window``
    The free cells (1) and walls (0) of the ``(2r+1) x (2r+1)`` square centred on the robot
    (``r = view_radius``; outside the maze counts as wall), north up.
``heading``
    The robot's heading, 0..3 for N, E, S, W.
``goal``
    The goal's offset ``(dx, dy)`` from the robot's cell (x east, y south).
``faults``
    The faults the robot knows, one flag per ``domain.faults`` entry (absent for a domain without
    faults). With detection ``now`` the robot senses the active faults before every step; with
    ``on-use`` it learns a fault when an action it forbids fails.

Reward per step: minus the step's duration in ticks; a failed attempt (an action a true fault
forbids: the robot does not move, one tick passes) also costs ``fault_penalty``; a blocked command
(its footprint is not free: the simulator refuses it, nothing changes) costs ``blocked_penalty``;
reaching the goal cell adds ``goal_bonus`` and terminates the episode. ``max_steps`` commands
without reaching the goal truncate it.

Episodes are drawn by :mod:`selfrepair.envs.scenarios` from the environment's ``np_random``, so
``reset(seed=s)`` fixes the maze, the route, the faults and the seed of intermittent faults;
``reset(options=...)`` can fix any of them (see :meth:`FaultyMazeEnv.reset`).

Every ``info`` has ``outcome`` (the simulator's :class:`~selfrepair.execution.simulator.Outcome`,
``""`` at reset), ``pose`` (``"x,y,H"``), ``known_faults`` (their text) and ``ticks`` (elapsed);
the reset ``info`` also describes the episode's draw. With ``guide=True``, ``info`` carries the
*guide*'s hints: a :class:`~selfrepair.execution.stepper.Stepper` (the executor's own loop, asked
one step at a time) with the ``replacement`` strategy and the environment's table, which plans
from the start without knowing any fault (as the executor does) and follows the robot.
``planned_action`` is what it would command now; when its next planned action is faulty under
the known faults, ``faulty_action`` is that action and ``replacement`` the table's suggestion (the
first valid candidate, as action indices). Off the plan the guide replans, which costs a planner
call per deviating step, so the guide is off unless ``guide=True``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium import spaces

from selfrepair.envs.guide import ask, followed
from selfrepair.envs.render import ansi_frame, check_cell_pixels, maze_frame, rgb_frame
from selfrepair.envs.scenarios import (
    BUNDLED,
    FaultSpec,
    MazeSource,
    MazeSpec,
    RouteChoice,
    Scenario,
    draw_scenario,
    maze_sources,
    with_options,
)
from selfrepair.envs.settings import (
    MAX_VIEW_RADIUS,
    check_behaviour,
    check_settings,
    observation_space,
)
from selfrepair.errors import ProblemError, choice
from selfrepair.execution.context import mission_context
from selfrepair.execution.faults import Detection
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS, Outcome, Simulator, StepOutcome
from selfrepair.execution.stepper import Entry, Stepper
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import (
    RepairSource,
    StrategyName,
    StrategyOptions,
    get_strategy,
    uses_table,
)
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.registry import get_domain
from selfrepair.search.astar import PlanStatus
from selfrepair.tables.fileformat import default_table, resolve_table
from selfrepair.tables.model import ReplacementTable, SomeTable

__all__ = ["MAX_VIEW_RADIUS", "FaultyMazeEnv", "Rewards", "ask", "default_table"]

Observation = dict[str, Any]

_HEADING_LETTERS = "".join(h.name for h in Heading)
_FAILED_TICKS = float(FAILED_ATTEMPT_TICKS)


@dataclass(frozen=True, slots=True)
class Rewards:
    """The reward terms besides minus each step's duration (see the module docstring)."""

    goal_bonus: float = 100.0
    blocked_penalty: float = 1.0
    fault_penalty: float = 1.0


class FaultyMazeEnv(gym.Env[Observation, np.int64]):
    """See the module docstring. Keyword arguments (all optional):

    ``domain``
        A registered domain name or a :class:`Domain` (default ``"four-wheel"``).
    ``mazes``
        ``"bundled"`` (default), a bundled name, a maze file, a ``Maze``, a
        :class:`~selfrepair.envs.scenarios.MazeGenerator`, or a sequence of these.
    ``routes``
        ``"bundled"`` (a bundled maze's own routes, random routes elsewhere) or ``"random"``.
    ``faults``
        A :class:`~selfrepair.envs.scenarios.FaultSpec` (default: one single or double fault,
        permanent from the first step, detected at once).
    ``table``, ``recursion``
        The guide's replacement table (a bundled name, a file or a table; default
        :func:`default_table`) and recursion mode (default ``flat``).
    ``rewards``
        :class:`Rewards`. ``max_steps``: commands per episode (default ``4 * width * height``).
    ``view_radius``
        ``r`` of the ``(2r+1)``-square window (default 3, at most :data:`MAX_VIEW_RADIUS`).
    ``guide``
        Whether ``info`` carries the guide's hints (default ``False``: they cost a planner call
        for every step off the guide's plan).
    ``render_mode``, ``cell_pixels``
        ``"ansi"`` or ``"rgb_array"``; pixels per cell of an RGB frame (default 8).
    ``behaviour``
        With hidden faults (``faults=FaultSpec(detection=("hidden",))``, the partially observable
        variant ``selfrepair/FaultyMazeHidden-v0``): the domain's fault-behaviour model
        (:meth:`Domain.effective <selfrepair.robots.domain.Domain.effective>`; default its
        first). The observation then has no ``faults`` key, a forbidden command does what the
        model says, and a motion into a wall is a bump (one tick, the blocked penalty).
    """

    metadata = {"render_modes": ["ansi", "rgb_array"], "render_fps": 8}  # noqa: RUF012 (Gymnasium's)

    def __init__(
        self,
        *,
        domain: str | SomeDomain = "four-wheel",
        mazes: MazeSpec | tuple[MazeSpec, ...] | list[MazeSpec] = BUNDLED,
        routes: str = RouteChoice.BUNDLED,
        faults: FaultSpec | None = None,
        table: str | SomeTable | None = None,
        recursion: str = RecursionMode.FLAT,
        rewards: Rewards | None = None,
        max_steps: int | None = None,
        view_radius: int = 3,
        guide: bool = False,
        render_mode: str | None = None,
        cell_pixels: int = 8,
        behaviour: str | None = None,
    ) -> None:
        self.domain = get_domain(domain) if isinstance(domain, str) else domain
        self.sources: tuple[MazeSource, ...] = maze_sources(mazes)
        self.routes = choice(RouteChoice, routes, "route choice")
        self.faults = faults or FaultSpec()
        self.hidden = self.faults.hidden
        self.behaviour = check_behaviour(self.domain, self.hidden, behaviour)
        self._fault_sets = self.faults.fault_sets(self.domain)
        self.table = self._table(table)
        self.recursion = choice(RecursionMode, recursion, "recursion mode")
        self.rewards = rewards or Rewards()
        check_settings(max_steps, view_radius, render_mode, self.metadata["render_modes"])
        self.max_steps = max_steps
        self.view_radius = view_radius
        self._side = 2 * view_radius + 1
        self.guide = guide
        self.render_mode = render_mode
        self.cell_pixels = check_cell_pixels(cell_pixels)
        self._setup_spaces()
        self._scenario: Scenario | None = None
        self._sim: Simulator | None = None
        self.last_outcome: StepOutcome | None = None
        self._known: frozenset[object] = frozenset()
        self._senses = False
        self._goal: Cell = (0, 0)
        self._steps = 0
        self._elapsed = 0.0
        self._limit = 0
        self._padded: npt.NDArray[np.int8] = np.zeros((0, 0), dtype=np.int8)
        self._fault_views: dict[frozenset[object], tuple[npt.NDArray[np.int8], str]] = {}
        self._base_frame: npt.NDArray[np.uint8] | None = None
        self._guide: Stepper | None = None
        self._guided: Entry | None = None

    def _table(self, table: str | SomeTable | None) -> SomeTable:
        resolved = default_table(self.domain) if table is None else (
            table if isinstance(table, ReplacementTable) else resolve_table(table)
        )  # fmt: skip
        if resolved.domain is not self.domain:
            raise ProblemError(
                f"table {resolved.source!r} is for the {resolved.domain.name!r} domain, "
                f"not {self.domain.name!r}"
            )
        return resolved

    def _setup_spaces(self) -> None:
        domain = self.domain
        self.actions: tuple[object, ...] = domain.actions
        self._index = {action: i for i, action in enumerate(self.actions)}
        self._durations = tuple(float(domain.duration(a)) for a in self.actions)
        self._fault_index = {fault: i for i, fault in enumerate(domain.faults)}
        self.observation_space = observation_space(
            domain, self.sources, self.view_radius, self.hidden
        )
        self.action_space = spaces.Discrete(len(self.actions))

    # --- episode state, read by policies ------------------------------------------------------

    @property
    def scenario(self) -> Scenario:
        """The current episode's maze, route and true fault schedule."""
        if self._scenario is None:
            raise ProblemError("the environment has no episode yet: call reset() first")
        return self._scenario

    @property
    def pose(self) -> Pose:
        """The robot's pose now."""
        return self._simulator().pose

    @property
    def known(self) -> frozenset[object]:
        """The faults the robot knows now (what the ``faults`` observation shows)."""
        self._simulator()
        return self._known

    @property
    def steps(self) -> int:
        """Commands given in this episode (failed and blocked ones included)."""
        return self._steps

    def _simulator(self) -> Simulator:
        if self._sim is None:
            raise ProblemError("the environment has no episode yet: call reset() first")
        return self._sim

    def action_index(self, action: object) -> int:
        """The index (in the action space) of one of the domain's actions."""
        return self._index[action]

    def mission_spec(self, strategy: str) -> MissionSpec:
        """The executor's :class:`MissionSpec` of this episode for ``strategy`` (the same maze,
        route, true faults, fault seed, table and step limit)."""
        scenario = self.scenario
        return MissionSpec(
            maze=scenario.maze,
            start=scenario.start,
            goal=scenario.goal,
            schedule=scenario.schedule,
            strategy=strategy,
            options=StrategyOptions(table=self.table, recursion=self.recursion),
            seed=scenario.fault_seed,
            max_steps=self._limit,
            domain=self.domain,
        )

    def stepper(self, strategy: str) -> Stepper:
        """A :class:`~selfrepair.execution.stepper.Stepper` for ``strategy`` that plans from the
        robot's pose now, knowing no fault (as the executor's initial plan does); stopped when no
        plan exists. Ask it with :func:`ask`; tell it what each command did with
        :meth:`Stepper.observe <selfrepair.execution.stepper.Stepper.observe>`."""
        spec = self.mission_spec(strategy)
        context = mission_context(spec, self.table if uses_table(strategy) else None)
        sim = self._simulator()
        initial = context.plan(
            sim.pose, context.goal, context.goal_heading, frozenset(), context.replan_budget
        )
        return Stepper(
            context,
            get_strategy(strategy)(context),
            initial.actions,
            frozenset(),
            sim.table,
            stopped=initial.status is not PlanStatus.SOLVED,
        )

    # --- the Gymnasium API --------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Observation, dict[str, Any]]:
        """Start an episode drawn from ``np_random`` (seeded by ``seed``). ``options`` may fix
        ``maze`` (a bundled name, file or ``Maze``; the route is then drawn on it unless given),
        ``start`` (a pose ``"x,y,H"``), ``goal`` (a cell ``"x,y"``) and ``faults`` (a fault-set
        text, permanent from the first step and detected at once, or a ``FaultSchedule``)."""
        super().reset(seed=seed)
        scenario = draw_scenario(
            self.sources, self.routes, self.domain, self.faults, self.np_random, self._fault_sets
        )
        if options:
            scenario = with_options(scenario, options, self.domain, self.np_random, self.hidden)
        self._begin(scenario)
        pose = self._simulator().pose
        info = self._info(pose, None)
        info.update(self._episode_info())
        return self._observe(pose), info

    def step(
        self, action: np.int64 | int
    ) -> tuple[Observation, SupportsFloat, bool, bool, dict[str, Any]]:
        """Send command ``action`` (an index into the domain's actions) to the simulator."""
        sim = self._simulator()
        index = int(action)
        if not 0 <= index < len(self.actions):
            raise ProblemError(f"expected an action index from 0 to {len(self.actions) - 1}")
        command = self.actions[index]
        outcome = sim.execute(command)
        self.last_outcome = outcome
        self._steps += 1
        status = outcome.status
        rewards = self.rewards
        if status is Outcome.MOVED:  # hidden faults: the action the wheels performed
            duration = self._durations[self._index[sim.last_action] if self.hidden else index]
            reward = -duration
        elif status is Outcome.FAILED_ATTEMPT:
            duration = _FAILED_TICKS
            reward = -duration - rewards.fault_penalty
            if not self._senses:
                self._known = self._known | outcome.blocking
        elif status is Outcome.BUMPED:  # hidden faults: stopped at a wall, one tick
            duration = _FAILED_TICKS
            reward = -duration - rewards.blocked_penalty
        else:
            duration = 0.0
            reward = -rewards.blocked_penalty
        self._elapsed += duration
        if self._senses:
            self._known = sim.sense()
        pose = sim.pose
        terminated = pose.x == self._goal[0] and pose.y == self._goal[1]
        if terminated:
            reward += rewards.goal_bonus
        truncated = not terminated and self._steps >= self._limit
        if self._guide is not None:
            self._guide.observe(outcome, followed(self._guided, command))
        return self._observe(pose), reward, terminated, truncated, self._info(pose, status)

    def render(self) -> str | npt.NDArray[np.uint8] | None:
        """The frame of ``render_mode``: an RGB array or the ASCII picture (``None`` without a
        render mode, as Gymnasium expects)."""
        if self.render_mode is None:
            return None
        scenario, pose = self.scenario, self.pose
        if self.render_mode == "ansi":
            known = self.domain.format_faults(self._known) or "none"
            return ansi_frame(
                scenario.maze, pose, scenario.goal, (f"step {self._steps}, known faults {known}",)
            )
        if self._base_frame is None:
            self._base_frame = maze_frame(scenario.maze, scenario.goal, self.cell_pixels)
        return rgb_frame(self._base_frame, pose, self.cell_pixels)

    # --- internals -------------------------------------------------------------------------

    def _begin(self, scenario: Scenario) -> None:
        self._scenario = scenario
        maze = scenario.maze
        self._sim = Simulator(
            self.domain,
            maze,
            scenario.start,
            scenario.schedule,
            scenario.fault_seed,
            behaviour=self.behaviour,
        )
        self._senses = scenario.schedule.detection is Detection.NOW
        self._known = self._sim.sense()
        self._goal = scenario.goal
        self._steps = 0
        self._elapsed = 0.0
        self.last_outcome = None
        self._limit = self.max_steps or 4 * maze.width * maze.height
        grid = maze.free_grid(self.view_radius)
        rows, cols = grid.height + 2 * grid.margin, grid.width + 2 * grid.margin
        self._padded = np.frombuffer(grid.data, dtype=np.int8).reshape(rows, cols)
        self._fault_views = {}
        self._base_frame = None
        self._guide = self.stepper(StrategyName.REPLACEMENT) if self.guide else None
        self._guided = None

    def _observe(self, pose: Pose) -> Observation:
        x, y = pose.x, pose.y
        side = self._side
        goal = self._goal
        observation: Observation = {
            "window": self._padded[y : y + side, x : x + side].copy(),
            "heading": int(pose.heading),
            "goal": np.array((goal[0] - x, goal[1] - y), dtype=np.int32),
        }
        if self._fault_index and not self.hidden:
            observation["faults"] = self._fault_view(self._known)[0].copy()
        return observation

    def _fault_view(self, known: frozenset[object]) -> tuple[npt.NDArray[np.int8], str]:
        """The mask and text of a known-fault set (kept per episode: at most one per subset of
        the schedule's faults)."""
        view = self._fault_views.get(known)
        if view is None:
            mask = np.zeros(len(self._fault_index), dtype=np.int8)
            mask[[self._fault_index[f] for f in known]] = 1
            view = (mask, self.domain.format_faults(known))
            self._fault_views[known] = view
        return view

    def _info(self, pose: Pose, status: Outcome | None) -> dict[str, Any]:
        info: dict[str, Any] = {
            "outcome": "" if status is None else str(status),
            "pose": f"{pose.x},{pose.y},{_HEADING_LETTERS[pose.heading]}",
            "known_faults": self._fault_view(self._known)[1],
            "ticks": self._elapsed,
        }
        if self._guide is not None:
            info.update(self._hints(self._guide, pose, self._simulator().steps))
        return info

    def _hints(self, guide: Stepper, pose: Pose, steps: int) -> dict[str, Any]:
        planned, record = ask(guide, pose, self._known, steps)
        self._guided = planned
        repair = None if record is None else record.repair
        faulty = None if record is None else record.action
        suggested: tuple[int, ...] = ()
        if repair is not None and repair.source is RepairSource.REPLACEMENT:
            suggested = tuple(self._index[a] for a in repair.actions)
        return {
            "planned_action": -1 if planned is None else self._index[planned[0]],
            "faulty_action": -1 if faulty is None else self._index[faulty],
            "replacement": suggested,
            "repair_source": "" if repair is None else repair.source.value,
        }

    def _episode_info(self) -> dict[str, Any]:
        scenario = self.scenario
        schedule = scenario.schedule
        return {
            "maze": scenario.maze_label,
            "start": str(scenario.start),
            "goal": f"{scenario.goal[0]},{scenario.goal[1]}",
            "faults": self.domain.format_faults(schedule.all_faults()),
            "schedule": schedule.describe(),
            "detection": schedule.detection.value,
            "fault_seed": scenario.fault_seed,
            "np_random_seed": self.np_random_seed,
            "max_steps": self._limit,
        }
