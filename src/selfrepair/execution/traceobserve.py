"""What a hidden-fault trace records of the diagnosis (trace version 2), and its replay check.

With the faults hidden (detection ``hidden``, docs/diagnosis.md) the robot learns of them only
from what it observes, so its trace records, per step, the readings it got and what it believed
after them (the fields are in :mod:`selfrepair.execution.traceformat`):

- the header's ``hidden`` gains ``hypotheses`` (the fault-set text of each hypothesis of the
  robot's :class:`~selfrepair.diagnosis.FaultModel`, ``none`` first) and ``classes`` (each class
  as the list of its hypotheses' indices), written once;
- each step line gains the robot's own reading and bump switch, its teammates' readings, whether
  the step surprised it and, for a strategy that keeps a belief, the bit set of the hypotheses
  still possible (hexadecimal text: 20 digits for the four-wheel robot's 79 hypotheses) and the
  most probable class (an index). The size per step is bounded by the readings, never by the
  hypotheses' names.

Everything is taken after the mission from what it kept (:attr:`MissionResult.observations
<selfrepair.execution.result.MissionResult.observations>` and ``beliefs``): the bit sets are the
live belief's, the most probable class is recomputed from a fresh belief fed the same readings
(the mission loop computes no posterior it does not need).

:func:`check_observations` is what ``replay`` adds for such a trace: every reading must be one
the observation model can give of the step's true end (the end itself with exact odometry; the
end or one of its seven wrong readings with noise), the bump switch must match the step, a
teammate's reading must be one its sensing range allowed (it follows the robot: observer ``i``
stands where the robot was ``i`` steps before) and, with the wheel view, name an action (exact:
the action the true faults made of the command, ``Domain.effective``), the surprise flag must be
what the reading says, and a fresh belief fed the recorded readings must give the recorded bit
set and most probable class after every step.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

from selfrepair.diagnosis import FaultBelief, FaultModel, Observation, fault_model, perturbed
from selfrepair.diagnosis.cooperative import Observer, following
from selfrepair.errors import InputError, TraceError
from selfrepair.execution.faults import Detection
from selfrepair.execution.moves import move_table
from selfrepair.execution.result import MissionResult, MissionSpec, StepSource, TraceStep
from selfrepair.execution.traceformat import Trace, TraceFields, TraceObservation, pose_json
from selfrepair.geometry import FreeGrid, Pose

__all__ = [
    "check_observations",
    "diagnosis_header",
    "header_classes",
    "observation_fields",
    "parse_observation",
    "spec_model",
    "surprising",
]


def spec_model(spec: MissionSpec) -> FaultModel:
    """The fault model a diagnosing robot of ``spec`` holds its belief over."""
    options = spec.options
    return fault_model(spec.domain, spec.behaviour, options.max_faults, options.fault_prior)


def _grid(spec: MissionSpec) -> FreeGrid:
    return spec.maze.free_grid(max(2, move_table(spec.domain, 1).reach))


def diagnosis_header(spec: MissionSpec) -> dict[str, Any]:
    """The header's ``hypotheses`` and ``classes`` (faults hidden; empty otherwise)."""
    if spec.schedule.detection is not Detection.HIDDEN:
        return {}
    model = spec_model(spec)
    domain = spec.domain
    return {
        "hypotheses": [domain.format_faults(s) or "none" for s in model.sets],
        "classes": [list(model.members(c)) for c in model.classes],
    }


def surprising(spec: MissionSpec, reading: Observation) -> bool:
    """Whether the robot's own ``reading`` surprises it: it is not where the command should have
    taken it, it bumped or the command failed."""
    expected = spec.domain.apply(reading.start, reading.action)
    return bool(reading.end != expected or reading.bumped or reading.failed)


