"""What the robot observes after each command, and the sensor model that makes the observation.

After every command the robot gets one :class:`Observation`: the pose it reads (exact, or from a
noisy odometry model), whether its bump switch closed (when it has one), and whether the command
failed outright (the signal of a domain without a fault-behaviour model, where a forbidden command
does not move the robot). ``source`` says who observed (``"self"``, or a teammate's name: a robot
that watched this one move, see docs/diagnosis.md) and ``noise`` the error rate of the sensor that
made it, so a belief weighs each observation by its own sensor.

The odometry model (:class:`ObservationModel`, rate ``p``): with probability ``1 - p`` the reading
is the true pose after the command; with probability ``p`` it is one of the
:data:`PERTURBATIONS` of the true pose, uniformly: one of the four edge-adjacent cells with the
true heading, or the true cell with one of the three other headings ("wrong cell or heading").
The bump switch and the failed signal are exact. Draws come from a ``numpy.random.Generator``
the caller seeds from the mission's seed (never global random state), one draw per command.

Modelling choice: the pose the robot navigates by is exact (localisation against the known map is
not this question); what is noisy is the reading of each command's motion that diagnosis uses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose

__all__ = ["PERTURBATIONS", "SELF", "Observation", "ObservationModel", "perturbed"]

SELF = "self"
"""The source of the robot's own observations."""

PERTURBATIONS = 7
"""How many wrong readings a true pose has in the odometry model (4 cells, 3 headings)."""

_STEPS = ((0, -1), (1, 0), (0, 1), (-1, 0))


def perturbed(pose: Pose) -> tuple[Pose, ...]:
    """The :data:`PERTURBATIONS` wrong readings of ``pose``: the edge-adjacent cells (north, east,
    south, west) with its heading, then its cell with the heading turned 1, 2 and 3 quarters."""
    x, y, h = pose.x, pose.y, pose.heading
    cells = tuple(Pose(x + dx, y + dy, h) for dx, dy in _STEPS)
    return cells + tuple(Pose(x, y, Heading((h + turn) % 4)) for turn in (1, 2, 3))


class Observation(NamedTuple):
    """One observation of one command (see the module docstring).

    ``start`` is the pose the command started from, ``end`` the pose read after it. ``bumped`` is
    the bump switch (``None``: no switch); ``failed`` whether the command failed outright.
    ``noise`` is the odometry error rate of the sensor that made the reading and ``source`` who
    made it. An immutable ``NamedTuple`` (one per command)."""

    step: int
    action: object
    start: Pose
    end: Pose
    bumped: bool | None = None
    failed: bool = False
    noise: float = 0.0
    source: str = SELF


@dataclass(frozen=True, slots=True)
class ObservationModel:
    """What the robot's sensors report after each command: odometry with error rate ``noise``
    (0: exact) and, with ``bumps`` (the default), a bump switch (see the module docstring)."""

    noise: float = 0.0
    bumps: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.noise, int | float) or not 0.0 <= self.noise < 0.5:
            raise ProblemError(f"expected an odometry noise rate in [0, 0.5), got {self.noise!r}")
        if not isinstance(self.bumps, bool):
            raise ProblemError(f"expected bumps to be true or false, got {self.bumps!r}")

    def read(
        self,
        step: int,
        action: object,
        start: Pose,
        end: Pose,
        bumped: bool,
        failed: bool,
        rng: np.random.Generator | None,
        source: str = SELF,
    ) -> Observation:
        """The observation of one command that took the robot from ``start`` to ``end`` (truly),
        bumping or failing as said; ``rng`` draws the odometry error (needed when ``noise > 0``)."""
        reading = end
        if self.noise > 0.0:
            if rng is None:
                raise ProblemError("a noisy observation model needs a random generator")
            draw = float(rng.random())
            if draw < self.noise:
                reading = perturbed(end)[int(draw / self.noise * PERTURBATIONS)]
        return Observation(
            step, action, start, reading, bumped if self.bumps else None, failed, self.noise, source
        )
