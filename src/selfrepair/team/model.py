"""The values of a team mission: robots, tasks, team faults, the scenario, and the higher-level
actions a team plan is made of.

A team plan is one queue of :class:`TeamAction` per robot:

``drive(r, a -> b)``
    Robot ``r`` drives from cell ``a`` to cell ``b`` (any heading). It is carried out with the
    robot's own planner and fault handling (:mod:`selfrepair.team.engine`). A drive is identified
    by its robot, start and goal, so a detour ``drive(r, a -> w); drive(r, w -> b)`` does not
    contain the drive it replaces (the recursion guard compares identities).
``pick(r, i)``
    ``r`` stands on the cell where item ``i`` lies, has a working gripper and carries nothing;
    afterwards it carries ``i``.
``drop(r, i)``
    ``r`` carries ``i`` and has a working gripper; ``i`` then lies on ``r``'s cell (delivered when
    that is the task's drop-off cell).
``handover(g, t, i)``
    ``g`` carries ``i``, ``t`` carries nothing, their cells are 4-adjacent and ``t``'s gripper
    works (the taker grasps; the giver only lets go, so an immobilised robot or one with a
    broken gripper can still give). Both robots take part; the action sits in both queues.

A robot carries at most one item. Pick, drop and handover take :data:`PICK_TICKS`,
:data:`DROP_TICKS` and :data:`HANDOVER_TICKS`. Time inside the team engine is counted in integer
*units* of ``1 / domain.time_unit`` ticks (thirds of a tick for the four-wheel robot), so every
action's duration is a whole number of units.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from enum import StrEnum

from selfrepair.errors import InputError, ProblemError
from selfrepair.execution.faults import Detection, Persistence, lasting_problem
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.events import WorldSchedule
from selfrepair.world.maze import Maze

__all__ = [
    "DROP_TICKS",
    "HANDOVER_TICKS",
    "NAME_PATTERN",
    "PICK_TICKS",
    "ActionKind",
    "IncidentKind",
    "Load",
    "RobotSpec",
    "Task",
    "TeamAction",
    "TeamFault",
    "TeamFaultKind",
    "TeamScenario",
    "TeamTableName",
    "Trigger",
    "drive",
    "drop",
    "format_plan",
    "handover",
    "parse_team_action",
    "pick",
]

PICK_TICKS = 2
"""Ticks a pick takes."""
DROP_TICKS = 2
"""Ticks a drop takes."""
HANDOVER_TICKS = 2
"""Ticks a handover takes (both robots are busy)."""

NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,31}$")
"""Robot and item names: a letter, then up to 31 letters, digits, ``_`` or ``-``."""


class ActionKind(StrEnum):
    """The higher-level actions of a team plan."""

    DRIVE = "drive"
    PICK = "pick"
    DROP = "drop"
    HANDOVER = "handover"


class TeamFaultKind(StrEnum):
    """What can go wrong in a team: a robot loses every motion (``immobilised``), a robot gets
    wheel faults of its domain (``wheels``, handled by its own table first), a gripper stops
    working (``gripper``: no pick, no drop, no taking in a handover), or cells of the maze become
    impassable (``blocked``: the dynamic environment)."""

    IMMOBILISED = "immobilised"
    WHEELS = "wheels"
    GRIPPER = "gripper"
    BLOCKED = "blocked"


class Trigger(StrEnum):
    """When a team fault starts: ``at`` ticks into the mission (``tick``), or ``at`` ticks after
    its robot's first completed pick (``pick``: the robot is then carrying an item)."""

    TICK = "tick"
    PICK = "pick"


class IncidentKind(StrEnum):
    """Why a robot's next higher-level action cannot go on, as the team learns it: the robot
    cannot drive to its target (``stuck``: immobilised, or its own wheel-fault repair found
    nothing), its drive met a blocked cell or its target cannot be reached on the known map
    (``blocked``), or its gripper failed (``gripper``)."""

    STUCK = "stuck"
    BLOCKED = "blocked"
    GRIPPER = "gripper"


class Load(StrEnum):
    """Whether the robot with the incident carries an item."""

    EMPTY = "empty"
    CARRYING = "carrying"


class TeamTableName(StrEnum):
    """The team replacement tables (see :mod:`selfrepair.team.table`)."""

    HANDWRITTEN = "handwritten"
    GENERATED = "generated"


# --- robots, tasks, faults ---------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class RobotSpec:
    """One robot of the team: its name, start pose and equipment (with or without gripper)."""

    name: str
    start: Pose
    gripper: bool = True


