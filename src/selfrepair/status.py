"""One family of end statuses: how a search, a repair, a mission, a team mission, an LPG call and
a Gymnasium episode ended, and the explicit conversions between them.

Each layer reports its own ending (a search knows nothing of missions), so the statuses stay
separate enums; but they are defined here, side by side, at the ground of the package, and one
status becomes another only through the mappings below, never by value (``MissionStatus(x.value)``
would silently accept any string that happens to match, and break when a value is renamed).
:data:`POSITIVE_OUTCOMES` holds the member of each enum that means success, after
unified-planning's ``POSITIVE_OUTCOMES`` of its result statuses.

The values are the words written in result rows and traces; they do not change.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import Enum, StrEnum
from types import MappingProxyType

from selfrepair.errors import ProblemError

__all__ = [
    "MISSION_OF_REPAIR",
    "POSITIVE_OUTCOMES",
    "REPAIR_OF_PLAN",
    "EpisodeEnd",
    "LpgStatus",
    "MissionStatus",
    "PlanStatus",
    "RepairOutcome",
    "RepairStatus",
    "TeamStatus",
    "is_positive",
    "mission_status",
    "repair_status",
]


class PlanStatus(Enum):
    """How a search ended. "No path" and "budget hit" are different outcomes."""

    SOLVED = "solved"
    UNSOLVABLE = "unsolvable"
    BUDGET_EXHAUSTED = "budget_exhausted"


class RepairStatus(StrEnum):
    """How a repair ended: a repaired queue, no plan exists, or the planner's budget ran out."""

    REPAIRED = "repaired"
    STUCK = "stuck"
    BUDGET_EXHAUSTED = "budget_exhausted"


class MissionStatus(StrEnum):
    """How a mission ended: goal reached; a repair replan found no plan (``stuck``); a replan hit
    its planner budget (``budget_exhausted``); the initial plan failed (``no_initial_plan``, see
    ``MissionResult.reason``); ``max_steps`` steps without reaching the goal (``step_limit``); the
    simulator refused a move into a wall (``collision``, never expected)."""

    REACHED = "reached"
    STUCK = "stuck"
    BUDGET_EXHAUSTED = "budget_exhausted"
    NO_INITIAL_PLAN = "no_initial_plan"
    STEP_LIMIT = "step_limit"
    COLLISION = "collision"


class TeamStatus(StrEnum):
    """How a team mission ended: every task delivered; nothing more could happen (``stalled``:
    the robots left with work cannot act and no fault will clear); or ``max_ticks`` passed."""

    DELIVERED = "delivered"
    STALLED = "stalled"
    TIME_LIMIT = "time_limit"


class RepairOutcome(StrEnum):
    """What a team strategy did about an incident: changed the plan (``repaired``), let the robot
    wait and try again (``deferred``), or gave the incident's task up (``lost``)."""

    REPAIRED = "repaired"
    DEFERRED = "deferred"
    LOST = "lost"


class LpgStatus(Enum):
    """How an LPG call ended."""

    SOLVED = "solved"
    NO_PLAN = "no-plan"
    TIMEOUT = "timeout"
    ERROR = "error"


class EpisodeEnd(StrEnum):
    """How an episode ended: the goal reached, the step limit, or the policy gave up."""

    REACHED = "reached"
    TRUNCATED = "truncated"
    GAVE_UP = "gave_up"


POSITIVE_OUTCOMES: tuple[Enum, ...] = (
    PlanStatus.SOLVED,
    RepairStatus.REPAIRED,
    MissionStatus.REACHED,
    TeamStatus.DELIVERED,
    RepairOutcome.REPAIRED,
    LpgStatus.SOLVED,
    EpisodeEnd.REACHED,
)
"""The success of each status enum (a deferred team repair or a truncated episode is not one).
A tuple, not a set: string enums of different kinds with the same value compare equal."""

_POSITIVE = frozenset((type(status), status.value) for status in POSITIVE_OUTCOMES)


def is_positive(status: Enum) -> bool:
    """Whether ``status`` is its enum's success (one of :data:`POSITIVE_OUTCOMES`, by kind and
    value: a plain string ``"reached"`` is no status)."""
    return (type(status), status.value) in _POSITIVE


REPAIR_OF_PLAN: Mapping[PlanStatus, RepairStatus] = MappingProxyType(
    {
        PlanStatus.SOLVED: RepairStatus.REPAIRED,
        PlanStatus.UNSOLVABLE: RepairStatus.STUCK,
        PlanStatus.BUDGET_EXHAUSTED: RepairStatus.BUDGET_EXHAUSTED,
    }
)
"""How a repair that planned ends, by how its search ended."""

MISSION_OF_REPAIR: Mapping[RepairStatus, MissionStatus] = MappingProxyType(
    {
        RepairStatus.STUCK: MissionStatus.STUCK,
        RepairStatus.BUDGET_EXHAUSTED: MissionStatus.BUDGET_EXHAUSTED,
    }
)
"""How a mission ends when a repair fails, by how the repair failed (a repaired queue ends
nothing, so ``repaired`` has no entry)."""


def repair_status(status: PlanStatus) -> RepairStatus:
    """The status of a repair whose search ended with ``status``."""
    return REPAIR_OF_PLAN[status]


def mission_status(status: RepairStatus) -> MissionStatus:
    """The end of a mission whose repair ended with ``status`` (a failed one: ``repaired`` ends
    no mission and raises :class:`~selfrepair.errors.ProblemError`)."""
    ended = MISSION_OF_REPAIR.get(status)
    if ended is None:
        raise ProblemError(f"a repair that ended {status!s} does not end a mission")
    return ended
