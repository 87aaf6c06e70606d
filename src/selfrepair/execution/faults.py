"""Fault schedules: which wheel faults occur, when, for how long, and how the robot learns of them.

A :class:`FaultSchedule` is a list of :class:`FaultEvent` plus a detection mode. Each
event names one fault (wheel, mode), when it starts (``at``, counted in executed steps or in ticks
per ``clock``) and how it persists:

``permanent``
    Active from ``at`` on.
``transient``
    Active for ``duration`` units of its clock from ``at`` on, then gone.
``intermittent``
    From ``at`` on, active at each step with probability ``probability``. The draw for event ``i``
    at step ``k`` comes from ``numpy.random.default_rng([seed, i, k])`` with the mission's seed,
    so whether a fault is active is a pure function of (schedule, seed, step, tick): the simulator
    and :func:`selfrepair.execution.trace.replay` compute the same true faults without sharing a generator's
    state.

Steps count every executed command, failed attempts included; ticks are the exact elapsed time at
the start of the step. Detection:

``now``
    The robot senses the active faults before every step (and senses a transient fault clearing).
``on-use``
    The robot learns of a fault only when it commands an action the fault forbids: the attempt
    fails without moving, costs one tick, and reveals the faults that blocked it (as a wheel sensor
    would). Faults once learned this way are never forgotten.

The default, :meth:`FaultSchedule.permanent` with ``at=0`` and detection ``now``, is the original
experiment's setting: every fault present from the first step and known at once.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np

from selfrepair.errors import InputError
from selfrepair.robots.four_wheel import Fault, FaultSet, format_faults, parse_fault

__all__ = [
    "CLOCKS",
    "DETECTIONS",
    "PERSISTENCES",
    "FaultEvent",
    "FaultSchedule",
]

PERSISTENCES = ("permanent", "transient", "intermittent")
CLOCKS = ("step", "tick")
DETECTIONS = ("now", "on-use")


@dataclass(frozen=True, slots=True)
class FaultEvent:
    """One fault and when it is active (see the module docstring)."""

    fault: Fault
    at: int = 0
    clock: str = "step"
    persistence: str = "permanent"
    duration: int | None = None
    probability: float | None = None

    def __post_init__(self) -> None:
        where = "<fault schedule>"
        if self.persistence not in PERSISTENCES:
            raise InputError(
                f"expected persistence in {', '.join(PERSISTENCES)}, got {self.persistence!r}",
                source=where,
            )
        if self.clock not in CLOCKS:
            raise InputError(
                f"expected clock in {', '.join(CLOCKS)}, got {self.clock!r}", source=where
            )
        if self.at < 0:
            raise InputError(f"expected a start 'at' >= 0, got {self.at}", source=where)
        if self.persistence == "transient" and (self.duration is None or self.duration < 1):
            raise InputError(
                f"expected a transient fault duration >= 1, got {self.duration}", source=where
            )
        if self.persistence == "intermittent" and (
            self.probability is None or not 0.0 <= self.probability <= 1.0
        ):
            raise InputError(
                f"expected an intermittent fault probability in [0, 1], got {self.probability}",
                source=where,
            )

    def active(self, index: int, step: int, tick: Fraction, seed: int) -> bool:
        """Whether this event (number ``index`` in its schedule) is active at ``step``/``tick``."""
        now = step if self.clock == "step" else tick
        if now < self.at:
            return False
        if self.persistence == "permanent":
            return True
        if self.persistence == "transient":
            assert self.duration is not None
            return now < self.at + self.duration
        assert self.probability is not None
        draw = float(np.random.default_rng([seed, index, step]).random())
        return draw < self.probability

    def to_json(self) -> dict[str, Any]:
        """A JSON-able dict; keys with default values are still written, for readable traces."""
        return {
            "fault": str(self.fault),
            "at": self.at,
            "clock": self.clock,
            "persistence": self.persistence,
            "duration": self.duration,
            "probability": self.probability,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], source: str = "<fault schedule>") -> FaultEvent:
        """Read what :meth:`to_json` wrote."""
        try:
            return cls(
                fault=parse_fault(str(data["fault"]), source=source),
                at=int(data.get("at", 0)),
                clock=str(data.get("clock", "step")),
                persistence=str(data.get("persistence", "permanent")),
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
    detection: str = "now"

    def __post_init__(self) -> None:
        if self.detection not in DETECTIONS:
            raise InputError(
                f"expected detection in {', '.join(DETECTIONS)}, got {self.detection!r}",
                source="<fault schedule>",
            )

    @classmethod
    def permanent(
        cls, faults: Iterable[Fault], *, at: int = 0, clock: str = "step", detection: str = "now"
    ) -> FaultSchedule:
        """Every fault in ``faults`` permanent from ``at`` on (sorted: the value is canonical)."""
        events = tuple(FaultEvent(f, at=at, clock=clock) for f in sorted(set(faults)))
        return cls(events, detection)

    def active_faults(self, step: int, tick: Fraction, seed: int = 0) -> FaultSet:
        """The true faults at the start of step ``step`` (elapsed time ``tick``); ``seed`` drives
        intermittent faults."""
        return frozenset(
            e.fault for i, e in enumerate(self.events) if e.active(i, step, tick, seed)
        )

    def all_faults(self) -> FaultSet:
        """Every fault that may ever be active."""
        return frozenset(e.fault for e in self.events)

    def describe(self) -> str:
        """A short human summary such as ``"FL:F,RL:F permanent from step 0, detected now"``."""
        if not self.events:
            return "no faults"
        parts = []
        for e in self.events:
            extra = ""
            if e.persistence == "transient":
                extra = f" for {e.duration} {e.clock}s"
            elif e.persistence == "intermittent":
                extra = f" p={e.probability}"
            parts.append(f"{e.fault} {e.persistence}{extra} from {e.clock} {e.at}")
        return "; ".join(parts) + f"; detected {self.detection}"

    def to_json(self) -> dict[str, Any]:
        """A JSON-able dict."""
        return {
            "events": [e.to_json() for e in self.events],
            "detection": self.detection,
            "faults": format_faults(self.all_faults()),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], source: str = "<fault schedule>") -> FaultSchedule:
        """Read what :meth:`to_json` wrote."""
        events = data.get("events", [])
        if not isinstance(events, list):
            raise InputError("expected 'events' to be a list", source=source)
        return cls(
            events=tuple(FaultEvent.from_json(e, source) for e in events),
            detection=str(data.get("detection", "now")),
        )
