"""The simulated world: the robot's true pose, the true faults, and what each command does.

The :class:`Simulator` is the only place that knows the true fault state; the executor
(:mod:`selfrepair.execution.executor`) knows only what the simulator lets it sense
(:meth:`Simulator.sense`) or what a failed attempt reveals. Motion comes from the robot's
:class:`~selfrepair.robots.domain.Domain`; nothing is re-derived here.

A command whose action a true fault forbids is a *failed attempt*: the robot does not move, one
tick passes, and the outcome names the faults that blocked it. A command that would sweep a wall
is refused with outcome ``"collision"`` and nothing changes (the executor never sends one; the
tests check that).

With a :class:`~selfrepair.world.events.WorldSchedule` the simulator also holds the true
occupancy over time: before each command it applies the events whose time has come to its own
copy of the free-cell buffer, and a command whose motion would sweep a blocked cell (other than
the robot's own) is a *bump* (outcome ``"bumped"``): the robot does not move, one tick passes and
``last_bumped`` names the blocked cells. :meth:`Simulator.sense_cells` is what the robot's range
sensors report (see :mod:`selfrepair.world.events`).

With detection ``hidden`` (the robot is never told its faults) a forbidden command is not refused:
the wheels do what the domain's fault-behaviour model says (:meth:`Domain.effective
<selfrepair.robots.domain.Domain.effective>`, model ``behaviour``, the domain's default unless
given), and the robot moves accordingly. Any motion whose footprint (its swept cells) is not free
then stops at the contact, a *bump* (outcome ``"bumped"``, as above): poses are whole cells and a
footprint lists the cells a motion sweeps, not the order in which it reaches them, so the last
free pose along the motion is the start pose. The robot stays there, heading unchanged, and one
tick passes (the bumper stops the motors at the contact); :attr:`Simulator.bumps` counts the
contacts with walls (``last_bumped`` names only cells blocked by world events, not walls).
A domain without a fault-behaviour model fails a forbidden command as above, but the outcome
names no fault (``blocking`` is empty): the robot learns only that the command failed.
"""

from __future__ import annotations

from enum import StrEnum
from fractions import Fraction
from typing import NamedTuple, Protocol

import numpy as np

from selfrepair.diagnosis.cooperative import (
    Observer,
    following,
    observer_streams,
    team_observations,
)
from selfrepair.diagnosis.observation import Observation, ObservationModel
from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection, FaultClock, FaultSchedule
from selfrepair.execution.moves import Move, MoveTable, available_moves, move_table
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.problem import make_pose, pose_table
from selfrepair.world.events import Sensing, WorldSchedule
from selfrepair.world.maze import Maze

__all__ = [
    "FAILED_ATTEMPT_TICKS",
    "OBSERVATION_STREAM",
    "FaultSource",
    "Outcome",
    "Simulator",
    "StepOutcome",
]

OBSERVATION_STREAM = 24
"""The second word of the seed of the observation noise generator, ``[seed, 24]``: a stream of
its own, so observation draws never share a generator with anything else."""

FAILED_ATTEMPT_TICKS = Fraction(1)
"""What a failed attempt costs."""


class Outcome(StrEnum):
    """What one command did."""

    MOVED = "moved"
    FAILED_ATTEMPT = "failed-attempt"
    COLLISION = "collision"
    BUMPED = "bumped"


class StepOutcome(NamedTuple):
    """What one command did, where from and to, how long it took and which faults blocked it.

    An immutable ``NamedTuple`` rather than a frozen dataclass: one is built for every simulated
    step, and a frozen dataclass costs several times more to construct.
    """

    status: Outcome
    step: int
    action: object
    start: Pose
    end: Pose
    swept: tuple[Cell, ...]
    duration: Fraction
    blocking: frozenset[object]


