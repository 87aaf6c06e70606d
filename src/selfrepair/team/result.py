"""The values of a team mission run: its options (:class:`TeamOptions`), what happened
(:class:`TeamResult` and its records) and the vocabularies they use.

Times are integer units (``scale`` units per tick, see
:attr:`selfrepair.robots.domain.Domain.time_unit`).
Records come in the order they happened; traces (:mod:`selfrepair.team.trace`) and metrics
(:mod:`selfrepair.team.metrics`) read them.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction

from selfrepair.errors import ProblemError, choice
from selfrepair.execution.result import StepSource
from selfrepair.geometry import Cell, Pose
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import MissionKind, RepairSource, RepairStatus, StrategyName
from selfrepair.status import RepairOutcome, TeamStatus
from selfrepair.team.model import (
    IncidentKind,
    Load,
    TeamAction,
    TeamScenario,
    TeamTableName,
)

__all__ = [
    "ActRecord",
    "DiscoveryRecord",
    "FaultRecord",
    "IncidentRecord",
    "MoveRecord",
    "OwnRepairRecord",
    "RepairOutcome",
    "TeamOptions",
    "TeamRepairRecord",
    "TeamResult",
    "TeamSource",
    "TeamStatus",
]


class TeamSource(StrEnum):
    """Where a queued higher-level action came from."""

    PLAN = "plan"
    TEAM_REPLACEMENT = StrategyName.TEAM_REPLACEMENT.value
    REALLOCATION = StrategyName.REALLOCATION.value
    ALONE = StrategyName.ALONE.value
    YIELD = "yield"


@dataclass(frozen=True, slots=True)
class TeamOptions:
    """How a team mission is run.

    ``strategy`` is a team strategy (a team member of
    :class:`~selfrepair.repair.strategies.StrategyName`) and ``table`` its team
    replacement table. Each robot handles its own wheel faults first with the single-robot
    strategy ``robot_strategy`` (a name in :mod:`selfrepair.repair.strategies`), table
    ``robot_table`` (a bundled name or a file; ``""``: the scenario's ``table``, else the
    robot's default, see :mod:`selfrepair.team.robottable`) and ``recursion``. ``max_depth``
    bounds nested team replacements (the recursion guard's depth). ``max_ticks`` ends the
    mission (default: see :func:`selfrepair.team.engine.default_max_ticks`). ``max_wait_ticks``
    is the longest wait :func:`~selfrepair.team.spacetime.schedule_path` accepts before
    cooperative A* is tried, with ``spacetime_expansions`` nodes at most. ``seed`` is recorded
    with the results (the engine draws nothing at random; scenarios are drawn from it).
    """

    strategy: str = StrategyName.TEAM_REPLACEMENT
    table: str = TeamTableName.HANDWRITTEN
    robot_strategy: str = StrategyName.REPLACEMENT
    robot_table: str = ""
    recursion: RecursionMode = RecursionMode.FLAT
    max_depth: int = 2
    backend: str = "auto"
    max_ticks: int | None = None
    max_wait_ticks: int = 24
    spacetime_expansions: int = 5_000
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "strategy", StrategyName.of(self.strategy, MissionKind.TEAM))
        object.__setattr__(self, "table", choice(TeamTableName, self.table, "team table"))
        object.__setattr__(
            self, "recursion", choice(RecursionMode, self.recursion, "recursion mode")
        )
        if self.max_depth < 0 or self.max_wait_ticks < 0 or self.spacetime_expansions < 1:
            raise ProblemError(
                "max_depth and max_wait_ticks must be >= 0, spacetime_expansions >= 1"
            )
        if self.max_ticks is not None and not 1 <= self.max_ticks <= 10**7:
            raise ProblemError(f"max_ticks must be from 1 to 10000000, got {self.max_ticks}")
        if self.seed < 0:
            raise ProblemError(f"seed must be a non-negative integer, got {self.seed}")

    @property
    def label(self) -> str:
        """A short readable variant such as ``team-replacement[handwritten]``."""
        if self.strategy is StrategyName.TEAM_REPLACEMENT:
            return f"{self.strategy}[{self.table}]"
        return str(self.strategy)


@dataclass(frozen=True, slots=True)
class MoveRecord:
    """One primitive action of one robot, from ``before`` at ``start`` to ``after`` at ``end``."""

    robot: str
    start: int
    end: int
    action: object
    before: Pose
    after: Pose
    source: StepSource


@dataclass(frozen=True, slots=True)
class ActRecord:
    """One pick, drop or handover, from ``start`` to ``end``, at the cells the robots stood on."""

    start: int
    end: int
    action: TeamAction
    cells: tuple[Cell, ...]


@dataclass(frozen=True, slots=True)
class FaultRecord:
    """Team fault number ``index`` of the scenario became active (or cleared) at ``at``."""

    at: int
    index: int
    active: bool


@dataclass(frozen=True, slots=True)
class DiscoveryRecord:
    """``robot`` learned of its team fault number ``index`` at ``at``, ``delay`` units after the
    fault started (0 when it senses its faults at once; with detection ``on-use`` it learns a
    fault when a command it forbids fails; an intermittent fault may also first show later)."""

    at: int
    robot: str
    index: int
    delay: int


@dataclass(frozen=True, slots=True)
class IncidentRecord:
    """``robot``'s next action could not go on, for reason ``kind``, with ``load``."""

    at: int
    robot: str
    action: TeamAction
    kind: IncidentKind
    load: Load


@dataclass(frozen=True, slots=True)
class OwnRepairRecord:
    """A robot's own repair of a faulty primitive action (its single-robot strategy)."""

    at: int
    robot: str
    pose: Pose
    action: object
    status: RepairStatus
    source: RepairSource
    actions: tuple[object, ...]
    latency_ns: int


@dataclass(frozen=True, slots=True)
class TeamRepairRecord:
    """What the team strategy did about one incident.

    ``candidate`` names the team replacement used (empty otherwise) and ``helper`` the teammate
    it recruited; ``preempted`` says whether the helper had work of its own, delayed by about
    ``preemption_ticks``. ``disturbed`` lists the robots other than the incident's whose plans
    changed; ``messages`` counts robot-to-robot notifications (a changed plan or a broadcast
    fault, one per receiving robot); ``plans`` counts drive plannings made within the repair and
    ``expansions`` their search nodes. ``latency_ns`` runs from the incident until every changed
    robot has its next action placed in time (wall clock); ``cpu_ns`` is the processor time the
    engine's thread spent in that stretch, which other processes on a shared machine do not
    inflate. ``changes`` lists the actions inserted per robot;
    ``lost`` the items given up.
    """

    at: int
    robot: str
    action: TeamAction
    kind: IncidentKind
    outcome: RepairOutcome
    source: TeamSource
    candidate: str = ""
    helper: str = ""
    preempted: bool = False
    preemption_ticks: int = 0
    disturbed: tuple[str, ...] = ()
    messages: int = 0
    plans: int = 0
    expansions: int = 0
    latency_ns: int = 0
    changes: tuple[tuple[str, tuple[TeamAction, ...]], ...] = ()
    lost: tuple[str, ...] = ()
    cpu_ns: int = 0


@dataclass(frozen=True, slots=True)
class TeamResult:
    """The outcome of one team mission.

    ``initial_plan`` is each robot's queue after the initial allocation; ``delivered`` the items
    with the unit at which their drop finished; ``end`` the last unit simulated. Counters:
    ``messages`` and ``plans`` over the whole mission (``plans``: every drive planning, lattice
    and space-time, with ``expansions`` their search nodes), ``yields`` (idle robots asked to clear
    a path). ``discoveries``: when each robot learned of each of its wheel faults.
    """

    scenario: TeamScenario
    options: TeamOptions
    status: TeamStatus
    reason: str
    scale: int
    initial_plan: tuple[tuple[str, tuple[TeamAction, ...]], ...]
    allocation_ns: int
    moves: tuple[MoveRecord, ...]
    acts: tuple[ActRecord, ...]
    faults: tuple[FaultRecord, ...]
    incidents: tuple[IncidentRecord, ...]
    repairs: tuple[TeamRepairRecord, ...]
    own_repairs: tuple[OwnRepairRecord, ...]
    delivered: tuple[tuple[str, int], ...]
    end: int
    messages: int = 0
    plans: int = 0
    yields: int = 0
    expansions: int = 0
    discoveries: tuple[DiscoveryRecord, ...] = ()

    @property
    def makespan(self) -> Fraction:
        """Ticks until the last delivered item was dropped (0 when none was)."""
        last = max((at for _, at in self.delivered), default=0)
        return Fraction(last, self.scale)

    @property
    def all_delivered(self) -> bool:
        """Whether every task was delivered."""
        return len(self.delivered) == len(self.scenario.tasks)
