"""The values of a mission: what to run (:class:`MissionSpec`) and what happened
(:class:`MissionResult`, with its :class:`TraceStep` and :class:`RepairRecord` entries).

The executor (:mod:`selfrepair.execution.executor`) turns a spec into a result; metrics, traces and
experiments read results. Keeping the values here lets each of those import them without importing
the others.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from fractions import Fraction
from typing import Any, NamedTuple

from selfrepair.diagnosis.cooperative import Observer
from selfrepair.diagnosis.observation import Observation, ObservationModel
from selfrepair.errors import ProblemError
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.simulator import Outcome
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.strategies import Repair, RepairSource, StrategyName, StrategyOptions
from selfrepair.repair.tolerance import PlanObjective
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanResult
from selfrepair.search.problem import PlannerSettings
from selfrepair.status import MissionStatus
from selfrepair.world.events import WorldSchedule
from selfrepair.world.maze import Maze

__all__ = [
    "STEP_OF_OUTCOME",
    "STEP_OF_REPAIR",
    "MissionResult",
    "MissionSpec",
    "MissionStatus",
    "MissionTally",
    "RepairRecord",
    "StepSource",
    "TraceStep",
]


class StepSource(StrEnum):
    """Where an executed step's action came from: the initial plan, a repair (by its source:
    ``plan-repair`` is a plan repaired by LPG-adapt), or a command that a fault the executor did
    not know yet made fail, or a wait in place while no plan exists, or a command that bumped
    into a blocked cell the robot did not know of or, with the faults hidden, whose motion hit a
    wall (see :mod:`selfrepair.execution.stepper` and :mod:`selfrepair.execution.simulator`)."""

    PLAN = "plan"
    REPLACEMENT = RepairSource.REPLACEMENT.value
    LOOKAHEAD = RepairSource.LOOKAHEAD.value
    REPLAN = RepairSource.REPLAN.value
    PLAN_REPAIR = RepairSource.PLAN_REPAIR.value
    DETOUR = RepairSource.DETOUR.value
    PROBE = RepairSource.PROBE.value
    FAILED_ATTEMPT = Outcome.FAILED_ATTEMPT.value
    WAIT = "wait"
    BUMPED = Outcome.BUMPED.value


STEP_OF_REPAIR: Mapping[RepairSource, StepSource] = {
        RepairSource.REPLACEMENT: StepSource.REPLACEMENT,
        RepairSource.LOOKAHEAD: StepSource.LOOKAHEAD,
        RepairSource.REPLAN: StepSource.REPLAN,
        RepairSource.PLAN_REPAIR: StepSource.PLAN_REPAIR,
        RepairSource.DETOUR: StepSource.DETOUR,
        RepairSource.PROBE: StepSource.PROBE,
}
"""The step source of the actions a repair spliced in, by the repair's source: an explicit
mapping, never a conversion by value (a plain dictionary, typed read-only: one look-up inside the
timed repair)."""

STEP_OF_OUTCOME: Mapping[Outcome, StepSource] = {
    Outcome.FAILED_ATTEMPT: StepSource.FAILED_ATTEMPT,
    Outcome.BUMPED: StepSource.BUMPED,
}
"""The step source of a command that did not move as commanded, by what the simulator says it
did (the other outcomes keep the source of the queued action, or record nothing)."""


@dataclass(frozen=True, slots=True)
class MissionSpec:
    """Everything needed to run (and so replay) one mission.

    ``domain`` is the robot (the four-wheel robot unless given); ``strategy`` a name in the
    strategy registry (:func:`selfrepair.repair.strategies.get_strategy`). ``seed`` drives
    intermittent faults (see :mod:`selfrepair.execution.faults`). ``max_steps`` bounds the
    executed steps (failed attempts included); ``None`` means ``20 * cells + 100``.
    """

    maze: Maze
    start: Pose
    goal: Cell
    goal_heading: Heading | None = None
    schedule: FaultSchedule = field(default_factory=FaultSchedule)
    strategy: str = StrategyName.REPLACEMENT
    options: StrategyOptions = field(default_factory=StrategyOptions)
    clearance_weight: Fraction = Fraction(0)
    clearance_radius: int = 2
    seed: int = 0
    heuristic: str = "grid-distance"
    backend: str = "auto"
    replan_max_expansions: int | None = None
    initial_faults_known: bool = False
    max_steps: int | None = None
    domain: SomeDomain = FOUR_WHEEL
    objective: PlanObjective | None = None
    """The tolerant planner's objective for the plan made before any fault is known (``None``:
    the plain cost, duration plus clearance term); replans, made with faults known, always
    minimise the plain cost. A hard objective without a tolerant plan falls back to it too."""
    behaviour: str | None = None
    """The domain's fault-behaviour model the simulator uses when the faults are hidden from the
    robot (detection ``hidden``; ``None``: the domain's default; see
    :meth:`Domain.effective <selfrepair.robots.domain.Domain.effective>`)."""
    observation: ObservationModel = field(default_factory=ObservationModel)
    """What the robot observes after each command when the faults are hidden (odometry noise,
    bump switch; see :mod:`selfrepair.diagnosis.observation`)."""
    observers: tuple[Observer, ...] = ()
    """Faults hidden: the teammates that watch the robot move and add their readings to its
    belief (:mod:`selfrepair.diagnosis.cooperative`). They follow it: observer ``i`` (from 1)
    stands where the robot truly was ``i`` commands earlier (its start pose before that), and
    sees a command when its start and true end cells are in its sensing range."""
    world: WorldSchedule = field(default_factory=WorldSchedule)
    """Cells that become blocked or free during the mission, and how the robot senses them (see
    :mod:`selfrepair.world.events`; empty: the maze never changes)."""
    footing: str = "auto"
    """Which mission loop runs it: ``auto`` (the compiled loop of
    :mod:`selfrepair.execution.compiled` when it can take the mission, else the Python loop),
    ``compiled`` (refused with the reason when it cannot) or ``python`` (the reference). Both
    give the same trace; the result's ``footing`` says which ran."""

    def __post_init__(self) -> None:
        if self.seed < 0:
            raise ProblemError(f"seed must be a non-negative integer, got {self.seed}")
        if self.footing not in ("auto", "compiled", "python"):
            raise ProblemError(f"footing must be auto, compiled or python, got {self.footing!r}")

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

    def at_goal(self, pose: Pose) -> bool:
        """Whether ``pose`` satisfies the mission's goal."""
        return pose.cell == self.goal and (
            self.goal_heading is None or pose.heading == self.goal_heading
        )


