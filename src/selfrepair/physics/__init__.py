"""The four-wheel robot in MuJoCo: the lattice motion model checked against physics, and missions
driven through it (the ``physics`` extra: ``mujoco`` and ``imageio``). See docs/physics.md.

* :mod:`selfrepair.physics.model`: the robot's physical parameters and the MJCF of robot and maze;
* :mod:`selfrepair.physics.tracker`: wheel speeds of a lattice action, open loop or tracked;
* :mod:`selfrepair.physics.world`: the MuJoCo world that runs an action (the only ``mujoco`` user);
* :mod:`selfrepair.physics.simulator`: that world in the lattice simulator's role, so the one
  mission loop drives it;
* :mod:`selfrepair.physics.mission`: missions in physics, their outcome, headless videos;
* :mod:`selfrepair.physics.fidelity`: every action against the lattice, open loop and tracked;
* :mod:`selfrepair.physics.identified`: the domain identified from physics (plain data, no
  MuJoCo needed).

The package sits above :mod:`selfrepair.execution` (its simulator is one) and beside
:mod:`selfrepair.team`; nothing below imports it.
"""

from selfrepair.physics.model import DEFAULT_PARAMS, RobotParams, mjcf, wall_boxes

__all__ = ["DEFAULT_PARAMS", "RobotParams", "mjcf", "wall_boxes"]
