"""The MuJoCo world of one robot in one maze: set its pose, run one action, read where it went.

:class:`PhysicsWorld` compiles the model of :func:`selfrepair.physics.model.mjcf` (or a robot's
own MJCF text, see docs/physics.md) and runs a lattice action's wheel commands on it
(:meth:`PhysicsWorld.run`), open loop or under the :class:`~selfrepair.physics.tracker.Tracker`,
returning an :class:`ActionRun`: the continuous end pose, how many control updates saw a contact
between the robot and a wall, and the seconds simulated. It is the only module that imports
``mujoco`` (the ``physics`` extra).
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from types import ModuleType

from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.optional import import_extra
from selfrepair.physics.model import DEFAULT_PARAMS, ORIGIN, WHEELS, RobotParams, heading_yaw, mjcf
from selfrepair.physics.tracker import ContinuousPose, LatticeMotion, Tracker, wrap
from selfrepair.world.maze import Maze

__all__ = ["ActionRun", "PhysicsWorld", "lattice_pose", "mujoco_module", "snap"]


def mujoco_module() -> ModuleType:
    """The ``mujoco`` package (the ``physics`` extra), or a :class:`ProblemError` naming it.

    On a machine without a display (no ``DISPLAY``) and without ``MUJOCO_GL`` set, MuJoCo's
    renderer is told to use OSMesa (``MUJOCO_GL=osmesa``) before ``mujoco`` is first imported,
    so videos render headless; an explicit ``MUJOCO_GL`` is left as it is."""
    if "mujoco" not in sys.modules and not os.environ.get("DISPLAY"):
        os.environ.setdefault("MUJOCO_GL", "osmesa")
    return import_extra("mujoco", "physics", need="physics simulations")


def lattice_pose(pose: Pose) -> ContinuousPose:
    """The continuous pose (cells, world frame) of a lattice pose."""
    return ContinuousPose(float(pose.x), float(-pose.y), heading_yaw(pose.heading))


def snap(pose: ContinuousPose) -> Pose:
    """The nearest lattice pose: the nearest cell centre and the nearest of the four headings
    (localisation on the lattice)."""
    quarter = round((math.pi / 2 - pose.yaw) / (math.pi / 2)) % 4
    return Pose(round(pose.x), round(-pose.y), Heading(quarter))


@dataclass(frozen=True, slots=True)
class ActionRun:
    """What one action did in physics: its end pose (continuous), the control updates during
    which the robot touched a wall, the physics steps and the seconds simulated."""

    end: ContinuousPose
    wall_contacts: int
    steps: int
    seconds: float


class PhysicsWorld:
    """One MuJoCo model and its state (mutable: the robot moves).

    ``maze`` gives the walls (``None``: an open floor), ``start`` the robot's first pose.
    ``xml`` replaces the generated model with a robot's own MJCF (its actuators in FL, FR, RL,
    RR order, a free-jointed body named ``robot``, its wall geoms named ``wall...``).
    ``observer``, when given, is called after every control update with the world (for video
    frames and traces).
    """

    def __init__(
        self,
        maze: Maze | None,
        start: Pose = ORIGIN,
        params: RobotParams = DEFAULT_PARAMS,
        *,
        xml: str | None = None,
        observer: Callable[[PhysicsWorld], None] | None = None,
    ) -> None:
        mj = mujoco_module()
        self.mj = mj
        self.params = params
        self.maze = maze
        self.model = mj.MjModel.from_xml_string(
            xml if xml is not None else mjcf(maze, params, start)
        )
        self.data = mj.MjData(self.model)
        self.observer = observer
        robot = mj.mj_name2id(self.model, mj.mjtObj.mjOBJ_BODY, "robot")
        if robot < 0 or self.model.nu != len(WHEELS):
            raise ProblemError("the MJCF model needs a body named 'robot' and four wheel actuators")
        self._qadr = int(self.model.jnt_qposadr[self.model.body_jntadr[robot]])
        self._vadr = int(self.model.jnt_dofadr[self.model.body_jntadr[robot]])
        names = [
            mj.mj_id2name(self.model, mj.mjtObj.mjOBJ_GEOM, i) or ""
            for i in range(self.model.ngeom)
        ]
        self._walls = frozenset(i for i, n in enumerate(names) if n.startswith("wall"))
        self.time = 0.0
        self.total_steps = 0
        self.place(start)

    def place(self, pose: Pose) -> None:
        """Put the robot at rest at the lattice pose ``pose`` (its wheels on the floor)."""
        self.mj.mj_resetData(self.model, self.data)
        c = lattice_pose(pose)
        q = self.data.qpos
        a = self._qadr
        q[a : a + 3] = (c.x * self.params.cell, c.y * self.params.cell, self.params.wheel_radius)
        q[a + 3 : a + 7] = (math.cos(c.yaw / 2), 0.0, 0.0, math.sin(c.yaw / 2))
        self.mj.mj_forward(self.model, self.data)

    def pose(self) -> ContinuousPose:
        """The robot's pose now, in cells and radians."""
        q, a, cell = self.data.qpos, self._qadr, self.params.cell
        w, x, y, z = q[a + 3], q[a + 4], q[a + 5], q[a + 6]
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return ContinuousPose(float(q[a]) / cell, float(q[a + 1]) / cell, yaw)

    def touching_wall(self) -> bool:
        """Whether any contact now joins the robot and a wall."""
        n = self.data.ncon
        if not n or not self._walls:
            return False
        walls = self._walls
        return any(int(g1) in walls or int(g2) in walls for g1, g2 in self.data.contact.geom[:n])

    def run(
        self,
        commands: tuple[int, int, int, int],
        ticks: Fraction,
        *,
        motion: LatticeMotion | None = None,
        reference_start: Pose | None = None,
    ) -> ActionRun:
        """Run the four wheel commands (+1, 0, -1 each) for ``ticks`` ticks: open loop, or, when
        ``motion`` is given, tracking the lattice motion from ``reference_start`` (the robot's
        snapped pose when not given). Either way each wheel's motor controller changes its
        speed by at most ``wheel_accel`` (at the rim) per second (:class:`RobotParams`)."""
        p = self.params
        steps = p.steps(ticks)
        seconds = steps * p.timestep
        tracker = None
        if motion is not None:
            start = lattice_pose(reference_start or snap(self.pose()))
            tracker = Tracker(commands, motion, start, seconds, p.wheel_speed / p.cell,
                              p.max_speed_factor, p.cell)  # fmt: skip
        ctrl = self.data.ctrl
        omega = p.wheel_omega
        wanted = [c * omega for c in commands]
        done = contacts = 0
        every = p.control_every
        while done < steps:
            n = min(every, steps - done)
            if tracker is not None:
                t = done * p.timestep
                wanted = [s * omega for s in tracker.speeds(self.pose(), t)]
            step = p.wheel_accel * n * p.timestep / p.wheel_radius  # rad/s this update
            ctrl[:] = [min(max(w, c - step), c + step) for w, c in zip(wanted, ctrl, strict=True)]
            self.mj.mj_step(self.model, self.data, n)
            done += n
            if self.touching_wall():
                contacts += 1
            if self.observer is not None:
                self.observer(self)
        self.time += seconds
        self.total_steps += steps
        return ActionRun(self.pose(), contacts, steps, seconds)

    def settle(self, seconds: float) -> None:
        """Hold every wheel at rest for ``seconds`` (the robot coasts to a stop)."""
        self.data.ctrl[:] = 0.0
        steps = max(1, round(seconds / self.params.timestep))
        self.mj.mj_step(self.model, self.data, steps)
        self.time += steps * self.params.timestep
        self.total_steps += steps


def pose_error(end: ContinuousPose, target: Pose) -> tuple[float, float]:
    """The position error in cells and the heading error in degrees of ``end`` against the
    lattice pose ``target``."""
    t = lattice_pose(target)
    return math.hypot(end.x - t.x, end.y - t.y), abs(math.degrees(wrap(end.yaw - t.yaw)))
