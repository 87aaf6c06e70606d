"""Wheel speeds for one lattice action: open loop, or tracking the lattice's motion.

Both work in the world frame of :mod:`selfrepair.physics.model` in cell units (``x`` east, ``y``
north, yaw anticlockwise from east) on a :class:`ContinuousPose`.

*Open loop* (:func:`open_loop_speeds`) runs each wheel at its command times the wheel speed
(``F`` = +1, ``S`` = 0, ``B`` = -1) for the action's duration: the lattice's model taken
literally.

*Tracked* (:class:`Tracker`) follows a reference along the lattice motion from the start pose to
the lattice end pose in the action's duration: a straight segment, a turn in place, or a quarter
circle of one cell's radius for an arc, with a trapezoidal time profile (accelerating over the
first and braking over the last :data:`RAMP` of the duration, so it starts and ends at rest). A
unicycle tracking law (Kanayama et al., 1990) turns the pose error into a forward speed and a
yaw rate, these into the two sides' ground speeds with the effective track width of a skid-steer
robot, and each side's speed into wheel speeds **within the signs of the command**: a wheel
commanded F turns forward or not at all, B backward or not at all, S stays stopped. So the
tracker never asks a wheel for a command the action does not give it, and a replacement action
stays that action; it only chooses how fast each permitted wheel turns (up to
``max_speed_factor`` times the wheel speed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

__all__ = [
    "RAMP",
    "ContinuousPose",
    "LatticeMotion",
    "Tracker",
    "balanced_drive",
    "open_loop_speeds",
    "reference",
    "wrap",
]

RAMP = 0.25
"""The share of the reference's duration spent accelerating (and, at its end, braking)."""

HOLD = 0.2
"""The share of an action's duration at its end in which the reference holds the end pose, so
the tracker can take out what the robot lags behind."""

K_X = 4.0
"""Along-track gain (1/s)."""
K_Y = 12.0
"""Cross-track gain (1/cell^2, scaled by the reference speed)."""
K_YAW = 8.0
"""Heading gain (1/s)."""
EFFECTIVE_TRACK = 0.85
"""The effective track width of the skid-steer robot in metres (its two sides' speed difference
per yaw rate): 3.4 times the geometric track of 0.25 m, measured open loop (spinning with
``FBFB``, the robot turns about 66 degrees per second at the wheel speed and 200 at three times
it, where wheels that rolled without slipping would turn it 229 and 688)."""


class ContinuousPose(NamedTuple):
    """A pose off the lattice: position in cells and yaw in radians (world frame)."""

    x: float
    y: float
    yaw: float


def wrap(angle: float) -> float:
    """``angle`` in ``(-pi, pi]``."""
    return math.atan2(math.sin(angle), math.cos(angle))


@dataclass(frozen=True, slots=True)
class LatticeMotion:
    """A lattice motion in the robot's frame: ``forward`` and ``lateral`` (right) cells and
    ``rotation`` quarter turns clockwise, as :class:`selfrepair.robots.four_wheel.Motion`."""

    forward: int
    lateral: int
    rotation: int


def _profile(t: float, duration: float) -> tuple[float, float]:
    """The trapezoidal progress ``s`` in [0, 1] at time ``t`` and its rate ``ds/dt``."""
    duration *= 1 - HOLD
    if t <= 0:
        return 0.0, 0.0
    if t >= duration:
        return 1.0, 0.0
    ramp = RAMP * duration
    peak = 1.0 / (duration - ramp)  # the rate that covers 1 with ramps of `ramp` at both ends
    if t < ramp:
        return 0.5 * peak * t * t / ramp, peak * t / ramp
    if t > duration - ramp:
        left = duration - t
        return 1.0 - 0.5 * peak * left * left / ramp, peak * left / ramp
    return 0.5 * peak * ramp + peak * (t - ramp), peak


def reference(
    start: ContinuousPose, motion: LatticeMotion, s: float
) -> tuple[ContinuousPose, float, float]:
    """The reference pose at progress ``s`` along ``motion`` from ``start``, with its forward
    speed and yaw rate per unit of progress (``dpath/ds`` in cells, ``dyaw/ds``)."""
    c, si = math.cos(start.yaw), math.sin(start.yaw)
    fwd, right = (c, si), (si, -c)
    turn = -motion.rotation * math.pi / 2  # anticlockwise positive
    if motion.rotation == 0:
        d = motion.forward
        pose = ContinuousPose(start.x + s * d * fwd[0], start.y + s * d * fwd[1], start.yaw)
        return pose, float(d), 0.0
    if motion.forward == 0 and motion.lateral == 0:
        return ContinuousPose(start.x, start.y, start.yaw + s * turn), 0.0, turn
    # an arc: a quarter circle of radius one cell about the cell beside the start
    lat = motion.lateral
    cx, cy = start.x + lat * right[0], start.y + lat * right[1]
    vx, vy = -lat * right[0], -lat * right[1]
    a = s * turn
    ca, sa = math.cos(a), math.sin(a)
    pose = ContinuousPose(cx + ca * vx - sa * vy, cy + sa * vx + ca * vy, start.yaw + a)
    speed = motion.forward * abs(turn)  # radius 1: the path length per unit progress
    return pose, float(speed), turn