@dataclass(frozen=True, slots=True)
class Task:
    """Deliver ``item``, lying at ``pickup`` at the start, to ``dropoff``."""

    item: str
    pickup: Cell
    dropoff: Cell


@dataclass(frozen=True, slots=True)
class TeamFault:
    """One team fault (see :class:`TeamFaultKind` and :class:`Trigger`).

    ``robot`` names the faulty robot (not for ``blocked``), ``cells`` the blocked cells,
    ``wheel_faults`` the domain faults of a ``wheels`` fault (in the domain's text, e.g.
    ``"FL:F,RR:B"``). ``persistence`` is ``permanent``, ``transient`` (then active for
    ``duration`` ticks) or, for the faults of a robot's wheels (``immobilised``, ``wheels``),
    ``intermittent``: from its start on, present at each of the robot's steps with
    ``probability`` (see :class:`~selfrepair.team.state.RobotFaultClock`).
    """

    kind: TeamFaultKind
    robot: str = ""
    cells: tuple[Cell, ...] = ()
    wheel_faults: str = ""
    at: int = 0
    trigger: Trigger = Trigger.TICK
    persistence: Persistence = Persistence.PERMANENT
    duration: int | None = None
    probability: float | None = None

    def __post_init__(self) -> None:
        if self.at < 0:
            raise ProblemError(f"a team fault's 'at' must be >= 0, got {self.at}")
        intermittent = self.persistence is Persistence.INTERMITTENT
        if intermittent and self.kind not in (TeamFaultKind.IMMOBILISED, TeamFaultKind.WHEELS):
            raise ProblemError(
                "only a robot's wheel faults (immobilised, wheels) can be intermittent"
            )
        if not intermittent and self.probability is not None:
            raise ProblemError("only an intermittent team fault has a probability")
        problem = lasting_problem(self.persistence, self.duration, self.probability)
        if problem is not None:
            raise ProblemError(problem)
        if self.kind is TeamFaultKind.BLOCKED and (self.robot or not self.cells):
            raise ProblemError("a blocked fault names cells and no robot")
        if self.kind is not TeamFaultKind.BLOCKED and not self.robot:
            raise ProblemError(f"a {self.kind} fault names its robot")
        if self.kind is TeamFaultKind.BLOCKED and self.trigger is Trigger.PICK:
            raise ProblemError("a blocked fault starts at a tick (trigger = tick)")

    def describe(self) -> str:
        """A short human summary such as ``"immobilised r2, 3 ticks after its first pick"``."""
        what = {
            TeamFaultKind.IMMOBILISED: f"immobilised {self.robot}",
            TeamFaultKind.WHEELS: f"wheels {self.wheel_faults} on {self.robot}",
            TeamFaultKind.GRIPPER: f"gripper of {self.robot}",
            TeamFaultKind.BLOCKED: "blocked " + " ".join(f"{x},{y}" for x, y in self.cells),
        }[self.kind]
        when = f"tick {self.at}" if self.trigger is Trigger.TICK else f"{self.at} ticks after pick"
        last = f" for {self.duration} ticks" if self.persistence is Persistence.TRANSIENT else ""
        if self.persistence is Persistence.INTERMITTENT:
            last = f", intermittent p={self.probability}"
        return f"{what} from {when}{last}"


