"""The one execution loop's body, :class:`~selfrepair.execution.stepper.Stepper`, on hand-made
cases: the splice, repairs and their records, a failed repair, an off-plan move, a failed
attempt, the early (horizon) repair, and a strategy that breaks its contract."""

from __future__ import annotations

from collections import deque
from fractions import Fraction
from typing import Any

import numpy as np
import pytest

from selfrepair.errors import ProblemError
from selfrepair.execution.context import mission_context
from selfrepair.execution.moves import move_table
from selfrepair.execution.result import MissionSpec, StepSource
from selfrepair.execution.simulator import Outcome
from selfrepair.execution.stepper import Stepper, splice
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import (
    MissionContext,
    Repair,
    RepairRequest,
    RepairSource,
    RepairStatus,
    get_strategy,
)
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.maze import Maze

A = FOUR_WHEEL.parse_action
FORWARD, TURN_LEFT, SLOW = A("FFFF"), A("BFBF"), A("SSFF")
FL_F = FOUR_WHEEL.parse_faults("FL:F")
OPEN = Maze(np.zeros((3, 9), dtype=bool), name="open")
START = Pose(0, 1, Heading.E)


def _context() -> MissionContext:
    spec = MissionSpec(OPEN, START, (8, 1), strategy="replan")
    return mission_context(spec, None)


class _Scripted:
    """A repairer that answers the repairs it was given, in order, and keeps the requests."""

    def __init__(self, *answers: Repair, horizon: int = 0) -> None:
        self.answers = list(answers)
        self.requests: list[RepairRequest] = []
        self.horizon = horizon

    def repair(self, request: RepairRequest) -> Repair:
        self.requests.append(request._replace(queue=tuple(request.queue)))  # a live view
        return self.answers.pop(0)


def _stepper(
    repairer: Any, actions: list[Any], known: frozenset[Any] = frozenset(), max_wait: int = 0
) -> Stepper:
    table = move_table(FOUR_WHEEL, 1)
    return Stepper(_context(), repairer, actions, known, table, max_wait=max_wait)


def test_splice_short_and_whole_queue() -> None:
    queue = deque([(1, StepSource.PLAN), (2, StepSource.PLAN), (3, StepSource.PLAN)])
    splice(queue, 1, (7, 8), StepSource.REPLACEMENT)
    assert list(queue) == [
        (7, StepSource.REPLACEMENT), (8, StepSource.REPLACEMENT),
        (2, StepSource.PLAN), (3, StepSource.PLAN),
    ]  # fmt: skip
    splice(queue, 3, (9,), StepSource.REPLAN)  # most of the queue: rebuilt at once
    assert list(queue) == [(9, StepSource.REPLAN), (3, StepSource.PLAN)]


def test_a_faulty_head_is_repaired_spliced_and_recorded() -> None:
    repairer = _Scripted(
        Repair(RepairStatus.REPAIRED, RepairSource.REPLACEMENT, (SLOW, SLOW), consumed=1)
    )
    stepper = _stepper(repairer, [FORWARD, TURN_LEFT], FL_F)
    assert stepper.next_action(START, 3) == (SLOW, StepSource.REPLACEMENT)
    assert list(repairer.requests[0].queue) == [FORWARD, TURN_LEFT]
    assert repairer.requests[0].known == FL_F and repairer.requests[0].step == 3
    [record] = stepper.repairs
    assert (record.step, record.pose, record.action) == (3, START, FORWARD)
    assert record.latency_ns > 0
    assert [a for a, _ in stepper.queue] == [SLOW, SLOW, TURN_LEFT]
    assert stepper.next_action(START, 3) == (SLOW, StepSource.REPLACEMENT)  # no second repair
    assert len(stepper.repairs) == 1


def test_a_failed_repair_stops_the_stepper_until_the_robot_leaves_the_plan() -> None:
    stuck = Repair(RepairStatus.STUCK, RepairSource.REPLAN, attempts=("replan",))
    stepper = _stepper(_Scripted(stuck), [FORWARD], FL_F)
    assert stepper.next_action(START, 0) is None
    assert stepper.failure is stuck and stepper.stopped
    assert stepper.next_action(START, 0) is None and len(stepper.repairs) == 1
    end = Pose(0, 1, Heading.N)
    stepper.record(0, TURN_LEFT, StepSource.PLAN, Outcome.MOVED, START, end, Fraction(2))
    assert not stepper.stopped and stepper.failure is None and not stepper.queue
    entry = stepper.next_action(end, 1)  # the empty queue: a plain replan from the new pose
    assert entry is not None and stepper.repairs[-1].action is None
    assert stepper.repairs[-1].repair.source is RepairSource.REPLAN


def test_a_stuck_repair_splices_a_wait_and_asks_again_until_the_bound() -> None:
    stuck = Repair(RepairStatus.STUCK, RepairSource.REPLAN, attempts=("replan",))
    stepper = _stepper(_Scripted(stuck, stuck, stuck), [FORWARD], FL_F, max_wait=2)
    wait = A("SSSS")
    for step in range(2):
        assert stepper.next_action(START, step) == (wait, StepSource.WAIT)
        assert list(stepper.queue) == [(wait, StepSource.WAIT), (FORWARD, StepSource.PLAN)]
        stepper.record(step, wait, StepSource.WAIT, Outcome.MOVED, START, START, Fraction(1))
        assert list(stepper.queue) == [(FORWARD, StepSource.PLAN)]  # the wait is consumed
    assert stepper.waits == 2 and not stepper.stopped
    assert stepper.next_action(START, 2) is None  # the bound ran out: the third stuck ends it
    assert stepper.failure is stuck and len(stepper.repairs) == 3