def open_loop_speeds(commands: tuple[int, ...]) -> tuple[float, ...]:
    """Each wheel's speed (in units of the wheel speed) for an open-loop command."""
    return tuple(float(c) for c in commands)


class Tracker:
    """Closes the loop on the lattice motion of one action (see the module docstring).
    Mutable only in that it is asked once per control update; one per executed action.

    ``commands`` are the four wheel commands (FL, FR, RL, RR; +1, 0, -1), ``start`` the pose
    the reference starts from (the lattice start pose), ``duration`` the action's duration in
    seconds, ``cell_speed`` the wheel speed in cells per second and ``cell`` the cell size in
    metres.
    """

    __slots__ = ("_drive", "_half", "_limit", "commands", "duration", "motion", "speed", "start")

    def __init__(
        self,
        commands: tuple[int, int, int, int],
        motion: LatticeMotion,
        start: ContinuousPose,
        duration: float,
        cell_speed: float,
        max_speed_factor: float,
        cell: float,
    ) -> None:
        self._half = EFFECTIVE_TRACK / cell / 2
        self.commands = commands
        self._drive = balanced_drive(commands, motion)
        self.motion = motion
        self.start = start
        self.duration = duration
        self.speed = cell_speed
        self._limit = max_speed_factor

    def target(self, t: float) -> ContinuousPose:
        """The reference pose at ``t`` seconds into the action."""
        s, _ = _profile(t, self.duration)
        return reference(self.start, self.motion, s)[0]

    def speeds(self, pose: ContinuousPose, t: float) -> tuple[float, float, float, float]:
        """The four wheels' speeds (in units of the wheel speed, signs within the commands) at
        ``t`` seconds into the action with the robot at ``pose``."""
        s, rate = _profile(t, self.duration)
        ref, dpath, dyaw = reference(self.start, self.motion, s)
        v_ref, w_ref = dpath * rate, dyaw * rate
        dx, dy = ref.x - pose.x, ref.y - pose.y
        c, si = math.cos(pose.yaw), math.sin(pose.yaw)
        ex, ey = c * dx + si * dy, -si * dx + c * dy
        eyaw = wrap(ref.yaw - pose.yaw)
        v = v_ref * math.cos(eyaw) + K_X * ex
        w = w_ref + K_Y * v_ref * ey + K_YAW * math.sin(eyaw)
        half = self._half
        left, right = (v - w * half) / self.speed, (v + w * half) / self.speed
        fl, fr, rl, rr = self._drive
        a, c_ = _side(fl, rl, left, self._limit)
        b, d = _side(fr, rr, right, self._limit)
        return (a, b, c_, d)


def balanced_drive(
    commands: tuple[int, int, int, int], motion: LatticeMotion
) -> tuple[int, int, int, int]:
    """The wheels the tracker drives for ``commands`` (FL, FR, RL, RR), each its command or 0.

    A turn in place (no translation) whose driving wheels sit unevenly front and back turns
    about a point off the robot's centre: ``FFFB`` turns clockwise with three wheels, but only
    the rear-right one pushes backward, so the robot swings about its front and its centre
    drifts 0.1 to 0.3 cells. When a diagonal pair of wheels (front-left with rear-right, or
    front-right with rear-left) can turn each side the way the turn needs, only that pair
    drives and the other wheels are held at rest: the robot then turns about its centre, as
    with the diagonal ``FSSB``. Holding a wheel commanded F or B at rest stays within the
    command's sign (F: forward or not at all), so a replacement stays that action. Every other
    motion, and a turn that has all four wheels or no diagonal pair, drives the commands as
    they are."""
    if motion.rotation == 0 or motion.forward or motion.lateral:
        return commands
    left = 1 if motion.rotation > 0 else -1  # clockwise: the left side forward, the right back
    fl, fr, rl, rr = commands
    wanted = (left, -left, left, -left)
    if commands == wanted:
        return commands
    if fl == left and rr == -left:
        return (fl, 0, 0, rr)
    if fr == -left and rl == left:
        return (0, fr, rl, 0)
    return commands


def _side(front: int, rear: int, speed: float, limit: float) -> tuple[float, float]:
    """The two wheels of one side for a side ground speed ``speed``, within their commands'
    signs: the wheels whose command has the sign of ``speed`` share it (a side's ground speed is
    about the mean of its wheels', so one wheel alone runs at twice the side's speed); a stopped
    or opposite wheel stays at 0."""
    if speed == 0:
        return 0.0, 0.0
    sign = 1 if speed > 0 else -1
    movers = (front == sign) + (rear == sign)
    if not movers:
        return 0.0, 0.0
    each = min(abs(speed) * 2 / movers, limit) * sign
    return (each if front == sign else 0.0, each if rear == sign else 0.0)
