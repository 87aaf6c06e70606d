"""Fault schedules: which faults occur, when, for how long, and how the robot learns of them.

A :class:`FaultSchedule` is a list of :class:`FaultEvent` plus a detection mode. Each
event names one fault of the robot's domain (for the four-wheel robot a wheel and a mode such as
``FL:F``), when it starts (``at``, counted in executed steps or in ticks
per ``clock``) and how it persists:

``permanent``
    Active from ``at`` on.
``transient``
    Active for ``duration`` units of its clock from ``at`` on, then gone.
``intermittent``
    From ``at`` on, active at each step with probability ``probability``. The draw for event ``i``
    at step ``k`` comes from ``numpy.random.default_rng([seed, i, k])`` with the mission's seed,
    so whether a fault is active is a pure function of (schedule, seed, step, tick): the simulator
    and :func:`selfrepair.execution.trace.replay` compute the same true faults without sharing a
    generator's state.

Steps count every executed command, failed attempts included; ticks are the exact elapsed time at
the start of the step. Detection:

``now``
    The robot senses the active faults before every step (and senses a transient fault clearing).
``on-use``
    The robot learns of a fault only when it commands an action the fault forbids: the attempt
    fails without moving, costs one tick, and reveals the faults that blocked it (as a wheel sensor
    would). Faults once learned this way are never forgotten.
``hidden``
    The robot is never told its faults. A forbidden command does what the domain's
    fault-behaviour model says (:meth:`Domain.effective
    <selfrepair.robots.domain.Domain.effective>`): the robot moves differently, and a motion
    that sweeps a wall stops at the contact (a bump; see
    :mod:`selfrepair.execution.simulator`). A domain without such a model fails the command
    without moving, and the robot is told only that it failed, not why. What the robot learns is
    what it observes (its pose after each command; see :mod:`selfrepair.diagnosis`).

The default, :meth:`FaultSchedule.permanent` with ``at=0`` and detection ``now``, is the original
experiment's setting: every fault present from the first step and known at once.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction
from typing import Any, TypeVar

import numpy as np

from selfrepair.errors import InputError, choice
from selfrepair.robots.domain import A, Domain, F, SomeDomain
from selfrepair.textio import JSONObject, JSONValue

__all__ = [
    "Clock",
    "Detection",
    "FaultClock",
    "FaultEvent",
    "FaultSchedule",
    "Persistence",
    "lasting_problem",
]


class Persistence(StrEnum):
    """How long a fault lasts once it starts."""

    PERMANENT = "permanent"
    TRANSIENT = "transient"
    INTERMITTENT = "intermittent"


class Clock(StrEnum):
    """What a fault event's ``at`` and ``duration`` count: executed steps or elapsed ticks."""

    STEP = "step"
    TICK = "tick"


class Detection(StrEnum):
    """How the robot learns of its faults (see the module docstring)."""

    NOW = "now"
    ON_USE = "on-use"
    HIDDEN = "hidden"


_SOURCE = "<fault schedule>"
"""The source named by the errors of a fault schedule made in code."""

_H = TypeVar("_H", bound=Hashable)


def lasting_problem(
    persistence: Persistence, duration: int | None, probability: float | None
) -> str | None:
    """What is wrong with how a fault lasts, or ``None``: a transient fault needs a ``duration``
    >= 1 and an intermittent one a ``probability`` in [0, 1]. The rule of a robot's
    :class:`FaultEvent` and of a team's :class:`~selfrepair.team.model.TeamFault` alike (each
    raises its own error with this message)."""
    if persistence is Persistence.TRANSIENT and (duration is None or duration < 1):
        return f"a transient fault needs a duration >= 1, got {duration}"
    if persistence is Persistence.INTERMITTENT and (
        probability is None or not 0.0 <= probability <= 1.0
    ):
        return f"an intermittent fault needs a probability in [0, 1], got {probability}"
    return None