def test_a_failed_wait_is_dropped_and_no_wait_is_left() -> None:
    stuck = Repair(RepairStatus.STUCK, RepairSource.REPLAN, attempts=("replan",))
    stepper = _stepper(_Scripted(stuck, stuck), [FORWARD], FL_F, max_wait=5)
    wait = A("SSSS")
    assert stepper.next_action(START, 0) == (wait, StepSource.WAIT)
    every_stop = FOUR_WHEEL.parse_faults("FL:S,FR:S,RL:S,RR:S")  # no wheel can stop: no wait
    stepper.record(0, wait, StepSource.WAIT, Outcome.FAILED_ATTEMPT, START, START, Fraction(1),
                   every_stop)  # fmt: skip
    assert list(stepper.queue) == [(FORWARD, StepSource.PLAN)]
    assert stepper.steps[-1].source is StepSource.FAILED_ATTEMPT
    # No wheel can stop and FL cannot go forward: the first wait left is BFFB (FL, RR back).
    assert stepper.next_action(START, 1) == (A("BFFB"), StepSource.WAIT)
    assert stepper.waits == 2 and len(stepper.repairs) == 2


def test_a_move_along_the_plan_consumes_it_and_is_recorded() -> None:
    stepper = _stepper(_Scripted(), [FORWARD, FORWARD])
    end = Pose(1, 1, Heading.E)
    stepper.record(0, FORWARD, StepSource.PLAN, Outcome.MOVED, START, end, Fraction(1))
    assert [a for a, _ in stepper.queue] == [FORWARD]
    [step] = stepper.steps
    assert (step.step, step.action, step.start, step.end, step.source) == (
        0, FORWARD, START, end, StepSource.PLAN
    )  # fmt: skip


def test_a_failed_attempt_reveals_its_faults_and_the_next_question_repairs() -> None:
    repairer = _Scripted(Repair(RepairStatus.REPAIRED, RepairSource.REPLACEMENT, (SLOW,), 1))
    stepper = _stepper(repairer, [FORWARD])
    assert stepper.next_action(START, 0) == (FORWARD, StepSource.PLAN)
    stepper.record(0, FORWARD, StepSource.PLAN, Outcome.FAILED_ATTEMPT, START, START,
                   Fraction(1), FL_F)  # fmt: skip
    assert stepper.known == FL_F
    assert stepper.steps[0].source is StepSource.FAILED_ATTEMPT
    assert stepper.steps[0].known == frozenset()  # what was known when it was sent
    assert stepper.next_action(START, 1) == (SLOW, StepSource.REPLACEMENT)


def test_a_collision_changes_nothing() -> None:
    stepper = _stepper(_Scripted(), [FORWARD])
    stepper.record(0, FORWARD, StepSource.PLAN, Outcome.COLLISION, START, START, Fraction(0))
    assert not stepper.steps and [a for a, _ in stepper.queue] == [FORWARD]


def test_a_horizon_repairs_a_known_fault_ahead_once_per_step() -> None:
    early = Repair(RepairStatus.REPAIRED, RepairSource.LOOKAHEAD, (SLOW, SLOW), consumed=2)
    repairer = _Scripted(early, horizon=2)
    stepper = _stepper(repairer, [TURN_LEFT, FORWARD, TURN_LEFT], FL_F)
    assert stepper.next_action(START, 0) == (SLOW, StepSource.LOOKAHEAD)
    assert stepper.repairs[0].action == FORWARD  # the faulty action ahead, not the head
    assert stepper.next_action(START, 0) == (SLOW, StepSource.LOOKAHEAD)
    assert len(stepper.repairs) == 1


def test_a_repair_that_leaves_a_faulty_head_breaks_the_contract() -> None:
    bad = Repair(RepairStatus.REPAIRED, RepairSource.REPLACEMENT, (FORWARD,), 1)
    stepper = _stepper(_Scripted(*[bad] * 100), [FORWARD], FL_F)
    with pytest.raises(ProblemError, match="still unavailable"):
        stepper.next_action(START, 0)


def test_a_real_strategy_drives_to_the_goal() -> None:
    """The executor's replanner, asked step by step, reaches the goal on the open maze."""
    context = _context()
    stepper = Stepper(context, get_strategy("replan")(context), [], FL_F, move_table(FOUR_WHEEL, 1))
    pose, step = START, 0
    while not context.at_goal(pose):
        entry = stepper.next_action(pose, step)
        assert entry is not None and FOUR_WHEEL.available(entry[0], FL_F)
        end = FOUR_WHEEL.apply(pose, entry[0])
        stepper.record(step, entry[0], entry[1], Outcome.MOVED, pose, end, Fraction(1))
        pose, step = end, step + 1
    assert step == len(stepper.steps) and len(stepper.repairs) == 1


def test_a_waiting_robot_lets_time_pass_forwards_only() -> None:
    """A team robot waits for its turn: its simulator's clock advances without a step."""
    from selfrepair.execution.faults import FaultSchedule
    from selfrepair.execution.simulator import Simulator

    sim = Simulator(FOUR_WHEEL, OPEN, START, FaultSchedule())
    sim.wait_until(6)
    assert (sim.units, sim.steps, sim.ticks) == (6, 0, Fraction(2))  # 3 units per tick
    with pytest.raises(ProblemError, match="forwards"):
        sim.wait_until(3)
