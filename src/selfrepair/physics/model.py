"""The four-wheel skid-steer robot and a maze as one MJCF model, generated from documented numbers.

:class:`RobotParams` holds every physical number (dimensions, masses, friction, contact softness,
motor gains, the time scale and the timestep) with the reason for its value in docs/physics.md;
:func:`mjcf` writes the MuJoCo XML of the robot on a floor with the walls of a
:class:`~selfrepair.world.maze.Maze` (:func:`wall_boxes`: each row's runs of wall cells merged into
one box, plus four border walls, since outside the grid counts as wall). The model needs no
MuJoCo to be written: only :mod:`selfrepair.physics.world` imports ``mujoco``.

Frames. Lattice cell ``(x, y)`` (``y`` down, as in the maze text) has its centre at world
``(x * cell, -y * cell)`` metres; the world's ``z`` is up, so the lattice's clockwise is the
world's clockwise seen from above. A lattice heading ``h`` (quarter turns clockwise from north)
is the world yaw ``pi/2 - h * pi/2`` (east 0, north pi/2), :func:`heading_yaw`.

The wheels. Skid steering turns by sliding wheels sideways, which is what makes such models
fragile: cylinders against a plane touch along an edge and chatter while they skid; here each
wheel collides as a sphere of the wheel's radius (one contact point per wheel, the same whatever
the wheel's tilt) and is drawn as a cylinder. Contacts are ``condim=3`` (isotropic sliding
friction; no torsional or rolling friction, whose extra resistance to a skid turn real tyres
do not show at these loads), the elliptic friction cone, and soft (``solref`` time constant
``contact_timeconst``, damping ratio 1) so that a skidding wheel's friction force grows smoothly
with its slip instead of jumping between stick and slip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.world.maze import Maze

__all__ = [
    "DEFAULT_PARAMS",
    "ORIGIN",
    "WHEELS",
    "RobotParams",
    "WallBox",
    "heading_yaw",
    "mjcf",
    "wall_boxes",
]

WHEELS = ("FL", "FR", "RL", "RR")
"""The wheels in the order of an action's commands (and of the model's actuators)."""


@dataclass(frozen=True, slots=True)
class RobotParams:
    """Every number of the physics model (SI units; see docs/physics.md for why each value).

    ``cell`` is the maze's cell size and ``tick`` the seconds one lattice tick lasts, so the
    fastest straight move (``FFFF``, one cell in one tick) drives each wheel's rim at
    ``wheel_speed = cell / tick`` metres per second. ``max_speed_factor`` bounds what the
    tracker may ask of one wheel (as a multiple of ``wheel_speed``).
    """

    cell: float = 0.5
    tick: float = 1.0
    timestep: float = 0.002
    control_every: int = 5
    """Physics steps per control update (5 steps of 2 ms: 100 Hz)."""
    chassis_half: tuple[float, float, float] = (0.14, 0.10, 0.04)
    chassis_mass: float = 4.0
    wheel_radius: float = 0.05
    wheel_half_width: float = 0.02
    wheel_mass: float = 0.3
    wheel_x: float = 0.09
    """Front/rear axle offset from the centre (wheelbase 0.18 m)."""
    wheel_y: float = 0.125
    """Wheel offset to either side (track 0.25 m)."""
    friction: float = 0.8
    contact_timeconst: float = 0.01
    motor_kv: float = 5.0
    """Velocity gain of each wheel motor, N m per rad/s."""
    motor_torque: float = 5.0
    """Torque limit of each wheel motor, N m (100 N at the rim: twice what the wheels' grip
    can transmit, so the motor, not the tyre, never limits a wheel that grips)."""
    max_speed_factor: float = 3.0
    wheel_accel: float = 4.0
    """The largest change of a wheel's commanded rim speed per second (m/s^2) that its motor
    controller passes on (a ramp, as real wheel controllers have): well under what the tyres'
    grip can transmit (0.8 g, 7.8 m/s^2), so the wheels do not jerk the robot into pitching,
    hopping and skidding when the tracker changes its speeds."""
    wall_height: float = 0.2

    def __post_init__(self) -> None:
        positive = {
            "cell": self.cell,
            "tick": self.tick,
            "timestep": self.timestep,
            "wheel_radius": self.wheel_radius,
            "friction": self.friction,
            "motor_kv": self.motor_kv,
            "motor_torque": self.motor_torque,
            "max_speed_factor": self.max_speed_factor,
            "wheel_accel": self.wheel_accel,
        }
        for name, value in positive.items():
            if not value > 0:
                raise ProblemError(f"physics parameter {name} must be positive, got {value}")
        if self.control_every < 1:
            raise ProblemError(f"control_every must be at least 1, got {self.control_every}")
        if 2 * self.radius >= self.cell:
            raise ProblemError(
                f"the robot (radius {self.radius:.3f} m when it turns) does not fit in a cell of "
                f"{self.cell} m"
            )

    @property
    def wheel_speed(self) -> float:
        """The rim speed of a wheel commanded F (m/s): one cell per tick."""
        return self.cell / self.tick

    @property
    def wheel_omega(self) -> float:
        """The angular speed of a wheel commanded F (rad/s)."""
        return self.wheel_speed / self.wheel_radius

    @property
    def radius(self) -> float:
        """The robot's radius about its centre when it turns (chassis or wheels, whichever
        reaches further): it fits in a cell when twice this is less than ``cell``."""
        cx, cy, _ = self.chassis_half
        wx = self.wheel_x + self.wheel_radius
        wy = self.wheel_y + self.wheel_half_width
        return max(math.hypot(cx, cy), math.hypot(wx, wy))

    def seconds(self, ticks: Fraction | int) -> float:
        """``ticks`` lattice ticks in seconds."""
        return float(ticks) * self.tick

    def steps(self, ticks: Fraction | int) -> int:
        """The whole number of physics steps that ``ticks`` ticks last (rounded)."""
        return max(1, round(self.seconds(ticks) / self.timestep))


DEFAULT_PARAMS = RobotParams()
"""The documented robot (docs/physics.md)."""
ORIGIN = Pose(0, 0, Heading.N)
"""Cell (0, 0) facing north."""


def heading_yaw(heading: Heading) -> float:
    """The world yaw (radians, anticlockwise from east) of a lattice heading."""
    return math.pi / 2 - int(heading) * math.pi / 2


@dataclass(frozen=True, slots=True)
class WallBox:
    """One wall box: its centre and half extents in the floor plane (metres)."""

    x: float
    y: float
    half_x: float
    half_y: float


def wall_boxes(maze: Maze, cell: float) -> tuple[WallBox, ...]:
    """The maze's walls as boxes: each row's runs of consecutive wall cells merged into one box
    (row by row, left to right), then the four border walls just outside the grid (north, south,
    west, east)."""
    boxes: list[WallBox] = []
    walls = np.asarray(maze.walls)
    for y in range(maze.height):
        row = walls[y]
        x = 0
        while x < maze.width:
            if not row[x]:
                x += 1
                continue
            end = x
            while end + 1 < maze.width and row[end + 1]:
                end += 1
            centre = (x + end) / 2 * cell
            boxes.append(WallBox(centre, -y * cell, (end - x + 1) * cell / 2, cell / 2))
            x = end + 1
    w, h = maze.width, maze.height
    mid_x, mid_y = (w - 1) / 2 * cell, -(h - 1) / 2 * cell
    half_w, half_h = (w + 2) * cell / 2, h * cell / 2
    boxes.append(WallBox(mid_x, cell, half_w, cell / 2))
    boxes.append(WallBox(mid_x, -h * cell, half_w, cell / 2))
    boxes.append(WallBox(-cell, mid_y, cell / 2, half_h))
    boxes.append(WallBox(w * cell, mid_y, cell / 2, half_h))
    return tuple(boxes)


def mjcf(maze: Maze | None, params: RobotParams = DEFAULT_PARAMS, start: Pose | None = None) -> str:
    """The MJCF text of the robot (at ``start``, default the origin facing north) on a floor,
    with the walls of ``maze`` (none when ``None``).

    Geoms: the floor first, then the walls (``wall0``, ``wall1``, ...), then the robot's. Walls
    and robot collide (collision bits 2), walls and floor do not; the robot's wheels carry the
    friction. The four actuators are velocity servos on the wheel hinges, in :data:`WHEELS`
    order; a positive control rolls a wheel forward.
    """
    p = params
    pose = start or Pose(0, 0, Heading.N)
    yaw = heading_yaw(pose.heading)
    qw, qz = math.cos(yaw / 2), math.sin(yaw / 2)
    boxes = wall_boxes(maze, p.cell) if maze is not None else ()
    hz = p.wall_height / 2
    walls = "\n".join(
        f'    <geom name="wall{i}" type="box" pos="{b.x:.6g} {b.y:.6g} {hz:.6g}" '
        f'size="{b.half_x:.6g} {b.half_y:.6g} {hz:.6g}" contype="2" conaffinity="2" '
        'rgba=".45 .45 .5 1"/>'
        for i, b in enumerate(boxes)
    )
    wheels = []
    for name in WHEELS:
        sx = 1 if name[0] == "F" else -1
        sy = 1 if name[1] == "L" else -1
        wheels.append(
            f'      <body name="{name}" pos="{sx * p.wheel_x:.6g} {sy * p.wheel_y:.6g} 0">\n'
            f'        <joint name="{name}" type="hinge" axis="0 1 0"/>\n'
            f'        <geom name="{name}" type="sphere" size="{p.wheel_radius:.6g}" '
            f'mass="{p.wheel_mass:.6g}" contype="1" conaffinity="1" rgba="0 0 0 0"/>\n'
            f'        <geom name="{name}_tyre" type="cylinder" size="{p.wheel_radius:.6g} '
            f'{p.wheel_half_width:.6g}" euler="90 0 0" contype="2" conaffinity="2" mass="0" '
            'rgba=".1 .1 .1 1"/>\n'
            "      </body>"
        )
    actuators = "\n".join(
        f'    <velocity name="{name}" joint="{name}" kv="{p.motor_kv:.6g}" '
        f'forcerange="{-p.motor_torque:.6g} {p.motor_torque:.6g}"/>'
        for name in WHEELS
    )
    cx, cy, cz = p.chassis_half
    x0, y0 = pose.x * p.cell, -pose.y * p.cell
    extent = max(maze.width, maze.height) * p.cell if maze is not None else 4 * p.cell
    if maze is not None:
        cam_x, cam_y = (maze.width - 1) / 2 * p.cell, -(maze.height - 1) / 2 * p.cell
    else:
        cam_x, cam_y = x0, y0
    cam_z = (extent / 2 + p.cell) / math.tan(math.radians(22.5)) * 1.05
    return f"""<mujoco model="selfrepair-four-wheel">
  <compiler angle="degree"/>
  <option timestep="{p.timestep:.6g}" integrator="implicitfast" cone="elliptic"/>
  <visual><global offwidth="640" offheight="480"/></visual>
  <default>
    <geom condim="3" friction="{p.friction:.6g} 0 0" solref="{p.contact_timeconst:.6g} 1"
          solimp="0.9 0.95 0.001"/>
  </default>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1=".85 .85 .85" rgb2=".75 .75 .75"
             width="64" height="64"/>
    <material name="grid" texture="grid" texrepeat="1 1" texuniform="true"/>
  </asset>
  <worldbody>
    <light pos="0 0 {2 * extent:.6g}" dir="0 0 -1" directional="true"/>
    <camera name="top" pos="{cam_x:.6g} {cam_y:.6g} {cam_z:.6g}" xyaxes="1 0 0 0 1 0"
            fovy="45"/>
    <geom name="floor" type="plane" size="{extent * 2:.6g} {extent * 2:.6g} 0.1"
          contype="1" conaffinity="1" material="grid"/>
{walls}
    <body name="robot" pos="{x0:.6g} {y0:.6g} {p.wheel_radius:.6g}" quat="{qw:.9g} 0 0 {qz:.9g}">
      <freejoint name="robot"/>
      <geom name="chassis" type="box" size="{cx:.6g} {cy:.6g} {cz:.6g}" mass="{p.chassis_mass:.6g}"
            contype="2" conaffinity="2" rgba=".85 .45 .1 1"/>
      <geom name="nose" type="box" pos="{cx * 0.8:.6g} 0 {cz:.6g}"
            size="{cx * 0.2:.6g} {cy * 0.3:.6g} 0.005" contype="0" conaffinity="0" mass="0"
            rgba=".1 .2 .8 1"/>
{chr(10).join(wheels)}
    </body>
  </worldbody>
  <actuator>
{actuators}
  </actuator>
</mujoco>
"""