class TraceStep(NamedTuple):
    """One executed command: what, from where to where, how long, why, and what was known.

    An immutable ``NamedTuple`` (one is made per executed step, on the mission loop's hot path;
    a frozen dataclass costs several times more to build)."""

    step: int
    action: object
    start: Pose
    end: Pose
    duration: Fraction
    source: StepSource
    known: frozenset[object]


class RepairRecord(NamedTuple):
    """One meeting with a faulty action and what the strategy did about it. ``action`` is
    ``None`` for the defensive replan made when the queue runs out away from the goal.
    An immutable ``NamedTuple`` (made per repair, on the hot path)."""

    step: int
    pose: Pose
    action: object | None
    repair: Repair
    latency_ns: int


class MissionTally(NamedTuple):
    """Sums the executor keeps while it runs, so that the metrics need not walk the steps again.

    ``actions_executed``: the number of executed (moving) steps; ``executed_units``: their total
    duration in units of ``1 / unit`` tick (see :mod:`selfrepair.execution.moves`); ``penalty``:
    the summed clearance penalty of their footprints (the cost model's
    ``max(0, radius - clearance)`` per cell, counted only when the clearance weight is not zero,
    else 0); ``plan_removed``/``plan_added``: the plan distance between the initial plan and
    the executed one, ``motion_removed``/``motion_added`` the same by motion class (see
    :mod:`selfrepair.execution.metrics`); ``waits``/``bumps``: the steps of source ``wait`` and
    ``bumped``.
    :func:`selfrepair.execution.metrics.mission_row` falls back to recomputing these from the
    steps when a result has no tally; tests check both agree.
    """

    actions_executed: int
    executed_units: int
    unit: int
    penalty: int
    plan_removed: int
    plan_added: int
    motion_removed: int
    motion_added: int
    waits: int
    bumps: int


@dataclass(frozen=True, slots=True)
class MissionResult:
    """The outcome of one mission; :func:`selfrepair.execution.metrics.mission_row` flattens it
    (columns in docs/replacement.md). ``tally`` holds sums the executor kept on the way
    (``None`` for a result made otherwise); ``footing`` the mission loop that ran it,
    ``compiled`` or ``python`` (see :attr:`MissionSpec.footing`). ``steps`` is a tuple, or for
    a compiled mission an :class:`~selfrepair.execution.compiled.trace.ArrayTrace` (the same
    steps, made from the kernel's rows when read)."""

    spec: MissionSpec
    status: MissionStatus
    reason: str
    steps: Sequence[TraceStep]
    repairs: tuple[RepairRecord, ...]
    initial_plan: PlanResult
    initial_planning_ns: int
    final_pose: Pose
    ticks: Fraction
    tally: MissionTally | None = None
    footing: str = "python"
    diagnosis: Mapping[str, Any] | None = None
    """What a diagnosing strategy recorded (faults hidden; ``None`` for any other): the step of
    the first surprise, the commands to isolation, the class isolated (its fault sets), probes
    (see :mod:`selfrepair.repair.strategies.diagnosing`)."""
    observations: tuple[Observation, ...] = ()
    """Faults hidden: every observation of the mission in order, per command the robot's own
    reading first, then its observing teammates' (empty otherwise)."""
    beliefs: tuple[int, ...] = ()
    """Faults hidden, a strategy that keeps a belief (:class:`~selfrepair.diagnosis.FaultBelief`):
    the bit set of the hypotheses still possible after each command's observations, one per
    command (empty for any other strategy)."""

    @property
    def reached(self) -> bool:
        """Whether the goal was reached."""
        return self.status is MissionStatus.REACHED

    @property
    def executed(self) -> tuple[TraceStep, ...]:
        """The steps that moved the robot (failed attempts and bumps left out): the executed
        plan."""
        return tuple(s for s in self.steps if s.source not in _NOT_EXECUTED)


_NOT_EXECUTED = frozenset({StepSource.FAILED_ATTEMPT, StepSource.BUMPED})
