"""Asking a :class:`~selfrepair.execution.stepper.Stepper` one step at a time from outside the
loop: what the environment's guide and the stepper-driven policies
(:mod:`selfrepair.envs.policies`) do, where the agent, not the stepper, chooses each command."""

from __future__ import annotations

from selfrepair.execution.result import RepairRecord, StepSource
from selfrepair.execution.stepper import Entry, Stepper
from selfrepair.geometry import Pose

__all__ = ["ask", "followed"]


def ask(
    stepper: Stepper, pose: Pose, known: frozenset[object], step: int
) -> tuple[Entry | None, RepairRecord | None]:
    """What ``stepper`` commands at ``pose`` knowing exactly ``known`` after ``step`` commands
    (``None`` at the goal or when no repair exists), and the last repair it made to answer
    (``None`` when it made none)."""
    if stepper.context.at_goal(pose):
        return None, None
    stepper.learn(known)
    before = len(stepper.repairs)
    entry = stepper.next_action(pose, step)
    return entry, stepper.repairs[-1] if len(stepper.repairs) > before else None


def followed(entry: Entry | None, command: object) -> StepSource:
    """The source of ``command``: that of the stepper's answer when the agent followed it."""
    if entry is not None and entry[0] == command:
        return entry[1]
    return StepSource.PLAN
