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

- :class:`SensingRange`: how far an observer sees, ``cells`` in the ``metric`` (Chebyshev: the
  square of side ``2 * cells + 1`` around it; Manhattan: the diamond).
- :class:`Observer`: a teammate's name (the observation's ``source``), its sensor's error rate
  and its sensing range. A teammate observes a command when **both** the robot's cell before the
  command and its true cell after it are in range of the teammate's cell (it watched the whole
  motion); where the teammate stands is given per command.
- :func:`observer_team`: ``t1``, ``t2``, ... alike (experiment files, ``--observers``);
- :func:`observer_streams`: one ``numpy.random.Generator`` per observer, seeded ``[seed, 24, 1 +
  i]`` from the mission's seed (the robot's own stream is ``[seed, 24]``), so the same seed gives
  the same readings and no two sensors share a generator.
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

import numpy as np

from selfrepair.diagnosis.observation import SELF, Observation, ObservationModel
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Pose

__all__ = [
    "OBSERVER_STREAM",
    "Metric",
    "Observer",
    "SensingRange",
    "following",
    "observer_streams",
    "observer_team",
    "team_observations",
]

OBSERVER_STREAM = 24
"""The stream number shared with the robot's own readings; observer ``i`` draws from
``[seed, OBSERVER_STREAM, 1 + i]``."""


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
    :class:`~.observation.ObservationModel`) and its :class:`SensingRange`."""

    name: str
    noise: float = 0.0
    sensing: SensingRange = SensingRange()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or self.name == SELF:
            raise ProblemError(f"expected an observer name other than {SELF!r}, got {self.name!r}")
        ObservationModel(self.noise)  # validates the rate

    def watches(self, at: Pose, start: Pose, end: Pose) -> bool:
        """Whether, standing at ``at``, it sees the whole motion from ``start`` to ``end``."""
        here = (at.x, at.y)
        return self.sensing.sees(here, (start.x, start.y)) and self.sensing.sees(
            here, (end.x, end.y)
        )


def observer_team(count: int, noise: float, cells: int) -> tuple[Observer, ...]:
    """``count`` observers named ``t1``, ``t2``, ... with odometry error rate ``noise`` and a
    Chebyshev range of ``cells`` (the teams of experiment files and ``--observers``)."""
    sensing = SensingRange(cells)
    return tuple(Observer(f"t{i}", noise, sensing) for i in range(1, count + 1))


def observer_streams(seed: int, observers: Sequence[Observer]) -> tuple[np.random.Generator, ...]:
    """One generator per observer, in order (see the module docstring)."""
    return tuple(
        np.random.default_rng([seed, OBSERVER_STREAM, 1 + i]) for i in range(len(observers))
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
    streams: Sequence[np.random.Generator],
) -> tuple[Observation, ...]:
    """The readings of one command by the observers that watch it: the robot was commanded
    ``action`` at ``start`` and truly ended at ``end`` (after a bump: ``start``), ``failed`` as
    said; observer ``i`` stands at ``poses[i]`` and draws from ``streams[i]``. In observer order.

    An observer out of range draws nothing, so an observer's readings do not depend on where the
    others stand."""
    if not len(observers) == len(poses) == len(streams):
        raise ProblemError(
            f"expected one pose and one stream per observer, got {len(observers)} observers, "
            f"{len(poses)} poses and {len(streams)} streams"
        )
    out = []
    for observer, at, rng in zip(observers, poses, streams, strict=True):
        if observer.watches(at, start, end):
            model = ObservationModel(observer.noise, bumps=False)
            out.append(model.read(step, action, start, end, False, failed, rng, observer.name))
    return tuple(out)