def observation_fields(result: MissionResult) -> dict[int, dict[str, Any]]:
    """Per step number, the fields its step line gains (see the module docstring; empty for a
    mission whose faults are not hidden or that kept no observation)."""
    spec = result.spec
    if spec.schedule.detection is not Detection.HIDDEN or not result.observations:
        return {}
    by_step = _by_step(result.observations)
    beliefs = result.beliefs
    belief = FaultBelief(spec_model(spec), _grid(spec)) if beliefs else None
    out: dict[int, dict[str, Any]] = {}
    for index, step in enumerate(result.steps):
        readings = by_step.get(step.step, ())
        if not readings:
            continue
        own, seen = readings[0], readings[1:]
        fields: dict[str, Any] = {
            "read": pose_json(own.end),
            "bumped": own.bumped,
            "surprise": surprising(spec, own),
        }
        if seen:
            fields["seen"] = [
                [o.source, pose_json(o.end)]
                if o.wheels is None
                else [o.source, pose_json(o.end), spec.domain.format_action(o.wheels)]
                for o in seen
            ]
        if belief is not None and index < len(beliefs):
            for reading in readings:
                belief.update(reading)
            fields["belief"] = format(beliefs[index], "x")
            fields["best"] = belief.most_probable()[0]
        out[step.step] = fields
    return out


def _by_step(observations: Sequence[Observation]) -> dict[int, tuple[Observation, ...]]:
    out: dict[int, list[Observation]] = {}
    for o in observations:
        out.setdefault(o.step, []).append(o)
    return {k: tuple(v) for k, v in out.items()}


def parse_observation(f: TraceFields) -> TraceObservation | None:
    """The observation fields of a step line, type-checked (``None`` when it has none)."""
    if "read" not in f.data:
        return None
    bumped = f.data.get("bumped")
    if bumped is not None and not isinstance(bumped, bool):
        raise f.fail(f"expected 'bumped' to be true, false or null, got {bumped!r}")
    surprise = f.get("surprise")
    if not isinstance(surprise, bool):
        raise f.fail(f"expected 'surprise' to be true or false, got {surprise!r}")
    seen = []
    for item in f.data.get("seen", []):
        if not (
            isinstance(item, list)
            and len(item) in (2, 3)
            and isinstance(item[0], str)
            and (len(item) == 2 or isinstance(item[2], str))
        ):
            raise f.fail(
                f'expected \'seen\' as [["name", [x, y, "N"]] or ["name", [x, y, "N"], '
                f'"action read"], ...], got {item!r}'
            )
        pose = TraceFields({"p": item[1]}, f.source, f.line).pose("p")
        seen.append((item[0], pose, item[2] if len(item) == 3 else None))
    belief_text = f.text("belief", optional=True)
    belief = None
    if belief_text is not None:
        try:
            belief = int(belief_text, 16)
        except ValueError:
            raise f.fail(f"expected 'belief' as hexadecimal text, got {belief_text!r}") from None
    best = f.integer("best", optional=True, minimum=0)
    return TraceObservation(f.pose("read"), bumped, tuple(seen), belief, best, surprise)


def check_observations(spec: MissionSpec, trace: Trace) -> tuple[int, str] | None:
    """The index of the first step whose recorded observations or belief do not hold, with why
    (see the module docstring); ``None`` when all hold or the trace records none."""
    if spec.schedule.detection is not Detection.HIDDEN or not any(trace.observations):
        return None
    model = spec_model(spec)
    belief = FaultBelief(model, _grid(spec))
    observers = {o.name: (i, o) for i, o in enumerate(spec.observers, start=1)}
    trail = [spec.start]
    ticks = Fraction(0)
    for index, (step, seen) in enumerate(zip(trace.steps, trace.observations, strict=False)):
        if seen is None:
            return index, "records no observation, but the trace records them for other steps"
        true = spec.schedule.active_faults(index, ticks, spec.seed)
        problem = _check_step(spec, step, seen, observers, trail, belief, true)
        if problem is not None:
            return index, problem
        trail.append(step.end)
        ticks += step.duration
    return None


