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

A watching teammate may also read the robot's actuators (the *wheel view*, see
:mod:`~.cooperative`): ``wheels`` is then the action the actuators were seen performing, read
actuator by actuator (:attr:`Domain.actuators <selfrepair.robots.domain.Domain.actuators>`, the
four-wheel robot: each wheel's mode) by :func:`read_actuators`: each actuator's state is read
right with probability ``1 - p`` and as one of its other states, uniformly, with probability
``p`` (the same rate as the sensor's pose readings), one draw per actuator.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "PERTURBATIONS",
    "SELF",
    "Actuators",
    "Observation",
    "ObservationModel",
    "actuators_of",
    "perturbed",
    "read_actuators",
]

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
    made it. ``wheels`` is the action a teammate with the wheel view saw the actuators perform
    (read with the same rate ``noise`` per actuator, :func:`read_actuators`; ``None``: no
    actuator reading). An immutable ``NamedTuple`` (one per command)."""

    step: int
    action: object
    start: Pose
    end: Pose
    bumped: bool | None = None
    failed: bool = False
    noise: float = 0.0
    source: str = SELF
    wheels: object = None


@dataclass(frozen=True, slots=True, eq=False)
class Actuators:
    """The actuators of one domain as a watching teammate sees them: ``states[a]`` the state of
    each actuator in action ``a`` (an index into ``Domain.actions``), ``values[i]`` the states
    actuator ``i`` takes (in order of first appearance), ``action`` the action of each
    combination of states (every combination is one: checked by ``check_domain``)."""

    states: tuple[tuple[Any, ...], ...]
    values: tuple[tuple[Any, ...], ...]
    action: dict[tuple[Any, ...], int]

    def mismatches(self, a: int, b: int) -> int:
        """How many actuators actions ``a`` and ``b`` (indices) set differently."""
        return sum(x != y for x, y in zip(self.states[a], self.states[b], strict=True))

    def likelihood(self, read: int, performed: int, noise: float) -> float:
        """The chance that action ``performed`` is read as ``read`` (indices) at error rate
        ``noise`` per actuator: ``1 - noise`` per actuator read right, ``noise / (m - 1)`` per
        actuator of ``m`` states read as one other state."""
        value = 1.0
        for i, (x, y) in enumerate(zip(self.states[read], self.states[performed], strict=True)):
            value *= 1.0 - noise if x == y else noise / (len(self.values[i]) - 1)
        return value


def actuators_of(domain: SomeDomain) -> Actuators:
    """The :class:`Actuators` of ``domain`` (kept); :class:`ProblemError` for a domain that
    declares none (:attr:`Domain.actuators <selfrepair.robots.domain.Domain.actuators>`)."""
    if domain.actuators is None:
        raise ProblemError(
            f"domain {domain.name!r} declares no actuators a teammate can see (the wheel view "
            "needs them)"
        )
    return _ACTUATORS.get(domain, lambda: _actuators(domain))


def _actuators(domain: SomeDomain) -> Actuators:
    assert domain.actuators is not None
    states = tuple(tuple(domain.actuators(a)) for a in domain.actions)
    values = tuple(tuple(dict.fromkeys(column)) for column in zip(*states, strict=True))
    return Actuators(states, values, {s: i for i, s in enumerate(states)})


_ACTUATORS: BoundedCache[SomeDomain, Actuators] = BoundedCache(
    "diagnosis actuator tables", 16, kind=CacheKind.PREFILLED
)


def read_actuators(
    domain: SomeDomain, performed: object, noise: float, rng: np.random.Generator | None
) -> object:
    """The action a teammate reads the actuators as performing when they truly perform
    ``performed``: each actuator read right with probability ``1 - noise``, else as one of its
    other states uniformly (one draw per actuator from ``rng``; none when ``noise == 0``)."""
    if noise == 0.0:
        return performed
    if rng is None:
        raise ProblemError("a noisy actuator reading needs a random generator")
    table = actuators_of(domain)
    states = list(table.states[domain.actions.index(performed)])
    for i, draw in enumerate(rng.random(len(states))):
        if draw < noise:
            others = [v for v in table.values[i] if v != states[i]]
            states[i] = others[int(draw / noise * len(others))]
    return domain.actions[table.action[tuple(states)]]


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