@dataclass(frozen=True, slots=True)
class FaultEvent:
    """One fault and when it is active (see the module docstring)."""

    fault: object
    at: int = 0
    clock: Clock = Clock.STEP
    persistence: Persistence = Persistence.PERMANENT
    duration: int | None = None
    probability: float | None = None

    def __post_init__(self) -> None:
        where = _SOURCE
        persistence = choice(Persistence, self.persistence, "persistence", source=where)
        object.__setattr__(self, "persistence", persistence)
        object.__setattr__(self, "clock", choice(Clock, self.clock, "clock", source=where))
        if self.at < 0:
            raise InputError(f"expected a start 'at' >= 0, got {self.at}", source=where)
        problem = lasting_problem(self.persistence, self.duration, self.probability)
        if problem is not None:
            raise InputError(problem, source=where)

    def active(self, index: int, step: int, tick: Fraction, seed: int) -> bool:
        """Whether this event (number ``index`` in its schedule) is active at ``step``/``tick``."""
        now = step if self.clock is Clock.STEP else tick
        if now < self.at:
            return False
        if self.persistence is Persistence.PERMANENT:
            return True
        if self.persistence is Persistence.TRANSIENT:
            assert self.duration is not None
            return now < self.at + self.duration
        assert self.probability is not None
        draw = float(np.random.default_rng([seed, index, step]).random())
        return draw < self.probability

    def to_json(self, domain: SomeDomain) -> JSONObject:
        """A JSON-able dict (the fault in ``domain``'s text); keys with default values are still
        written, for readable traces."""
        return {
            "fault": domain.format_faults([self.fault]),
            "at": self.at,
            "clock": self.clock.value,
            "persistence": self.persistence.value,
            "duration": self.duration,
            "probability": self.probability,
        }

    @classmethod
    def from_json(
        cls, data: Mapping[str, Any], domain: SomeDomain, source: str = _SOURCE
    ) -> FaultEvent:
        """Read what :meth:`to_json` wrote."""
        try:
            return cls(
                fault=_one_fault(domain, str(data["fault"]), source),
                at=int(data.get("at", 0)),
                clock=choice(Clock, data.get("clock", "step"), "clock", source=source),
                persistence=choice(
                    Persistence, data.get("persistence", "permanent"), "persistence", source=source
                ),
                duration=None if data.get("duration") is None else int(data["duration"]),
                probability=None if data.get("probability") is None else float(data["probability"]),
            )
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise
            raise InputError(
                f"expected a fault event with a 'fault' key, got {dict(data)!r}", source=source
            ) from None


@dataclass(frozen=True, slots=True)
class FaultSchedule:
    """Every fault event of a mission and how faults are detected."""

    events: tuple[FaultEvent, ...] = ()
    detection: Detection = Detection.NOW

    def __post_init__(self) -> None:
        detection = choice(Detection, self.detection, "detection", source=_SOURCE)
        object.__setattr__(self, "detection", detection)

    @classmethod
    def permanent(
        cls,
        faults: Iterable[object],
        *,
        at: int = 0,
        clock: Clock = Clock.STEP,
        detection: Detection = Detection.NOW,
    ) -> FaultSchedule:
        """Every fault in ``faults`` permanent from ``at`` on (sorted: the value is canonical)."""
        events = tuple(FaultEvent(f, at=at, clock=clock) for f in canonical_order(faults))
        return cls(events, detection)

    def active_faults(self, step: int, tick: Fraction, seed: int = 0) -> frozenset[object]:
        """The true faults at the start of step ``step`` (elapsed time ``tick``); ``seed`` drives
        intermittent faults."""
        return frozenset(
            e.fault for i, e in enumerate(self.events) if e.active(i, step, tick, seed)
        )

    def all_faults(self) -> frozenset[object]:
        """Every fault that may ever be active."""
        return frozenset(e.fault for e in self.events)

    def describe(self) -> str:
        """A short human summary such as ``"FL:F,RL:F permanent from step 0, detected now"``."""
        if not self.events:
            return "no faults"
        parts = []
        for e in self.events:
            extra = ""
            if e.persistence is Persistence.TRANSIENT:
                extra = f" for {e.duration} {e.clock}s"
            elif e.persistence is Persistence.INTERMITTENT:
                extra = f" p={e.probability}"
            parts.append(f"{e.fault} {e.persistence}{extra} from {e.clock} {e.at}")
        return "; ".join(parts) + f"; detected {self.detection}"

    def to_json(self, domain: SomeDomain) -> JSONObject:
        """A JSON-able dict, faults in ``domain``'s text."""
        events: list[JSONValue] = [e.to_json(domain) for e in self.events]
        return {
            "events": events,
            "detection": self.detection.value,
            "faults": domain.format_faults(self.all_faults()),
        }

    @classmethod
    def from_json(
        cls, data: Mapping[str, Any], domain: SomeDomain, source: str = _SOURCE
    ) -> FaultSchedule:
        """Read what :meth:`to_json` wrote."""
        events = data.get("events", [])
        if not isinstance(events, list):
            raise InputError("expected 'events' to be a list", source=source)
        return cls(
            events=tuple(FaultEvent.from_json(e, domain, source) for e in events),
            detection=str(data.get("detection", "now")),  # type: ignore[arg-type]
        )


