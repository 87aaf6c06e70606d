"""The simulated world: the robot's true pose, the true faults, and what each command does.

The :class:`Simulator` is the only place that knows the true fault state; the executor
(:mod:`selfrepair.execution.executor`) knows only what the simulator lets it sense
(:meth:`Simulator.sense`) or what a failed attempt reveals. Motion comes from the robot's
:class:`~selfrepair.robots.domain.Domain`; nothing is re-derived here.

A command whose action a true fault forbids is a *failed attempt*: the robot does not move, one
tick passes, and the outcome names the faults that blocked it. A command that would sweep a wall
is refused with outcome ``"collision"`` and nothing changes (the executor never sends one; the
tests check that).
"""

from __future__ import annotations

from enum import StrEnum
from fractions import Fraction
from typing import Any, NamedTuple

from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import Domain
from selfrepair.world.maze import Maze

__all__ = ["FAILED_ATTEMPT_TICKS", "Outcome", "Simulator", "StepOutcome"]

FAILED_ATTEMPT_TICKS = Fraction(1)
"""What a failed attempt costs."""


class Outcome(StrEnum):
    """What one command did."""

    MOVED = "moved"
    FAILED_ATTEMPT = "failed-attempt"
    COLLISION = "collision"


class StepOutcome(NamedTuple):
    """What one command did, where from and to, how long it took and which faults blocked it.

    An immutable ``NamedTuple`` rather than a frozen dataclass: one is built for every simulated
    step, and a frozen dataclass costs several times more to construct.
    """

    status: Outcome
    step: int
    action: Any
    start: Pose
    end: Pose
    swept: tuple[Cell, ...]
    duration: Fraction
    blocking: frozenset[Any]


class Simulator:
    """The true world for one mission (mutable: the pose, step count and clock advance)."""

    def __init__(
        self,
        domain: Domain[Any, Any],
        maze: Maze,
        start: Pose,
        schedule: FaultSchedule,
        seed: int = 0,
    ) -> None:
        self.domain = domain
        self.maze = maze
        self.grid = maze.free_grid()
        self.schedule = schedule
        self.seed = seed
        self.pose = start
        self.steps = 0
        self.ticks = Fraction(0)
        self._active: tuple[int, Fraction, frozenset[Any]] | None = None

    def true_faults(self) -> frozenset[Any]:
        """The faults active now (at the start of the next step).

        A pure function of (schedule, seed, step, tick), so it is computed once per step: the
        executor and the Gymnasium environment ask for it to sense and again to execute.
        """
        steps, ticks = self.steps, self.ticks
        active = self._active
        # ``ticks`` is a new Fraction whenever time passes, so identity is the cheap test.
        if active is not None and active[0] == steps and active[1] is ticks:
            return active[2]
        faults = self.schedule.active_faults(steps, ticks, self.seed)
        self._active = (steps, ticks, faults)
        return faults

    def sense(self) -> frozenset[Any]:
        """What the robot's sensors report before the next step.

        Detection ``now``: the active faults. Detection ``on-use``: nothing (faults are learned only
        from failed attempts).
        """
        if self.schedule.detection is Detection.NOW:
            return self.true_faults()
        return frozenset()

    def execute(self, action: Any) -> StepOutcome:
        """Command ``action`` from the current pose and advance the world."""
        domain = self.domain
        faults = self.true_faults()
        start = self.pose
        if not domain.available(action, faults):
            outcome = StepOutcome(
                Outcome.FAILED_ATTEMPT,
                self.steps,
                action,
                start,
                start,
                (start.cell,),
                FAILED_ATTEMPT_TICKS,
                domain.blocking(action, faults),
            )
        else:
            end, swept, duration = domain.step(start, action)
            if not self.grid.all_free(swept):
                return StepOutcome(
                    Outcome.COLLISION, self.steps, action, start, start, swept, Fraction(0),
                    frozenset(),
                )  # fmt: skip
            outcome = StepOutcome(
                Outcome.MOVED, self.steps, action, start, end, swept, Fraction(duration),
                frozenset(),
            )  # fmt: skip
        self.pose = outcome.end
        self.steps += 1
        self.ticks += outcome.duration
        return outcome
