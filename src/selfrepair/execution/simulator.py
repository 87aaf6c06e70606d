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
from typing import Any, NamedTuple, Protocol

from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection, FaultClock, FaultSchedule
from selfrepair.execution.moves import Move, MoveTable, available_moves, move_table
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import Domain
from selfrepair.search.problem import make_pose, pose_table
from selfrepair.world.maze import Maze

__all__ = ["FAILED_ATTEMPT_TICKS", "FaultSource", "Outcome", "Simulator", "StepOutcome"]

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


class FaultSource(Protocol):
    """The true faults over time: what :class:`~selfrepair.execution.faults.FaultClock` is for a
    schedule (a team robot's clock, whose faults start at events no schedule knows in advance,
    is another)."""

    def at(self, step: int, units: int) -> frozenset[Any]:
        """The faults active at the start of step ``step``, ``units`` time units in (the same
        object while they do not change)."""
        ...


class Simulator:
    """The true world for one mission (mutable: the pose, step count and clock advance).

    Motion comes from the domain's :class:`~selfrepair.execution.moves.MoveTable` (derived from
    ``Domain.apply``/``footprint``/``duration`` once per domain), footprints are tested against the
    maze's :class:`~selfrepair.geometry.FreeGrid` with a margin of the table's reach, and the clock
    counts integer time units (``ticks`` is the exact :class:`~fractions.Fraction`).
    ``clock`` replaces the schedule's fault clock when the true faults are not a function of a
    schedule alone (a team robot's); the schedule then gives only the detection. A robot that
    waits between commands (a team robot waiting for its turn) says so with
    :meth:`wait_until`.
    """

    deviated = False
    """Whether the last move ended elsewhere than the domain says (never, here: a physics
    simulator, :mod:`selfrepair.physics.simulator`, sets it after localising the robot); the
    mission loop then replans from the pose the robot is at."""

    def __init__(
        self,
        domain: Domain[Any, Any],
        maze: Maze,
        start: Pose,
        schedule: FaultSchedule,
        seed: int = 0,
        clock: FaultSource | None = None,
    ) -> None:
        self.domain = domain
        self.maze = maze
        self.schedule = schedule
        self.seed = seed
        self.pose = start
        self.steps = 0
        margin = max(2, move_table(domain, 1).reach)
        self.grid = maze.free_grid(margin)
        self.table: MoveTable = move_table(domain, self.grid.stride)
        self.unit = self.table.unit
        self.units = 0
        """Elapsed time in units of ``1 / unit`` tick."""
        self.last_move: Move | None = None
        """The move of the last command if it moved the robot, else ``None``."""
        self.last_duration = Fraction(0)
        self.last_blocking: frozenset[Any] = frozenset()
        self._clock: FaultSource = clock or FaultClock(schedule, seed, self.unit)
        self._sense_now = schedule.detection is Detection.NOW
        self._faults: frozenset[Any] | None = None
        self._moves: dict[Any, tuple[Move, ...]] = {}
        self._failed_units = int(FAILED_ATTEMPT_TICKS * self.unit)
        self._inside = maze.in_bounds(start.x, start.y)
        self._pw = maze.width + 2
        self._poses = pose_table(maze) if self.table.ends_covered else None

    @property
    def ticks(self) -> Fraction:
        """The exact elapsed time."""
        return Fraction(self.units, self.unit)

    def true_faults(self) -> frozenset[Any]:
        """The faults active now (at the start of the next step)."""
        return self._clock.at(self.steps, self.units)

    def sense(self) -> frozenset[Any]:
        """What the robot's sensors report before the next step.

        Detection ``now``: the active faults. Detection ``on-use``: nothing (faults are learned only
        from failed attempts).
        """
        if self._sense_now:
            return self._clock.at(self.steps, self.units)
        return frozenset()

    def wait_until(self, units: int) -> None:
        """Let time pass without a command until ``units`` (no step; never backwards)."""
        if units < self.units:
            raise ProblemError(f"time runs forwards: {units} < {self.units} units")
        self.units = units

    def execute(self, action: Any) -> StepOutcome:
        """Command ``action`` from the current pose and advance the world."""
        start, step = self.pose, self.steps
        status = self.advance(action)
        if status is Outcome.FAILED_ATTEMPT:
            swept: tuple[Cell, ...] = (start.cell,)
        else:  # the footprint of the move table, shifted (a collision moves nothing)
            x, y = start.x, start.y
            shape = self.table.shapes[action][start.heading]
            swept = tuple([(x + dx, y + dy) for dx, dy in shape])
        return StepOutcome(
            status, step, action, start, self.pose, swept, self.last_duration, self.last_blocking
        )

    def advance(self, action: Any) -> Outcome:
        """Command ``action`` and advance the world; what it did is left in ``pose``,
        ``last_move``, ``last_duration`` and ``last_blocking`` (the executor's fast path:
        :meth:`execute` wraps it into a :class:`StepOutcome`). A collision changes nothing."""
        faults = self._clock.at(self.steps, self.units)
        if faults is not self._faults:
            self._faults = faults
            self._moves = available_moves(self.table, faults)
        moves = self._moves.get(action)
        start = self.pose
        if moves is None:
            self.last_move = None
            self.last_duration = FAILED_ATTEMPT_TICKS
            self.last_blocking = self.domain.blocking(action, faults)
            self.units += self._failed_units
        else:
            move = moves[start.heading]
            if not self._free(start, move, action):
                self.last_move = None
                self.last_duration = Fraction(0)
                self.last_blocking = frozenset()
                return Outcome.COLLISION
            x, y, heading = start.x + move.dx, start.y + move.dy, move.heading
            poses = self._poses
            if poses is not None and self._inside:  # the end is on the grid: a shared pose
                state = ((y + 1) * self._pw + x + 1) * 4 + heading
                end = poses[state] or _shared(poses, state, x, y, heading)
            else:
                end = make_pose(x, y, heading)
                if not self.table.ends_covered:  # the end cell may lie off the footprint
                    self._inside = self.maze.in_bounds(x, y)
            self.pose = end
            self.last_move = move
            self.last_duration = move.duration
            self.last_blocking = frozenset()
            self.units += move.units
        self.steps += 1
        return Outcome.MOVED if moves is not None else Outcome.FAILED_ATTEMPT

    def _free(self, start: Pose, move: Move, action: Any) -> bool:
        """Whether the footprint of ``move`` from ``start`` is free (on the grid)."""
        if not self._inside:  # a start off the grid: the general test
            return self.grid.all_free(self.domain.footprint(start, action))
        grid = self.grid
        data = grid.data
        base = (start.y + grid.margin) * grid.stride + start.x + grid.margin
        for offset in move.cells:  # noqa: SIM110 - a loop is faster than all() on a generator
            if not data[base + offset]:
                return False
        return True


def _shared(poses: list[Pose | None], state: int, x: int, y: int, heading: Heading) -> Pose:
    """Make the pose of ``state`` and keep it in the maze's pose table."""
    pose = poses[state] = make_pose(x, y, heading)
    return pose
