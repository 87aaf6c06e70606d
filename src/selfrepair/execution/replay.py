"""Replaying a mission trace: re-simulate its steps with the robot's domain and the fault
schedule its header records, and name the first step that does not hold."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from selfrepair.execution.faults import Detection
from selfrepair.execution.result import MissionSpec, StepSource, TraceStep
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS
from selfrepair.execution.traceformat import Trace
from selfrepair.execution.traceobserve import check_observations
from selfrepair.execution.traceread import read_trace, spec_from_header
from selfrepair.geometry import Pose

__all__ = ["ReplayReport", "replay"]


@dataclass(frozen=True, slots=True)
class ReplayReport:
    """The outcome of a replay. ``ok`` when every step holds; otherwise ``first_bad_step`` (the
    step number, or ``None`` for a problem with the summary), its ``line`` and the ``reason``.
    ``partial`` when the trace had no summary to check."""

    ok: bool
    steps_checked: int
    first_bad_step: int | None = None
    line: int | None = None
    reason: str = ""
    partial: bool = False

    def __str__(self) -> str:
        if self.ok:
            tail = " (partial trace: no summary to check)" if self.partial else ""
            return f"ok: all {self.steps_checked} steps replay{tail}"
        where = "summary" if self.first_bad_step is None else f"step {self.first_bad_step}"
        return f"{where} (line {self.line}) does not hold: {self.reason}"


def replay(trace: Trace | str | Path) -> ReplayReport:
    """Re-simulate every step of ``trace`` and report the first one that does not hold.

    Every step must start where the previous one ended and use an action available under the
    faults it recorded as known; with detection ``now`` those must be the faults the sensors
    report at that step (the true ones). A moving step must also be allowed by the true faults
    of the schedule at that step, sweep only free cells, and end at the pose and after the
    duration that the domain's ``step`` gives, and sweep no cell (but its start cell) that the
    world events (``MissionSpec.world``) block at the tick it starts. A failed attempt must use
    an action the true faults forbid, stay put and last one tick; a bump must stay put, last one
    tick and touch a cell blocked then (with detection ``hidden``, a bump may also come from a
    wall: :mod:`selfrepair.execution.simulator` explains it, and every step is checked against the
    action the wheels performed, ``Domain.effective`` under the true faults and the trace's
    behaviour model). The summary, when present, must
    agree on the number of steps, the final pose, the ticks and whether the goal was reached.
    A hidden-fault trace that records the robot's observations and belief (version 2) has them
    checked too (:func:`~selfrepair.execution.traceobserve.check_observations`: every reading
    possible, and the belief re-derived from the readings equal to the recorded one).
    """
    if not isinstance(trace, Trace):
        trace = read_trace(trace)
    spec = spec_from_header(trace.header, trace.source)
    pose = spec.start
    ticks = Fraction(0)
    for index, (step, line) in enumerate(zip(trace.steps, trace.step_lines, strict=True)):
        problem = _check_step(spec, index, step, pose, ticks)
        if problem is not None:
            return ReplayReport(False, index, step.step, line, problem)
        pose = step.end
        ticks += step.duration
    observed = check_observations(spec, trace)
    if observed is not None:
        index, problem = observed
        return ReplayReport(False, index, trace.steps[index].step, trace.step_lines[index], problem)
    return _check_summary(trace, spec, pose, ticks)


def _check_step(
    spec: MissionSpec, index: int, step: TraceStep, pose: Pose, ticks: Fraction
) -> str | None:
    domain = spec.domain
    name = domain.format_action(step.action)
    if step.step != index:
        return f"expected step number {index}, got {step.step}"
    if step.start != pose:
        return f"starts at {step.start}, but the robot is at {pose}"
    true = spec.schedule.active_faults(index, ticks, spec.seed)
    if spec.schedule.detection is Detection.NOW and step.known != true:
        return (
            f"records the known faults {domain.format_faults(step.known) or 'none'}, but with "
            f"detection 'now' the robot senses {domain.format_faults(true) or 'none'}"
        )
    if not domain.available(step.action, step.known):
        return f"{name} uses a known-faulty command ({domain.format_faults(step.known)})"
    if step.source is StepSource.FAILED_ATTEMPT:
        if domain.available(step.action, true):
            return f"a failed attempt of {name}, but no true fault forbids it"
        if step.end != step.start or step.duration != FAILED_ATTEMPT_TICKS:
            return "a failed attempt must stay put and last one tick"
        return None
    blocked = spec.world.blocked_at(ticks) if spec.world else frozenset()
    performed = step.action
    hidden = spec.schedule.detection is Detection.HIDDEN and bool(domain.behaviours)
    if hidden:
        performed = domain.effective(step.action, true, spec.behaviour)  # what the wheels did
    if step.source is StepSource.BUMPED:
        if step.end != step.start or step.duration != FAILED_ATTEMPT_TICKS:
            return "a bump must stay put and last one tick"
        cells = domain.footprint(pose, performed)
        touched = blocked.intersection(cells[1:])
        if not touched and spec.schedule.detection is not Detection.HIDDEN:
            return f"a bump of {name} at {pose}, but it sweeps no cell blocked at tick {ticks}"
        if not touched and hidden and spec.maze.all_free(cells):
            did = domain.format_action(performed)
            return f"a bump of {name} (performing {did}), but its motion sweeps no wall"
        return None
    if not hidden and not domain.available(step.action, true):
        return f"{name} is forbidden by the true faults {domain.format_faults(true)}"
    end, swept, duration = domain.step(pose, performed)
    if not spec.maze.all_free(swept):
        return f"{name} at {pose} sweeps a wall or leaves the grid"
    if hit := sorted(blocked.intersection(swept[1:])):
        return f"{name} at {pose} sweeps {hit}, blocked at tick {ticks} by world events"
    if end != step.end:
        return f"{name} from {pose} ends at {end}, trace says {step.end}"
    if duration != step.duration:
        return f"{name} lasts {duration} ticks, trace says {step.duration}"
    return None


def _check_summary(trace: Trace, spec: MissionSpec, pose: Pose, ticks: Fraction) -> ReplayReport:
    count = len(trace.steps)
    summary = trace.summary
    if summary is None:
        return ReplayReport(True, count, partial=True)
    line = trace.summary_line
    checks = (
        (summary.get("steps") == count, f"summary says {summary.get('steps')} steps, the trace "
         f"has {count}"),
        (summary.get("final_pose") == str(pose), f"summary says final pose "
         f"{summary.get('final_pose')}, replay ends at {pose}"),
        ((summary.get("status") == "reached") == spec.at_goal(pose), f"summary status "
         f"{summary.get('status')!r} but the replay "
         f"{'ends' if spec.at_goal(pose) else 'does not end'} at the goal"),
        (summary.get("ticks") == str(ticks), f"summary says {summary.get('ticks')} ticks, "
         f"replay takes {ticks}"),
    )  # fmt: skip
    for holds, reason in checks:
        if not holds:
            return ReplayReport(False, count, None, line, reason)
    return ReplayReport(True, count)