class FaultSource(Protocol):
    """The true faults over time: what :class:`~selfrepair.execution.faults.FaultClock` is for a
    schedule (a team robot's clock, whose faults start at events no schedule knows in advance,
    is another)."""

    def at(self, step: int, units: int) -> frozenset[object]:
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
    :meth:`wait_until`. ``behaviour`` names the domain's fault-behaviour model used when the
    faults are hidden (``None``: the default; see the module docstring).
    """

    deviated = False
    """Whether the last move ended elsewhere than the domain says (never, here: a physics
    simulator, :mod:`selfrepair.physics.simulator`, sets it after localising the robot); the
    mission loop then replans from the pose the robot is at."""

    def __init__(
        self,
        domain: SomeDomain,
        maze: Maze,
        start: Pose,
        schedule: FaultSchedule,
        seed: int = 0,
        clock: FaultSource | None = None,
        world: WorldSchedule | None = None,
        behaviour: str | None = None,
        observation: ObservationModel | None = None,
        observers: tuple[Observer, ...] = (),
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
        self.last_blocking: frozenset[object] = frozenset()
        self._clock: FaultSource = clock or FaultClock(schedule, seed, self.unit)
        self._sense_now = schedule.detection is Detection.NOW
        self._faults: frozenset[object] | None = None
        self._moves: dict[object, tuple[Move, ...]] = {}
        self._failed_units = int(FAILED_ATTEMPT_TICKS * self.unit)
        self._inside = maze.in_bounds(start.x, start.y)
        self._pw = maze.width + 2
        self._poses = pose_table(maze) if self.table.ends_covered else None
        self.world = world or None
        """The world events (``None``: the maze never changes)."""
        self.blocked: dict[Cell, None] = {}
        """The cells blocked now by world events, in the order they were blocked."""
        self.last_bumped: tuple[Cell, ...] = ()
        """The blocked cells the last command bumped into (empty unless it bumped)."""
        self._data = bytearray(self.grid.data) if self.world else self.grid.data
        self._next_event = 0
        self._event_cells = frozenset(self.world.cells()) if self.world else frozenset()
        self._hidden = schedule.detection is Detection.HIDDEN
        self.behaviour = behaviour
        if self._hidden and domain.behaviours:
            domain.behaviour(behaviour)  # an unknown name fails before the first step
        self._performed: dict[object, object] = {}
        """The effective action of each commanded action under the current faults (hidden)."""
        self.last_action: object = None
        """The action the wheels really performed in the last command (hidden faults: the
        effective action; otherwise the command)."""
        self.bumps = 0
        """Motions stopped at a wall so far (hidden faults only)."""
        self.observation = observation or ObservationModel()
        """What the robot's sensors report after each command (faults hidden)."""
        self._rng = np.random.default_rng([seed, OBSERVATION_STREAM]) if self._hidden else None
        self.observers = observers if self._hidden else ()
        """The teammates that watch the robot (faults hidden; see :meth:`witnessed`)."""
        self._streams = observer_streams(seed, observers) if self.observers else ()
        self._trail: list[Pose] = [start]

    @property
    def ticks(self) -> Fraction:
        """The exact elapsed time."""
        return Fraction(self.units, self.unit)

    def true_faults(self) -> frozenset[object]:
        """The faults active now (at the start of the next step)."""
        return self._clock.at(self.steps, self.units)

    def sense(self) -> frozenset[object]:
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

    def execute(self, action: object) -> StepOutcome:
        """Command ``action`` from the current pose and advance the world."""
        start, step = self.pose, self.steps
        status = self.advance(action)
        if status is Outcome.FAILED_ATTEMPT or status is Outcome.BUMPED:
            swept: tuple[Cell, ...] = (start.cell,)
        else:  # the footprint of the move table, shifted (a collision moves nothing)
            x, y = start.x, start.y
            shape = self.table.shapes[self.performed(action)][start.heading]
            swept = tuple([(x + dx, y + dy) for dx, dy in shape])
        return StepOutcome(
            status, step, action, start, self.pose, swept, self.last_duration, self.last_blocking
        )

    def performed(self, action: object) -> object:
        """The action the wheels performed for ``action``, the command just executed: with the
        faults hidden the effective action (:attr:`last_action`), else the command itself."""
        return self.last_action if self._hidden else action

    def advance(self, action: object) -> Outcome:
        """Command ``action`` and advance the world; what it did is left in ``pose``,
        ``last_move``, ``last_duration`` and ``last_blocking`` (the executor's fast path:
        :meth:`execute` wraps it into a :class:`StepOutcome`). A collision changes nothing."""
        if self.world is not None:
            self._apply_events()
        if self._hidden:
            return self._advance_hidden(action)
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
            if self.world is not None and (bumped := self._bumped(start, move)):
                self.last_move = None
                self.last_duration = FAILED_ATTEMPT_TICKS
                self.last_blocking = frozenset()
                self.last_bumped = bumped
                self.units += self._failed_units
                self.steps += 1
                return Outcome.BUMPED
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

    def observe(self, step: int, action: object, start: Pose, outcome: Outcome) -> Observation:
        """What the robot observes of its last command, ``action`` (number ``step``) from
        ``start`` with ``outcome``: a reading of its pose after it by :attr:`observation`, with
        the bump switch and the failed signal (seeded: one draw per command from the
        generator of ``[seed, OBSERVATION_STREAM]``)."""
        return self.observation.read(
            step,
            action,
            start,
            self.pose,
            outcome is Outcome.BUMPED,
            outcome is Outcome.FAILED_ATTEMPT,
            self._rng,
        )

    def witnessed(
        self, step: int, action: object, start: Pose, outcome: Outcome
    ) -> tuple[Observation, ...]:
        """What the observing teammates saw of the last command (see :meth:`observe`): they
        follow the robot, observer ``i`` (from 1) standing where it truly was ``i`` commands
        before this one (its start pose before that), and each in range of the motion reads the
        true end with its own sensor and stream ``[seed, 24, i]``; with the wheel view also the
        actuators of the action truly performed (:attr:`last_action`, ``Domain.effective``),
        from stream ``[seed, 24, i, 1]``
        (:func:`~selfrepair.diagnosis.cooperative.team_observations`). Call it once per command,
        after :meth:`observe`; empty without observers."""
        if not self.observers:
            return ()
        trail = self._trail
        behind = following(trail, len(self.observers))
        trail.append(self.pose)
        return team_observations(
            step,
            action,
            start,
            self.pose,
            outcome is Outcome.FAILED_ATTEMPT,
            self.observers,
            behind,
            self._streams,
            performed=self.last_action,
            domain=self.domain,
        )

    def _advance_hidden(self, action: object) -> Outcome:
        """:meth:`advance` with the faults hidden from the robot (see the module docstring):
        the effective action moves, a swept wall stops the motion at the start pose (a bump)."""
        faults = self._clock.at(self.steps, self.units)
        if faults is not self._faults:
            self._faults = faults
            self._moves = available_moves(self.table, faults)
            self._performed = {}
        start = self.pose
        self.last_blocking = frozenset()
        self.steps += 1
        performed = action
        if action not in self._moves:
            if not self.domain.behaviours:  # no model: the command fails, nothing is named
                self.last_move, self.last_action = None, action
                self.last_duration = FAILED_ATTEMPT_TICKS
                self.units += self._failed_units
                return Outcome.FAILED_ATTEMPT
            performed = self._performed.get(action)
            if performed is None:
                performed = self.domain.effective(action, faults, self.behaviour)
                self._performed[action] = performed
        self.last_action = performed
        move = self.table.moves[performed][start.heading]
        self.last_bumped = ()
        wall = not self._free(start, move, performed)
        if wall or (self.world is not None and (bumped := self._bumped(start, move))):
            self.last_move = None
            self.last_duration = FAILED_ATTEMPT_TICKS
            self.units += self._failed_units
            if wall:
                self.bumps += 1
            else:
                self.last_bumped = bumped
            return Outcome.BUMPED
        self.last_duration = move.duration
        self.units += move.units
        x, y = start.x + move.dx, start.y + move.dy
        self._inside = self.maze.in_bounds(x, y)
        self.pose = make_pose(x, y, move.heading)
        self.last_move = move
        return Outcome.MOVED

    def _apply_events(self) -> None:
        """Apply the world events due by now to the occupancy (``blocked`` and the buffer)."""
        assert self.world is not None
        events, now = self.world.events, self.units
        grid, data = self.grid, self._data
        assert isinstance(data, bytearray)
        while self._next_event < len(events) and events[self._next_event].at * self.unit <= now:
            event = events[self._next_event]
            self._next_event += 1
            x, y = event.cell
            if not self.maze.is_free(x, y):
                continue  # the maze's walls never change
            if event.blocked:
                self.blocked[event.cell] = None
            else:
                self.blocked.pop(event.cell, None)
            data[grid.index(x, y)] = 0 if event.blocked else 1

    def _bumped(self, start: Pose, move: Move) -> tuple[Cell, ...]:
        """The cells of ``move``'s footprint from ``start`` blocked now, but the start cell."""
        grid, data = self.grid, self._data
        base = (start.y + grid.margin) * grid.stride + start.x + grid.margin
        if all(data[base + offset] for offset in move.cells[1:]):
            return ()
        shape = self.table.shapes[self.domain.actions[move.action_index]][start.heading]
        swept = [(start.x + dx, start.y + dy) for dx, dy in shape[1:]]
        return tuple(cell for cell in swept if cell in self.blocked)

    def sense_cells(self, believed: frozenset[Cell]) -> frozenset[Cell]:
        """What the robot believes blocked after its sensors look, given what it believed
        (``believed``, returned as it is when nothing changed): in ``range`` sensing the true
        state of every cell that an event names within the sensing range; in ``bump`` sensing
        nothing (the robot learns only by bumping)."""
        world = self.world
        if world is None or world.sensing is Sensing.BUMP:
            return believed
        self._apply_events()
        reach, (x0, y0) = world.sensing_range, self.pose.cell
        cells, blocked = self._event_cells, self.blocked
        added, removed = [], []
        for y in range(y0 - reach, y0 + reach + 1):
            for x in range(x0 - reach, x0 + reach + 1):
                if (cell := (x, y)) in cells:
                    if cell in blocked:
                        if cell not in believed:
                            added.append(cell)
                    elif cell in believed:
                        removed.append(cell)
        if not added and not removed:
            return believed
        return (believed - frozenset(removed)) | frozenset(added)

    def _free(self, start: Pose, move: Move, action: object) -> bool:
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