def _check_step(
    spec: MissionSpec,
    step: TraceStep,
    seen: TraceObservation,
    observers: Mapping[str, Any],
    trail: Sequence[Pose],
    belief: FaultBelief,
    true: frozenset[object],
) -> str | None:
    noise = spec.observation.noise
    if not _possible(seen.read, step.end, noise):
        return f"reads {seen.read} after ending at {step.end}, which odometry at {noise:g} cannot"
    bumped = (step.source is StepSource.BUMPED) if spec.observation.bumps else None
    if seen.bumped != bumped:
        return f"records the bump switch {seen.bumped}, the step says {bumped}"
    failed = step.source is StepSource.FAILED_ATTEMPT
    own = Observation(step.step, step.action, step.start, seen.read, seen.bumped, failed, noise)
    if seen.surprise != surprising(spec, own):
        return f"records surprise {seen.surprise}, its reading says {not seen.surprise}"
    readings = [own]
    for name, pose, text in seen.seen:
        if name not in observers:
            return f"a reading by {name!r}, who is not among the header's observers"
        number, observer = observers[name]
        at = following(trail, number)[-1]
        if not observer.watches(at, step.start, step.end):
            return f"a reading by {name!r}, out of its range at {at}"
        if not _possible(pose, step.end, observer.noise):
            return f"{name!r} reads {pose} after the step ended at {step.end}"
        wheels = _wheels(spec, step, observer, text, failed, true)
        if isinstance(wheels, str):
            return f"{name!r} {wheels}"
        readings.append(Observation(step.step, step.action, step.start, pose, None, failed,
                                    observer.noise, name, wheels))  # fmt: skip
    for reading in readings:
        belief.update(reading)
    if seen.belief is not None and seen.belief != belief.alive:
        return (
            f"records {bin(seen.belief).count('1')} hypotheses possible after its readings, "
            f"which leave {bin(belief.alive).count('1')}"
        )
    if seen.best is not None and seen.best != belief.most_probable()[0]:
        best = belief.most_probable()[0]
        return f"records class {seen.best} as most probable, the readings give {best}"
    return None


def _wheels(
    spec: MissionSpec,
    step: TraceStep,
    observer: Observer,
    text: str | None,
    failed: bool,
    true: frozenset[object],
) -> object:
    """The action an observer's recorded actuator reading names (``None``: no reading), or why
    it cannot be (a string): one is recorded exactly when the observer has the wheel view and
    the command did not fail; read exactly it is the action the true faults made of the step's
    command (``Domain.effective``)."""
    want = observer.wheels and not failed
    if text is None:
        return "records no wheel reading, but it has the wheel view" if want else None
    if not want:
        return f"records the wheel reading {text!r} without the wheel view of a moving command"
    try:
        read = spec.domain.parse_action(text)
    except InputError:
        return f"records the wheel reading {text!r}, not an action of the robot"
    performed = spec.domain.effective(step.action, true, spec.behaviour)
    if observer.noise == 0 and read != performed:
        return f"reads the wheels as {text}, exact, where they performed " + (
            spec.domain.format_action(performed)
        )
    return read


def _possible(read: Pose, end: Pose, noise: float) -> bool:
    return read == end or (noise > 0 and read in perturbed(end))


def header_classes(header: Mapping[str, Any], source: str) -> tuple[list[str], list[list[int]]]:
    """The ``hypotheses`` and ``classes`` of a hidden-fault trace's header (empty lists for a
    trace without them), type-checked."""
    hidden = header.get("hidden") or {}
    names = hidden.get("hypotheses", [])
    classes = hidden.get("classes", [])
    if not (isinstance(names, list) and all(isinstance(n, str) for n in names)) or not (
        isinstance(classes, list)
        and all(isinstance(c, list) and all(type(i) is int for i in c) for c in classes)
    ):
        raise TraceError("expected 'hidden.hypotheses' and 'hidden.classes' lists", source=source,
                         line=1)  # fmt: skip
    return names, classes
