"""The simulated world: the robot's true pose, the true faults, and what each command does.

The :class:`Simulator` is the only place that knows the true fault state; the executor
(:mod:`selfrepair.execution.executor`) knows only what the simulator lets it sense (:meth:`Simulator.sense`)
or what a failed attempt reveals. Motion comes from :func:`selfrepair.robots.four_wheel.step`; nothing is
re-derived here.

A command whose action a true fault forbids is a *failed attempt*: the robot does not move, one
tick passes, and the outcome names the faults that blocked it. A command that would sweep a wall
is refused with outcome ``"collision"`` and nothing changes (the executor never sends one; the
tests check that).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from selfrepair.execution.faults import FaultSchedule
from selfrepair.geometry import Cell, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import Action, FaultSet
from selfrepair.world.maze import Maze

__all__ = ["FAILED_ATTEMPT_TICKS", "Simulator", "StepOutcome"]

FAILED_ATTEMPT_TICKS = Fraction(1)
"""What a failed attempt costs."""


@dataclass(frozen=True, slots=True)
class StepOutcome:
    """What one command did. ``status`` is ``"moved"``, ``"failed-attempt"`` or ``"collision"``."""

    status: str
    step: int
    action: Action
    start: Pose
    end: Pose
    swept: tuple[Cell, ...]
    duration: Fraction
    blocking: FaultSet


class Simulator:
    """The true world for one mission (mutable: the pose, step count and clock advance)."""

    def __init__(self, maze: Maze, start: Pose, schedule: FaultSchedule, seed: int = 0) -> None:
        self.maze = maze
        self.schedule = schedule
        self.seed = seed
        self.pose = start
        self.steps = 0
        self.ticks = Fraction(0)

    def true_faults(self) -> FaultSet:
        """The faults active now (at the start of the next step)."""
        return self.schedule.active_faults(self.steps, self.ticks, self.seed)

    def sense(self) -> FaultSet:
        """What the robot's sensors report before the next step.

        Detection ``now``: the active faults. Detection ``on-use``: nothing (faults are learned only
        from failed attempts).
        """
        if self.schedule.detection == "now":
            return self.true_faults()
        return frozenset()

    def execute(self, action: Action) -> StepOutcome:
        """Command ``action`` from the current pose and advance the world."""
        faults = self.true_faults()
        start = self.pose
        if not four_wheel.available(action, faults):
            blocking = frozenset(f for f in faults if not four_wheel.available(action, (f,)))
            outcome = StepOutcome(
                "failed-attempt",
                self.steps,
                action,
                start,
                start,
                (start.cell,),
                FAILED_ATTEMPT_TICKS,
                blocking,
            )
        else:
            end, swept, duration = four_wheel.step(start, action)
            if not self.maze.all_free(swept):
                return StepOutcome(
                    "collision", self.steps, action, start, start, swept, Fraction(0), frozenset()
                )
            outcome = StepOutcome(
                "moved", self.steps, action, start, end, swept, duration, frozenset()
            )
        self.pose = outcome.end
        self.steps += 1
        self.ticks += outcome.duration
        return outcome
