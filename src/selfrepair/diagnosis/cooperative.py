"""Cooperative diagnosis: teammates that watch a robot move add their readings to its belief.

A robot with hidden faults reads its own motion through odometry with error rate ``p``
(:mod:`~.observation`). A teammate standing near it sees the same motion with its own sensor (a
camera, a lidar) and tells the robot what it saw. Each such reading is one more
:class:`~.observation.Observation` of the command, made with the same odometry model (with
probability ``1 - p_i`` the true pose after the command, else one of its seven wrong readings,
uniformly) but with the observer's own rate ``p_i`` and its own random stream, so its errors are
independent of the robot's. The robot's :class:`~.belief.FaultBelief` takes it in by the same
:meth:`~.belief.FaultBelief.update` as its own reading: one more likelihood term, with the
observation's own noise rate. There is no second belief.

What a teammate sees is its *view* (:class:`ObserverView`, ``--observer-view``):

- ``pose`` (the default): the robot's pose after the command, as above: the same information as
  the robot's own odometry, from an independent sensor;
- ``wheels``: the pose reading and, besides it, the robot's actuators
  (:attr:`Domain.actuators <selfrepair.robots.domain.Domain.actuators>`: for the four-wheel robot,
  which wheels turn and which way), i.e. the effective command the faults made of the command
  (``Domain.effective``, the one world model), each actuator read wrong with the observer's rate
  ``p_i`` (:func:`~.observation.read_actuators`). It reads them whenever it watches the whole
  motion, a bump included (the wheels were driven before the bumper stopped them); a command
  that failed outright (a domain without a fault-behaviour model) turns no actuator and gives no
  actuator reading. The actuator draws come from a stream of their own, ``[seed, 24, 1 + i,
  1]``, so an observer's pose readings are the same draws under either view.

- :class:`SensingRange`: how far an observer sees, ``cells`` in the ``metric`` (Chebyshev: the
  square of side ``2 * cells + 1`` around it; Manhattan: the diamond).
- :class:`Observer`: a teammate's name (the observation's ``source``), its sensor's error rate,
  its sensing range and its view. A teammate observes a command when **both** the robot's cell
  before the command and its true cell after it are in range of the teammate's cell (it watched
  the whole motion); where the teammate stands is given per command.
- :func:`observer_team`: ``t1``, ``t2``, ... alike (experiment files, ``--observers``);
- :func:`observer_streams`: per observer, its pose stream ``[seed, 24, 1 + i]`` and actuator
  stream ``[seed, 24, 1 + i, 1]`` (:class:`Streams`) from the mission's seed (the robot's own
  stream is ``[seed, 24]``), so the same seed gives the same readings and no two sensors share a
  generator.
- :func:`following`: where each observer stands for the next command when the team follows
  the robot (observer ``i``, from 1, where the robot truly was ``i`` commands before: the
  simulator's rule, which the robot's probe planner and the trace check use too);
- :func:`team_observations`: the observations of one command by the observers in range.

A teammate has no access to the robot's bump switch (``bumped`` is ``None`` in its reading); the
"command failed" signal it carries is the robot's own (it says which predictions the pose is
compared with, and the robot knows it exactly anyway).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from selfrepair.diagnosis.observation import (
    SELF,
    Observation,
    ObservationModel,
    actuators_of,
    read_actuators,
)
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "OBSERVER_STREAM",
    "Metric",
    "Observer",
    "ObserverView",
    "SensingRange",
    "Streams",
    "following",
    "observer_streams",
    "observer_team",
    "team_observations",
]

OBSERVER_STREAM = 24
"""The stream number shared with the robot's own readings; observer ``i`` draws from
``[seed, OBSERVER_STREAM, 1 + i]``."""


class ObserverView(enum.Enum):
    """What an observer sees of a command it watches (see the module docstring)."""

    POSE = "pose"
    """The robot's pose after the command."""
    WHEELS = "wheels"
    """The pose and the robot's actuators (which wheels turn, which way)."""


class Metric(enum.Enum):
    """The distance a :class:`SensingRange` is measured in, over whole cells."""

    CHEBYSHEV = "chebyshev"
    MANHATTAN = "manhattan"


@dataclass(frozen=True, slots=True)
class SensingRange:
    """An observer sees a cell at most ``cells`` away from its own in ``metric``."""

    cells: int = 3
    metric: Metric = Metric.CHEBYSHEV

    def __post_init__(self) -> None:
        if isinstance(self.cells, bool) or not isinstance(self.cells, int) or self.cells < 0:
            raise ProblemError(f"expected a sensing range of at least 0 cells, got {self.cells!r}")
        if not isinstance(self.metric, Metric):
            raise ProblemError(f"expected a sensing metric of {[m.value for m in Metric]}")

    def distance(self, a: Cell, b: Cell) -> int:
        """The distance of cells ``a`` and ``b`` in this range's metric."""
        dx, dy = abs(a[0] - b[0]), abs(a[1] - b[1])
        return max(dx, dy) if self.metric is Metric.CHEBYSHEV else dx + dy

    def sees(self, observer: Cell, cell: Cell) -> bool:
        """Whether an observer at ``observer`` sees ``cell``."""
        return self.distance(observer, cell) <= self.cells


