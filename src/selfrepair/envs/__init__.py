"""Gymnasium environments: the faulty robot in a maze as a standard RL task, with baselines.

Importing this package registers ``selfrepair/FaultyMaze-v0`` with Gymnasium (Gymnasium 1.x has no
plug-in entry points; ``gymnasium.make("selfrepair.envs:selfrepair/FaultyMaze-v0")`` imports this
package for you). It needs the ``gym`` extra (``pip install 'selfrepair[gym]'``). See docs/gym.md.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from selfrepair.envs.env import FaultyMazeEnv, Rewards, default_table
from selfrepair.envs.scenarios import FaultSpec, MazeGenerator, RouteChoice

__all__ = [
    "ENV_ID",
    "PHYSICS_ENV_ID",
    "FaultSpec",
    "FaultyMazeEnv",
    "MazeGenerator",
    "Rewards",
    "RouteChoice",
    "default_table",
]

ENV_ID = "selfrepair/FaultyMaze-v0"
"""The Gymnasium id of :class:`FaultyMazeEnv`."""

if ENV_ID not in registry:
    register(id=ENV_ID, entry_point="selfrepair.envs.env:FaultyMazeEnv", nondeterministic=False)

PHYSICS_ENV_ID = "selfrepair/FaultyMazePhysics-v0"
"""The Gymnasium id of :class:`selfrepair.envs.physics.PhysicsMazeEnv` (MuJoCo underneath; the
``physics`` extra)."""

if PHYSICS_ENV_ID not in registry:
    register(id=PHYSICS_ENV_ID, entry_point="selfrepair.envs.physics:PhysicsMazeEnv")