class FaultClock:
    """The true faults of one mission over time, for a clock that counts in integer time units
    (``unit`` units per tick, see :mod:`selfrepair.execution.moves`).

    The active set is a step function of (step, tick): :meth:`at` recomputes it with
    :meth:`FaultSchedule.active_faults` (the reference) only when the step or the time reaches the
    next point at which some event can start or end, and otherwise returns the same frozenset
    object. Intermittent events draw anew at every step, so with one of them active the set is
    recomputed at each step. Mutable (it remembers the last set and how long it holds).
    """

    __slots__ = ("_faults", "_schedule", "_seed", "_step_until", "_unit", "_units_until")

    def __init__(self, schedule: FaultSchedule, seed: int, unit: int) -> None:
        self._schedule = schedule
        self._seed = seed
        self._unit = unit
        self._faults: frozenset[object] = frozenset()
        self._step_until = -1  # the cached set holds for steps < _step_until ...
        self._units_until = -1  # ... and times < _units_until (in units)

    def at(self, step: int, units: int) -> frozenset[object]:
        """The faults active at the start of step ``step``, ``units`` time units in."""
        if step < self._step_until and units < self._units_until:
            return self._faults
        unit = self._unit
        faults = self._schedule.active_faults(step, Fraction(units, unit), self._seed)
        if faults != self._faults:
            self._faults = faults
        step_until = units_until = _FOREVER
        for event in self._schedule.events:
            at, end = event.at, None
            if event.persistence is Persistence.TRANSIENT:
                assert event.duration is not None
                end = at + event.duration
            if event.clock is Clock.STEP:
                now, scale = step, 1
            else:
                now, scale = units, unit
            edges = [b * scale for b in (at, end) if b is not None and b * scale > now]
            if event.persistence is Persistence.INTERMITTENT and now >= at * scale:
                step_until = min(step_until, step + 1)  # a new draw at every step
            if edges:
                if event.clock is Clock.STEP:
                    step_until = min(step_until, *edges)
                else:
                    units_until = min(units_until, *edges)
        self._step_until, self._units_until = step_until, units_until
        return self._faults


_FOREVER = 1 << 62
"""A step or time no mission reaches."""


def canonical_order(faults: Iterable[_H]) -> list[_H]:
    """Distinct faults in a canonical order: sorted when the domain's faults are ordered (the
    four-wheel robot's are), else by their text."""
    distinct = set(faults)
    try:
        return sorted(distinct)  # type: ignore[type-var]  # unordered faults: the TypeError below
    except TypeError:
        return sorted(distinct, key=str)


def _one_fault(domain: Domain[A, F], text: str, source: str) -> F:
    try:
        faults = domain.parse_faults(text)
    except InputError as exc:
        raise InputError(exc.reason, source=source) from None
    if len(faults) != 1:
        raise InputError(f"expected exactly one fault, got {text!r}", source=source)
    return next(iter(faults))
