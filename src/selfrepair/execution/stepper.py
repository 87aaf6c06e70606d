"""The one execution loop's body: the queue of planned actions, the strategy that repairs it, the
splice, and the record of what happened.

A :class:`Stepper` serves one robot's mission. It holds the queue of ``(action, StepSource)``,
the :class:`~selfrepair.repair.strategies.Repairer` started for the mission, and the faults the
robot knows. It never knows who drives it or what the world is: a caller asks it for the next
command (:meth:`Stepper.next_action`), sends the command to its world, and tells it what happened
(:meth:`Stepper.record`). Three callers drive it:

- :func:`selfrepair.execution.executor.run_mission` runs it to the end against a
  :class:`~selfrepair.execution.simulator.Simulator`;
- the Gymnasium environment (:mod:`selfrepair.envs.env`) exposes it one step at a time (its
  guide's hints and the planner policies are steppers that follow the agent's commands);
- the team engine (:mod:`selfrepair.team.engine`) drives one stepper per robot drive, each robot
  with its own simulator, interleaved by the reservation table.

Before each command, :meth:`Stepper.next_action`:

1. if the queue is empty (away from the goal: the caller checks the goal), replans (the
   defensive replan, recorded with ``action=None``; with the faults hidden an observing
   repairer is asked instead: it may assume other faults than the stepper checks);
2. if the queue's first action is unavailable under the known faults, asks the strategy for a
   repair and splices it into the queue (:func:`splice`, the one splice of the code base);
3. if the strategy has a ``horizon`` (lookahead with a window before the faulty action), asks it
   as soon as one of the next ``horizon`` actions after the first is known to be faulty (at most
   once per step, so it cannot loop);
4. answers the queue's first entry, or ``None`` when a repair failed (:attr:`Stepper.failure`
   says how; the stepper then answers ``None`` until the robot moves off the plan).

Waiting is a repair too. When a repair ends ``stuck`` (no plan exists under the known faults) and
the robot has waits left (:attr:`Stepper.max_wait`, ``StrategyOptions.max_wait`` unless the
caller says otherwise; the executor gives 0 under detection ``on-use``, whose known faults never
clear), the stepper splices the robot's wait action (the first of
:attr:`Domain.waits <selfrepair.robots.domain.Domain.waits>` available under the known faults),
marked ``wait``, in front of the queue and answers it; the wait moves nothing and is consumed like
any queued action, and the next question asks the strategy again, with the faults sensed then
(which may have cleared). A wait that fails (a fault the robot did not know forbids it) is dropped
from the queue. A robot without an available wait action, or out of waits, gives
up as before; :attr:`Stepper.waits` counts the waits answered.

Each repair is timed with ``time.perf_counter_ns`` from the request to the spliced queue (the
repair latency) and recorded as a :class:`~selfrepair.execution.result.RepairRecord`.

After the command, :meth:`Stepper.record` is told its outcome: a move of the queue's first action
consumes it; a move of another action (an agent that does not follow the plan) empties the queue,
so the next question replans from where the robot is; a failed attempt reveals the faults that
blocked it (detection on use); each command is recorded as a
:class:`~selfrepair.execution.result.TraceStep`. What the robot senses between
commands (detection ``now``) comes in through :meth:`Stepper.learn`.

A changing world (:mod:`selfrepair.world.events`): the cells the robot believes blocked come in
through :meth:`Stepper.see` (its range sensors) and from bumps (a command that bumped into a cell
reveals it). When the queue's first action would sweep a cell believed blocked (other than the
robot's own), the stepper asks for a repair as for a faulty action: a strategy that has a method
``repair_blocked(request)`` is asked through it and must answer with actions that avoid the
believed-blocked cells (the replacement strategy's local detours), one that declares
``sees_cells`` (true) is asked through its ``repair`` (D* Lite, whose kept search takes the
cells as updates); any other is answered by a plain replan around them (the mission's planner
plans around ``MissionContext.belief``).

Faults hidden (detection ``hidden``, docs/diagnosis.md): after each command the caller gives the
stepper what the robot observed (:meth:`Stepper.perceive`). A repairer that observes (one with
``observe`` and ``assumption``, see :class:`~selfrepair.repair.strategies.Repairer`) gets it and
says whether the queue no longer starts where the robot is (its command went elsewhere); the
stepper then asks it for a repair before the next command (``rejoin``), even with an empty queue
or an available front. Teammates' readings of the same command
(:mod:`selfrepair.diagnosis.cooperative`) come with it, to a repairer that declares
``hears_teammates`` (a fourth argument of ``observe``). The stepper records every observation,
and after each command the bit set of the hypotheses a repairer with a ``belief`` still holds
possible (for the trace). After each observation and each repair the stepper takes the repairer's
:class:`~selfrepair.repair.strategies.Assumption`: the faults the queue is checked against, and
actions that are unusable whatever the faults. Any other repairer is not told anything.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Container, Iterable, Iterator, Sequence
from fractions import Fraction
from itertools import islice, repeat
from operator import itemgetter
from typing import overload

from selfrepair.diagnosis.observation import Observation
from selfrepair.errors import ProblemError
from selfrepair.execution.moves import MoveTable, available_moves
from selfrepair.execution.result import STEP_OF_REPAIR, RepairRecord, StepSource, TraceStep
from selfrepair.execution.simulator import Outcome, StepOutcome
from selfrepair.geometry import Cell, Pose
from selfrepair.repair.queue import splice
from selfrepair.repair.strategies import (
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    RepairStatus,
    replan,
)

__all__ = ["MAX_REPAIRS_PER_STEP", "ActionView", "Entry", "Stepper", "splice"]

MAX_REPAIRS_PER_STEP = 64
"""Repairs one question may ask for before the strategy is taken to break its contract (every
action of a repair is available under the known faults, so a correct strategy needs one, a
deferring recursion mode a few)."""

Entry = tuple[object, StepSource]
"""One queued action and where it came from."""

_ACTION = itemgetter(0)

_new_tuple = tuple.__new__
"""Builds the :class:`TraceStep` of each step without the ``NamedTuple`` constructor's Python
frame (the same value)."""


class ActionView(Sequence[object]):
    """A read-only view of the queue's actions, so a repair request costs O(1) to build."""

    __slots__ = ("_queue",)

    def __init__(self, queue: deque[Entry]) -> None:
        self._queue = queue

    def __len__(self) -> int:
        return len(self._queue)

    def __iter__(self) -> Iterator[object]:
        return map(_ACTION, self._queue)

    @overload
    def __getitem__(self, index: int) -> object: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[object, ...]: ...

    def __getitem__(self, index: int | slice) -> object:
        if isinstance(index, slice):
            start, stop, stride = index.indices(len(self._queue))
            if stride == 1:  # in C: a deque is slow to index in the middle
                return tuple(islice(map(_ACTION, self._queue), start, max(start, stop)))


            return tuple(self._queue[i][0] for i in range(start, stop, stride))
        return self._queue[index][0]


