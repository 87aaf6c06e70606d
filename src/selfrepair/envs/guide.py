"""A planner with a repair strategy that drives a robot one step at a time: the executor's loop,
turned inside out so that someone else (an agent, a Gymnasium environment) sends the commands.

:func:`selfrepair.execution.executor.run_mission` runs a whole mission in one call. A
:class:`Navigator` keeps the same state between calls instead: the queue of planned actions and a
strategy started for the mission (:mod:`selfrepair.repair.strategies`). Asked for the next action
(:meth:`Navigator.next_action`) with the robot's pose and the faults it knows, it does what the
executor does before each command:

1. if the queue is empty away from the goal, replan (the executor's defensive replan);
2. if the next queued action is unavailable under the known faults, ask the strategy for a repair
   and splice it into the queue (for ``replacement``: the table's first valid candidate, else a
   replan);
3. answer the queue's first action, or ``None`` when no repair exists.

After the command is executed, :meth:`Navigator.record` is told what happened: a move along the plan
consumes the queued action; a move off the plan (another action) empties the
queue, so the next question replans from where the robot is; a failed attempt or a refused command
changes nothing (the faults it revealed make the next question repair).

So a navigator whose commands are all executed behaves exactly like the executor on the same
mission; the environment's baseline policies and the ``info`` hints are navigators.
"""

from __future__ import annotations

from collections import deque
from typing import Any

from selfrepair.execution.simulator import Outcome
from selfrepair.geometry import Pose
from selfrepair.repair.strategies import (
    MissionContext,
    Repair,
    RepairRequest,
    RepairStatus,
    get_strategy,
    replan,
)
from selfrepair.search.astar import PlanStatus

__all__ = ["Navigator"]

_MAX_REPAIRS_PER_STEP = 4
"""Repairs tried for one question before giving up (a correct strategy needs one)."""


class Navigator:
    """The planned actions of one mission and the strategy that repairs them (see the module
    docstring). Mutable: one per mission."""

    def __init__(
        self, context: MissionContext, strategy: str, start: Pose, known: frozenset[Any]
    ) -> None:
        self.context = context
        self.repairer = get_strategy(strategy)(context)
        initial = context.plan(
            start, context.goal, context.goal_heading, known, context.replan_budget
        )
        self.initial_status = initial.status
        self.queue: deque[Any] = deque(initial.actions)
        self.stuck = initial.status is not PlanStatus.SOLVED
        self.last_repair: Repair | None = None
        self.last_faulty: Any | None = None
        self.repairs = 0

    def next_action(self, pose: Pose, known: frozenset[Any], step: int = 0) -> Any | None:
        """The action to command at ``pose`` knowing ``known``, repairing the queue first when its
        next action is faulty (then :attr:`last_repair` and :attr:`last_faulty` say how, else they
        are ``None``); ``None`` at the goal or when no repair exists."""
        self.last_repair = self.last_faulty = None
        context = self.context
        if self.stuck or context.at_goal(pose):
            return None
        available = context.domain.available
        for _ in range(_MAX_REPAIRS_PER_STEP):
            queue = self.queue
            if queue and available(queue[0], known):
                return queue[0]
            request = RepairRequest(pose, tuple(queue), known, step)
            if queue:
                self.last_faulty = queue[0]
                repair = self.repairer.repair(request)
            else:
                repair = replan(context, request)
            self.last_repair = repair
            self.repairs += 1
            if repair.status is not RepairStatus.REPAIRED:
                self.stuck = True
                return None
            for _ in range(repair.consumed):
                queue.popleft()
            queue.extendleft(reversed(repair.actions))
        self.stuck = True
        return None

    def record(self, action: Any, outcome: Outcome) -> None:
        """Tell the navigator what the command ``action`` did (see the module docstring). The
        queue always plans from the robot's pose: only a move changes the pose, and a move of the
        queue's first action ends where the plan says (the simulator moves by the same domain)."""
        if outcome is not Outcome.MOVED:
            return
        queue = self.queue
        if queue and queue[0] == action:
            queue.popleft()
        else:
            queue.clear()
            self.stuck = False  # off the plan: the next question replans from the new pose