@dataclass(frozen=True, slots=True)
class Observer:
    """A teammate that watches the robot: ``name`` (the observations' ``source``; not
    ``"self"``), the odometry error rate ``noise`` of its sensor (the model of
    :class:`~.observation.ObservationModel`; the wheel view reads each actuator with the same
    rate), its :class:`SensingRange` and its :class:`ObserverView`."""

    name: str
    noise: float = 0.0
    sensing: SensingRange = SensingRange()
    view: ObserverView = ObserverView.POSE

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or self.name == SELF:
            raise ProblemError(f"expected an observer name other than {SELF!r}, got {self.name!r}")
        ObservationModel(self.noise)  # validates the rate
        if not isinstance(self.view, ObserverView):
            raise ProblemError(f"expected an observer view of {[v.value for v in ObserverView]}")

    @property
    def wheels(self) -> bool:
        """Whether it sees the robot's actuators (:attr:`ObserverView.WHEELS`)."""
        return self.view is ObserverView.WHEELS

    def watches(self, at: Pose, start: Pose, end: Pose) -> bool:
        """Whether, standing at ``at``, it sees the whole motion from ``start`` to ``end``."""
        here = (at.x, at.y)
        return self.sensing.sees(here, (start.x, start.y)) and self.sensing.sees(
            here, (end.x, end.y)
        )


def observer_team(
    count: int, noise: float, cells: int, view: ObserverView = ObserverView.POSE
) -> tuple[Observer, ...]:
    """``count`` observers named ``t1``, ``t2``, ... with odometry error rate ``noise``, a
    Chebyshev range of ``cells`` and ``view`` (the teams of experiment files and
    ``--observers``)."""
    sensing = SensingRange(cells)
    return tuple(Observer(f"t{i}", noise, sensing, view) for i in range(1, count + 1))


class Streams(NamedTuple):
    """One observer's random streams: ``pose`` for its pose readings, ``wheels`` for its
    actuator readings (the wheel view)."""

    pose: np.random.Generator
    wheels: np.random.Generator


def observer_streams(seed: int, observers: Sequence[Observer]) -> tuple[Streams, ...]:
    """The :class:`Streams` of each observer, in order (see the module docstring)."""
    return tuple(
        Streams(
            np.random.default_rng([seed, OBSERVER_STREAM, 1 + i]),
            np.random.default_rng([seed, OBSERVER_STREAM, 1 + i, 1]),
        )
        for i in range(len(observers))
    )


def following(trail: Sequence[Pose], count: int) -> tuple[Pose, ...]:
    """Where observers ``1 .. count`` stand for the next command when they follow the robot:
    ``trail`` holds the robot's true poses from the mission's start, the last its pose now (the
    next command's start); observer ``i`` stands at ``trail[-1 - i]`` (the start, while the
    trail is shorter)."""
    if not trail:
        raise ProblemError("expected a trail of at least the start pose")
    last = len(trail) - 1
    return tuple(trail[max(0, last - i)] for i in range(1, count + 1))


def team_observations(
    step: int,
    action: object,
    start: Pose,
    end: Pose,
    failed: bool,
    observers: Sequence[Observer],
    poses: Sequence[Pose],
    streams: Sequence[Streams],
    *,
    performed: object = None,
    domain: SomeDomain | None = None,
) -> tuple[Observation, ...]:
    """The readings of one command by the observers that watch it: the robot was commanded
    ``action`` at ``start`` and truly ended at ``end`` (after a bump: ``start``), ``failed`` as
    said; observer ``i`` stands at ``poses[i]`` and draws from ``streams[i]``. In observer order.
    An observer with the wheel view also reads the actuators of ``performed``, the action the
    actuators truly performed (``Domain.effective`` of ``action`` under the true faults), of
    ``domain``: both are needed then, unless the command failed.

    An observer out of range draws nothing, so an observer's readings do not depend on where the
    others stand."""
    if not len(observers) == len(poses) == len(streams):
        raise ProblemError(
            f"expected one pose and one stream per observer, got {len(observers)} observers, "
            f"{len(poses)} poses and {len(streams)} streams"
        )
    wheels = not failed and any(o.wheels for o in observers)
    if wheels:
        if domain is None or performed is None:
            raise ProblemError("the wheel view needs the domain and the action performed")
        actuators_of(domain)  # fails for a domain without actuators
    out = []
    for observer, at, rng in zip(observers, poses, streams, strict=True):
        if observer.watches(at, start, end):
            model = ObservationModel(observer.noise, bumps=False)
            seen = model.read(step, action, start, end, False, failed, rng.pose, observer.name)
            if wheels and observer.wheels:
                assert domain is not None
                read = read_actuators(domain, performed, observer.noise, rng.wheels)
                seen = seen._replace(wheels=read)
            out.append(seen)
    return tuple(out)
