"""``selfrepair/FaultyMazePhysics-v0``: the Gymnasium environment with MuJoCo underneath.

:class:`PhysicsMazeEnv` is :class:`~selfrepair.envs.env.FaultyMazeEnv` (same discrete actions,
rewards, scenarios, guide and baselines) whose world is a
:class:`~selfrepair.physics.simulator.PhysicsSimulator`: every command that moves runs in physics
(tracked unless ``tracked=False``) and the robot is localised on the lattice after it. The
observation adds ``pose``: the robot's continuous pose, ``(x, y)`` in cells in the maze's frame
(``x`` right, ``y`` down, cell centres at whole numbers) and its heading in radians clockwise from
north, as physics left it. ``info`` adds ``wall_contacts`` (control updates of the last step with
a robot-wall contact). Needs the ``gym`` and ``physics`` extras.
"""

from __future__ import annotations

import math
from typing import Any, SupportsFloat

import numpy as np
from gymnasium import spaces

from selfrepair.envs.env import FaultyMazeEnv, Observation
from selfrepair.envs.scenarios import Scenario
from selfrepair.geometry import Pose
from selfrepair.physics.model import DEFAULT_PARAMS, RobotParams
from selfrepair.physics.simulator import PhysicsSimulator

__all__ = ["PhysicsMazeEnv"]


class PhysicsMazeEnv(FaultyMazeEnv):
    """The faulty-maze task in MuJoCo (see the module docstring); every keyword of
    :class:`~selfrepair.envs.env.FaultyMazeEnv`, plus ``params`` and ``tracked``."""

    def __init__(
        self, *, params: RobotParams = DEFAULT_PARAMS, tracked: bool = True, **kwargs: Any
    ) -> None:
        self.params = params
        self.tracked = tracked
        super().__init__(**kwargs)

    def _setup_spaces(self) -> None:
        super()._setup_spaces()
        assert isinstance(self.observation_space, spaces.Dict)
        self.observation_space.spaces["pose"] = spaces.Box(
            -np.inf, np.inf, shape=(3,), dtype=np.float64
        )

    def _begin(self, scenario: Scenario) -> None:
        super()._begin(scenario)
        self._sim = PhysicsSimulator(
            self.domain,
            scenario.maze,
            scenario.start,
            scenario.schedule,
            scenario.fault_seed,
            params=self.params,
            tracked=self.tracked,
        )

    @property
    def physics(self) -> PhysicsSimulator:
        """The episode's physics simulator."""
        sim = self._simulator()
        assert isinstance(sim, PhysicsSimulator)
        return sim

    def step(
        self, action: np.int64 | int
    ) -> tuple[Observation, SupportsFloat, bool, bool, dict[str, Any]]:
        """:meth:`FaultyMazeEnv.step`, the command run in physics."""
        before = len(self.physics.physics_steps)
        observation, reward, terminated, truncated, info = super().step(action)
        steps = self.physics.physics_steps
        info["wall_contacts"] = steps[-1].wall_contacts if len(steps) > before else 0
        return observation, reward, terminated, truncated, info

    def _observe(self, pose: Pose) -> Observation:
        observation = super()._observe(pose)
        end = self.physics.physics.pose()
        observation["pose"] = np.array(
            (end.x, -end.y, math.remainder(math.pi / 2 - end.yaw, 2 * math.pi)),
            dtype=np.float64,
        )
        return observation