class Stepper:
    """The queue, strategy and record of one robot's mission (see the module docstring).
    Mutable: one per mission (or per team drive).

    ``actions`` is the initial plan (marked ``source``), ``known`` the faults known at the start,
    ``table`` the robot's move table (availability is looked up in it per fault set).
    ``stopped`` starts the stepper given up (an initial plan that failed): it answers ``None``
    until the robot moves off the plan. ``max_wait`` bounds the waits while no plan exists
    (``None``: ``context.options.max_wait``; see the module docstring).
    """

    __slots__ = (
        "_assume",
        "_available",
        "_belief",
        "_blocked_repair",
        "_early_at",
        "_hears",
        "_observe",
        "_perceived",
        "_table",
        "_unusable",
        "beliefs",
        "blocked",
        "context",
        "failure",
        "horizon",
        "known",
        "max_wait",
        "observations",
        "queue",
        "rejoin",
        "repairer",
        "repairs",
        "steps",
        "stopped",
        "waits",
    )

    def __init__(
        self,
        context: MissionContext,
        repairer: Repairer,
        actions: Iterable[object],
        known: frozenset[object],
        table: MoveTable,
        *,
        source: StepSource = StepSource.PLAN,
        stopped: bool = False,
        max_wait: int | None = None,
    ) -> None:
        self.context = context
        self.repairer = repairer
        self.queue: deque[Entry] = deque(zip(actions, repeat(source)))
        self.known = known
        self._table = table
        self._available: Container[object] = available_moves(table, known)
        self.horizon = int(getattr(repairer, "horizon", 0))
        self._blocked_repair: Callable[[RepairRequest], Repair] | None = getattr(
            repairer, "repair_blocked", None
        )
        if self._blocked_repair is None and getattr(repairer, "sees_cells", False):
            self._blocked_repair = repairer.repair  # its one repair also sees the cells
        self._observe = getattr(repairer, "observe", None)
        self._assume = getattr(repairer, "assumption", None)
        self._hears = bool(getattr(repairer, "hears_teammates", False))
        self._belief = getattr(repairer, "belief", None)
        self.observations: list[Observation] = []
        """Faults hidden: every observation perceived, per command the robot's own first."""
        self.beliefs: list[int] = []
        """Faults hidden, a repairer with a ``belief``: its bit set of the hypotheses still
        possible after each command's observations."""
        self._unusable: frozenset[object] = frozenset()
        self._perceived = False  # observations came (faults hidden): take the assumption
        self.rejoin = False
        """Whether the observing repairer asked to be asked before the next command."""
        self.blocked: frozenset[Cell] = context.belief.blocked
        """The cells the robot believes blocked by world events (see the module docstring)."""
        self._early_at = -1  # the step of the last early repair: at most one per step
        self.steps: list[TraceStep] = []
        self.repairs: list[RepairRecord] = []
        self.failure: Repair | None = None
        """The repair that failed (then :meth:`next_action` answers ``None``)."""
        self.stopped = stopped
        self.max_wait = context.options.max_wait if max_wait is None else max_wait
        self.waits = 0
        """The wait actions answered so far (see the module docstring)."""

    def learn(self, known: frozenset[object]) -> None:
        """The robot now knows exactly ``known`` (what its sensors report, detection ``now``)."""
        if known is not self.known:
            self.known = known
            self._available = available_moves(self._table, known)

    def perceive(
        self,
        observation: Observation,
        deviated: bool,
        moved: bool,
        seen: Sequence[Observation] = (),
    ) -> None:
        """Faults hidden: give an observing repairer ``observation`` of the last command (a
        :class:`~selfrepair.diagnosis.Observation`), with whether the robot truly ``deviated``
        from the pose its command should have reached and whether it ``moved``, and the
        readings ``seen`` by observing teammates (to a repairer that declares
        ``hears_teammates``); then take its assumption (see the module docstring). Nothing for
        any other repairer. Every observation is recorded (:attr:`observations`), and so is the
        repairer's belief after it (:attr:`beliefs`)."""
        self.observations.append(observation)
        if seen:
            self.observations.extend(seen)
        observe = self._observe
        if observe is None:
            return
        self._perceived = True
        asked = (
            observe(observation, deviated, moved, seen)
            if seen and self._hears
            else observe(observation, deviated, moved)
        )
        if asked:
            self.rejoin = True
        if self._belief is not None:
            self.beliefs.append(self._belief.alive)
        self._sync()

    def _sync(self) -> None:
        """Take the observing repairer's :class:`~selfrepair.repair.strategies.Assumption`."""
        known, unusable = self._assume()  # type: ignore[misc]  # set with _observe
        if known != self.known or unusable != self._unusable:
            self.known, self._unusable = known, unusable
            available = available_moves(self._table, known)
            if unusable:
                available = {a: m for a, m in available.items() if a not in unusable}
            self._available = available

    def see(self, blocked: frozenset[Cell]) -> None:
        """The robot now believes exactly ``blocked`` blocked (its sensors, or a bump)."""
        if blocked is not self.blocked:
            self.blocked = blocked
            self.context.belief.blocked = blocked

    def sweeps_blocked(self, pose: Pose, action: object) -> bool:
        """Whether ``action`` from ``pose`` sweeps a cell believed blocked, other than the cell
        the robot stands on."""
        blocked = self.blocked
        x, y = pose.x, pose.y
        shape = self._table.shapes[action][pose.heading]
        return any((x + dx, y + dy) in blocked for dx, dy in shape[1:])

    def available(self, action: object) -> bool:
        """Whether ``action`` is available under the known faults."""
        return action in self._available

    def next_action(self, pose: Pose, step: int) -> Entry | None:
        """The next command at ``pose`` (``step`` commands so far) and its source, repairing the
        queue first when needed (see the module docstring); ``None`` when a repair failed or the
        stepper is stopped."""
        queue = self.queue
        if queue and queue[0][0] in self._available and not (
            self.horizon or self.stopped or self.blocked or self.rejoin
        ):
            return queue[0]  # the hot path: nothing to repair
        if self.stopped:
            return None
        for _ in range(MAX_REPAIRS_PER_STEP):
            if self.rejoin:  # the observing repairer asked: the queue starts elsewhere
                self.rejoin = False
                repair = self._repair(pose, step, queue[0][0] if queue else None, asked=True)
            elif not queue or queue[0][0] not in self._available:
                repair = self._repair(pose, step, queue[0][0] if queue else None)
            elif self.blocked and self.sweeps_blocked(pose, queue[0][0]):
                repair = self._repair(pose, step, queue[0][0], blocked=True)
            elif (
                self.horizon
                and self._early_at != step
                and (ahead := self._faulty_ahead()) is not None
            ):
                self._early_at = step
                repair = self._repair(pose, step, ahead)  # a known fault ahead: repair it early
            else:
                return queue[0]
            if repair.status is not RepairStatus.REPAIRED:
                if repair.status is RepairStatus.STUCK and (wait := self._wait()) is not None:
                    splice(queue, 0, (wait,), StepSource.WAIT)
                    return queue[0]
                self.failure, self.stopped = repair, True
                return None
        raise ProblemError(
            f"strategy repaired the queue {MAX_REPAIRS_PER_STEP} times at {pose} and its first "
            "action is still unavailable: a repair must start with an available action"
        )

    def _wait(self) -> object | None:
        """The wait action to splice in while no plan exists (counted), or ``None`` when the
        robot has no waits left or no wait action available under the known faults."""
        if self.waits >= self.max_wait:
            return None
        available = self._available
        for action in self.context.domain.waits:
            if action in available:
                self.waits += 1
                wait: object = action
                return wait
        return None

    def _faulty_ahead(self) -> object | None:
        """The first of the ``horizon`` queued actions after the front that is unavailable under
        the known faults (``None`` when all are available)."""
        queue, available = self.queue, self._available
        for i in range(1, min(self.horizon + 1, len(queue))):
            action = queue[i][0]
            if action not in available:
                return action
        return None

    def _repair(
        self,
        pose: Pose,
        step: int,
        action: object | None,
        blocked: bool = False,
        asked: bool = False,
    ) -> Repair:
        """Ask the strategy (or, with an empty queue or for a blocked action the strategy does not
        see, a plain replan) for a repair of ``action`` and splice it into the queue; the
        latency covers both."""
        t0 = time.perf_counter_ns()
        queue = self.queue
        request = RepairRequest(pose, ActionView(queue), self.known, step)
        blocked_repair = self._blocked_repair
        if (action is None and not (asked or self._perceived)) or (
            blocked and blocked_repair is None
        ):
            repair = replan(self.context, request)  # no queue, or a strategy blind to cells
        elif blocked_repair is not None and blocked:
            repair = blocked_repair(request)
        else:
            repair = self.repairer.repair(request)
        if repair.status is RepairStatus.REPAIRED:
            source = STEP_OF_REPAIR[repair.source]
            splice(queue, repair.consumed, repair.actions, source)
        if self._perceived:  # an observing repairer may change what it assumes
            self._sync()
        latency = time.perf_counter_ns() - t0
        self.repairs.append(RepairRecord(step, pose, action, repair, latency))
        return repair

    def relocalise(self) -> None:
        """The robot is not where the last move should have put it (a physics simulator localised
        it elsewhere): drop the queue, so the next question replans from where it is."""
        self.queue.clear()
        self.stopped, self.failure = False, None

    def observe(self, outcome: StepOutcome, source: StepSource = StepSource.PLAN) -> None:
        """:meth:`record` a command that :meth:`Simulator.execute
        <selfrepair.execution.simulator.Simulator.execute>` reported as ``outcome``; ``source``
        is where the command came from (the one :meth:`next_action` gave, when it was followed)."""
        self.record(
            outcome.step,
            outcome.action,
            source,
            outcome.status,
            outcome.start,
            outcome.end,
            outcome.duration,
            outcome.blocking,
        )

    def moved(
        self,
        step: int,
        action: object,
        source: StepSource,
        start: Pose,
        end: Pose,
        duration: Fraction,
    ) -> None:
        """:meth:`record` a command that moved the robot (the mission loop's hot path)."""
        queue = self.queue
        if queue and ((head := queue[0][0]) is action or head == action):
            queue.popleft()
        else:  # off the plan: the next question replans from the new pose
            queue.clear()
            self.stopped, self.failure = False, None
        self.steps.append(
            _new_tuple(TraceStep, (step, action, start, end, duration, source, self.known))
        )

    def record(
        self,
        step: int,
        action: object,
        source: StepSource,
        outcome: Outcome,
        start: Pose,
        end: Pose,
        duration: Fraction,
        blocking: frozenset[object] = frozenset(),
        bumped: tuple[Cell, ...] = (),
    ) -> None:
        """Tell the stepper what command ``action`` (number ``step``, of ``source``) did: a move
        from ``start`` to ``end`` in ``duration``, a failed attempt revealing ``blocking``, or a
        refused command (a collision: nothing changes, nothing is recorded), or a bump into the
        blocked cells ``bumped`` (learned) or, faults hidden, into a wall (recorded; the action
        stays queued). See the module docstring."""
        if outcome is Outcome.MOVED:
            self.moved(step, action, source, start, end, duration)
            return
        known = self.known
        if outcome is Outcome.FAILED_ATTEMPT:
            if source is StepSource.WAIT and self.queue and self.queue[0][1] is source:
                self.queue.popleft()  # a wait an unknown fault forbids: ask again, not repair it
            source = StepSource.FAILED_ATTEMPT
            if not blocking <= known:
                self.known = known | blocking
                self._available = available_moves(self._table, self.known)
        elif outcome is Outcome.BUMPED:
            source = StepSource.BUMPED
            self.see(self.blocked | frozenset(bumped))
        else:
            return
        self.steps.append(
            _new_tuple(TraceStep, (step, action, start, end, duration, source, known))
        )