@dataclass(frozen=True, slots=True)
class TeamScenario:
    """A whole team mission's world: maze, robots, tasks and team faults, for the robot
    ``domain`` (every robot is of the same kind; equipment may differ). ``table`` is the
    robots' own replacement table for their wheel faults (a bundled name, ``"generated"`` or a
    table file; ``""``: the domain's default, see
    :func:`selfrepair.tables.fileformat.default_table`). ``source`` names the file it came from
    and ``digest`` is the SHA-256 of that file's text (``""`` for a scenario built in code).
    ``detection`` is how every robot learns of its wheel faults (as in a single robot's
    :class:`~selfrepair.execution.faults.FaultSchedule`: ``now``, sensed before every command,
    or ``on-use``, learned when a command fails). ``world`` holds the world events (cells that
    become blocked or free at given ticks, :mod:`selfrepair.world.events`) and how the robots
    sense them; every robot's simulator applies the one schedule (docs/team.md, "A changing
    world"). Checked by :func:`selfrepair.team.check.check_scenario`."""

    maze: Maze
    robots: tuple[RobotSpec, ...]
    tasks: tuple[Task, ...]
    faults: tuple[TeamFault, ...] = ()
    domain: SomeDomain = FOUR_WHEEL
    name: str = ""
    source: str = "<scenario>"
    table: str = ""
    digest: str = ""
    detection: Detection = Detection.NOW
    world: WorldSchedule = field(default_factory=WorldSchedule)
    _index: dict[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_index", {r.name: i for i, r in enumerate(self.robots)})

    def robot(self, name: str) -> RobotSpec:
        """The robot called ``name``."""
        return self.robots[self._index[name]]

    def task(self, item: str) -> Task:
        """The task of ``item``."""
        for task in self.tasks:
            if task.item == item:
                return task
        raise ProblemError(f"no task delivers item {item!r}")

    def without_faults(self) -> TeamScenario:
        """The same scenario with no team fault and no world event (the undisturbed baseline;
        no longer the file's content, so without its digest)."""
        return replace(self, faults=(), digest="", world=replace(self.world, events=()))


# --- higher-level actions ----------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class TeamAction:
    """One higher-level action (see the module docstring); build with :func:`drive`,
    :func:`pick`, :func:`drop` or :func:`handover`. ``robot`` is the acting robot (the giver of a
    handover), ``taker`` the receiving one."""

    kind: ActionKind
    robot: str
    item: str = ""
    taker: str = ""
    source: Cell | None = None
    target: Cell | None = None

    @property
    def robots(self) -> tuple[str, ...]:
        """Every robot that takes part."""
        return (self.robot, self.taker) if self.kind is ActionKind.HANDOVER else (self.robot,)

    def __str__(self) -> str:
        if self.kind is ActionKind.DRIVE:
            assert self.source is not None and self.target is not None
            (ax, ay), (bx, by) = self.source, self.target
            return f"drive({self.robot},{ax},{ay}->{bx},{by})"
        if self.kind is ActionKind.HANDOVER:
            return f"handover({self.robot},{self.taker},{self.item})"
        return f"{self.kind}({self.robot},{self.item})"


def drive(robot: str, source: Cell, target: Cell) -> TeamAction:
    """``drive(robot, source -> target)``."""
    return TeamAction(ActionKind.DRIVE, robot, source=source, target=target)


def pick(robot: str, item: str) -> TeamAction:
    """``pick(robot, item)``."""
    return TeamAction(ActionKind.PICK, robot, item=item)


def drop(robot: str, item: str) -> TeamAction:
    """``drop(robot, item)``."""
    return TeamAction(ActionKind.DROP, robot, item=item)


def handover(giver: str, taker: str, item: str) -> TeamAction:
    """``handover(giver, taker, item)``."""
    return TeamAction(ActionKind.HANDOVER, giver, item=item, taker=taker)


_NAME = r"[A-Za-z][A-Za-z0-9_-]*"
_INT = r"-?\d+"
_ACTION_TEXT = re.compile(
    rf"^(?:drive\((?P<dr>{_NAME}),(?P<ax>{_INT}),(?P<ay>{_INT})->(?P<bx>{_INT}),(?P<by>{_INT})\)"
    rf"|(?P<kind>pick|drop)\((?P<pr>{_NAME}),(?P<pi>{_NAME})\)"
    rf"|handover\((?P<hg>{_NAME}),(?P<ht>{_NAME}),(?P<hi>{_NAME})\))$"
)


def parse_team_action(text: str, *, source: str = "<team action>") -> TeamAction:
    """Parse the text form written by ``str(action)``, e.g. ``"drive(r1,3,4->7,8)"``."""
    m = _ACTION_TEXT.match(text.replace(" ", ""))
    if m is None:
        raise InputError(
            "expected a team action such as drive(r1,3,4->7,8), pick(r1,i1), drop(r1,i1) or "
            f"handover(r1,r2,i1), got {text!r}",
            source=source,
        )
    if m.group("dr"):
        return drive(
            m.group("dr"),
            (int(m.group("ax")), int(m.group("ay"))),
            (int(m.group("bx")), int(m.group("by"))),
        )
    if m.group("kind"):
        return TeamAction(ActionKind(m.group("kind")), m.group("pr"), item=m.group("pi"))
    return handover(m.group("hg"), m.group("ht"), m.group("hi"))


def format_plan(actions: Iterable[TeamAction]) -> list[str]:
    """The text of each action, for traces and displays."""
    return [str(a) for a in actions]
