"""The values of a mission: what to run (:class:`MissionSpec`) and what happened
(:class:`MissionResult`, with its :class:`TraceStep` and :class:`RepairRecord` entries).

The executor (:mod:`selfrepair.execution.executor`) turns a spec into a result; metrics, traces and
experiments read results. Keeping the values here lets each of those import them without importing
the others.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

from selfrepair.errors import ProblemError
from selfrepair.execution.faults import FaultSchedule
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.strategies import PlannerSettings, Repair, StrategyOptions
from selfrepair.robots.four_wheel import Action, FaultSet
from selfrepair.search.problem import PlanResult
from selfrepair.world.maze import Maze

__all__ = ["SOURCES", "STATUSES", "MissionResult", "MissionSpec", "RepairRecord", "TraceStep"]


STATUSES = ("reached", "stuck", "budget_exhausted", "no_initial_plan", "step_limit", "collision")
"""Mission outcomes: goal reached; a repair replan found no plan (``stuck``); a replan hit its
planner budget (``budget_exhausted``); the initial plan failed (``no_initial_plan``, see
``MissionResult.reason``); ``max_steps`` steps without reaching the goal (``step_limit``); the
simulator refused a move into a wall (``collision``, never expected)."""


SOURCES = ("plan", "replacement", "lookahead", "replan", "failed-attempt")
"""Where an executed step's action came from."""


@dataclass(frozen=True, slots=True)
class MissionSpec:
    """Everything needed to run (and so replay) one mission.

    ``seed`` drives intermittent faults (see :mod:`selfrepair.execution.faults`). ``max_steps`` bounds
    the executed steps (failed attempts included); ``None`` means ``20 * cells + 100``.
    """

    maze: Maze
    start: Pose
    goal: Cell
    goal_heading: Heading | None = None
    schedule: FaultSchedule = field(default_factory=FaultSchedule)
    strategy: str = "replacement"
    options: StrategyOptions = field(default_factory=StrategyOptions)
    clearance_weight: Fraction = Fraction(0)
    clearance_radius: int = 2
    seed: int = 0
    heuristic: str = "grid-distance"
    backend: str = "auto"
    replan_max_expansions: int | None = None
    initial_faults_known: bool = False
    max_steps: int | None = None

    def __post_init__(self) -> None:
        if self.seed < 0:
            raise ProblemError(f"seed must be a non-negative integer, got {self.seed}")

    @property
    def planner(self) -> PlannerSettings:
        """The planner settings shared by every planner call of the mission."""
        return PlannerSettings(
            self.heuristic,
            self.backend,
            Fraction(self.clearance_weight),
            self.clearance_radius,
            self.replan_max_expansions,
        )

    def step_limit(self) -> int:
        """``max_steps`` or its default."""
        if self.max_steps is not None:
            return self.max_steps
        return 20 * self.maze.width * self.maze.height + 100


@dataclass(frozen=True, slots=True)
class TraceStep:
    """One executed command: what, from where to where, how long, why, and what was known."""

    step: int
    action: Action
    start: Pose
    end: Pose
    duration: Fraction
    source: str
    known: FaultSet


@dataclass(frozen=True, slots=True)
class RepairRecord:
    """One meeting with a faulty action and what the strategy did about it. ``action`` is
    ``None`` for the defensive replan made when the queue runs out away from the goal."""

    step: int
    pose: Pose
    action: Action | None
    repair: Repair
    latency_ns: int


@dataclass(frozen=True, slots=True)
class MissionResult:
    """The outcome of one mission; :meth:`to_row` flattens it (columns in docs/replacement.md)."""

    spec: MissionSpec
    status: str
    reason: str
    steps: tuple[TraceStep, ...]
    repairs: tuple[RepairRecord, ...]
    initial_plan: PlanResult
    initial_planning_ns: int
    final_pose: Pose
    ticks: Fraction

    @property
    def reached(self) -> bool:
        """Whether the goal was reached."""
        return self.status == "reached"

    @property
    def executed(self) -> tuple[TraceStep, ...]:
        """The steps that moved the robot (failed attempts left out): the executed plan."""
        return tuple(s for s in self.steps if s.source != "failed-attempt")
