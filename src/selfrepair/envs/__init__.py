"""Gymnasium environments: the faulty robot in a maze as a standard RL task, with baselines.

Importing this package registers ``selfrepair/FaultyMaze-v0`` with Gymnasium (Gymnasium 1.x has no
plug-in entry points; ``gymnasium.make("selfrepair.envs:selfrepair/FaultyMaze-v0")`` imports this
package for you), with :class:`~selfrepair.envs.vector.FaultyMazeVectorEnv` as its vector entry
point (``gymnasium.make_vec(ENV_ID, num_envs=N)``). It needs the ``gym`` extra
(``pip install 'selfrepair[gym]'``). See docs/gym.md.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from selfrepair.envs.env import FaultyMazeEnv, Rewards, default_table
from selfrepair.envs.scenarios import FaultSpec, MazeGenerator, RouteChoice
from selfrepair.envs.vector import FaultyMazeVectorEnv
from selfrepair.execution.faults import Detection

__all__ = [
    "ENV_ID",
    "HIDDEN_ENV_ID",
    "PHYSICS_ENV_ID",
    "FaultSpec",
    "FaultyMazeEnv",
    "FaultyMazeVectorEnv",
    "MazeGenerator",
    "Rewards",
    "RouteChoice",
    "default_table",
]

ENV_ID = "selfrepair/FaultyMaze-v0"
"""The Gymnasium id of :class:`FaultyMazeEnv`."""

HIDDEN_ENV_ID = "selfrepair/FaultyMazeHidden-v0"
"""The partially observable variant: the faults are hidden from the agent (detection ``hidden``:
no ``faults`` observation, the robot performs what ``Domain.effective`` says)."""

_LATTICE_ENVS = {
    ENV_ID: {},
    HIDDEN_ENV_ID: {"faults": FaultSpec(detection=(Detection.HIDDEN,))},
}
"""Each lattice environment id and the keyword arguments it makes its environment with."""

for _env_id, _kwargs in _LATTICE_ENVS.items():
    if _env_id not in registry:
        register(
            id=_env_id,
            entry_point="selfrepair.envs.env:FaultyMazeEnv",
            vector_entry_point="selfrepair.envs.vector:FaultyMazeVectorEnv",
            nondeterministic=False,
            kwargs=_kwargs,
        )

PHYSICS_ENV_ID = "selfrepair/FaultyMazePhysics-v0"
"""The Gymnasium id of :class:`selfrepair.envs.physics.PhysicsMazeEnv` (MuJoCo underneath; the
``physics`` extra)."""

if PHYSICS_ENV_ID not in registry:
    register(id=PHYSICS_ENV_ID, entry_point="selfrepair.envs.physics:PhysicsMazeEnv")
