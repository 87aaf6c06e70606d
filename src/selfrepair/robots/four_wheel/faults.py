"""The four-wheel robot's wheel faults: a wheel that cannot perform one command (``FL:F``), their
text, which actions they forbid, and what a faulty wheel really does (the fault-behaviour models
a hidden fault follows).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass

from selfrepair.errors import InputError
from selfrepair.robots.domain import FaultBehaviour
from selfrepair.robots.four_wheel.motion import (
    ACTIONS,
    Action,
    Mode,
    Motion,
    Wheel,
    duration,
    motion,
    parse_action,
)

__all__ = [
    "BEHAVIOURS",
    "DOUBLE_FAULTS",
    "SINGLE_FAULTS",
    "Fault",
    "FaultSet",
    "available",
    "effective",
    "fastest_by_motion",
    "format_faults",
    "parse_fault",
    "parse_faults",
]


@dataclass(frozen=True, slots=True, order=True)
class Fault:
    """A wheel that cannot perform one command, e.g. ``FL:F``: front-left cannot go forward."""

    wheel: Wheel
    mode: Mode

    def __str__(self) -> str:
        return f"{self.wheel.name}:{self.mode.letter}"


FaultSet = frozenset[Fault]
"""A set of simultaneous faults."""

SINGLE_FAULTS: tuple[Fault, ...] = tuple(
    Fault(w, m) for w in Wheel for m in (Mode.F, Mode.S, Mode.B)
)
"""The 12 single faults, wheel by wheel, F then S then B."""

DOUBLE_FAULTS: tuple[FaultSet, ...] = tuple(
    frozenset(pair) for pair in itertools.combinations(SINGLE_FAULTS, 2)
)
"""The 66 unordered pairs of distinct single faults."""


def parse_fault(text: str, *, source: str = "<faults>") -> Fault:
    """Parse one fault such as ``"FL:F"`` (case-insensitive)."""
    wheel_text, sep, mode_text = text.strip().upper().partition(":")
    if not sep or wheel_text not in Wheel.__members__ or mode_text not in Mode.__members__:
        raise InputError(
            f"expected a fault WHEEL:MODE with WHEEL in FL, FR, RL, RR and MODE in F, S, B "
            f"(e.g. FL:F), got {text.strip()!r}",
            source=source,
        )
    return Fault(Wheel[wheel_text], Mode[mode_text])


def parse_faults(text: str, *, source: str = "<faults>") -> FaultSet:
    """Parse a comma-separated fault set such as ``"FL:F,RR:B"``; an empty string is no fault.

    An empty item (``"FL:F,,RR:B"``, ``","``) is an error, not silently no fault."""
    if not text.strip():
        return frozenset()
    return frozenset(parse_fault(p, source=source) for p in text.split(","))


def format_faults(faults: Iterable[Fault]) -> str:
    """Print a fault set in canonical order (by wheel FL, FR, RL, RR, then by mode value:
    B, S, F), comma-separated (``""`` for none)."""
    return ",".join(str(f) for f in sorted(faults))


_LETTERS = ("S", "F", "B")
"""A mode's letter by its value (``F`` = 1, ``S`` = 0, ``B`` = -1 counts from the end)."""


def available(action: Action, faults: Iterable[Fault]) -> bool:
    """Whether no fault in ``faults`` forbids a command that ``action`` gives."""
    code = action.code
    for fault in faults:  # noqa: SIM110 (a plain loop: no generator frame per call)
        if code[fault.wheel] == _LETTERS[fault.mode]:
            return False
    return True


def fastest_by_motion(faults: Iterable[Fault] = ()) -> dict[Motion, Action]:
    """For each motion still possible under ``faults``, its fastest available action.

    Ties go to the action that comes first in :data:`ACTIONS`, so the choice is deterministic.
    Every other action with that motion is dominated: same effect, no shorter. This is what keeps
    a planner's branching factor at the number of motions rather than 81.
    """
    fault_set = frozenset(faults)
    best: dict[Motion, Action] = {}
    for action in ACTIONS:
        if not available(action, fault_set):
            continue
        m = motion(action)
        current = best.get(m)
        if current is None or duration(action) < duration(current):
            best[m] = action
    return best


# --- what a fault really does -----------------------------------------------------------------

_FALLBACKS: dict[str, dict[Mode, tuple[Mode, ...]]] = {
    "stall": {Mode.F: (Mode.S, Mode.B), Mode.B: (Mode.S, Mode.F), Mode.S: (Mode.F, Mode.B)},
    "runaway-backward": {
        Mode.F: (Mode.S, Mode.B),
        Mode.B: (Mode.S, Mode.F),
        Mode.S: (Mode.B, Mode.F),
    },
    "reverse": {Mode.F: (Mode.B, Mode.S), Mode.B: (Mode.F, Mode.S), Mode.S: (Mode.F, Mode.B)},
}
"""Per model, for each commanded wheel mode, the modes the wheel falls back to when a fault
forbids it, in order: the wheel does the first one no fault of that wheel forbids."""

_DESCRIPTIONS = {
    "stall": (
        "a wheel that cannot go forward or backward stops (a dead driver channel gives no "
        "torque and the wheel's gearbox holds it); a wheel that cannot stop keeps running "
        "forward (a driver stuck on)"
    ),
    "runaway-backward": (
        "as stall, but a wheel that cannot stop keeps running backward"
    ),
    "reverse": (
        "a wheel commanded a direction it cannot go turns the other way (a stuck direction "
        "line); a wheel that cannot stop runs forward"
    ),
}


def effective(action: Action, faults: Iterable[Fault], behaviour: str = "stall") -> Action:
    """The action the wheels really perform when ``action`` is commanded under ``faults`` in the
    fault-behaviour model ``behaviour`` (see :data:`BEHAVIOURS`): each wheel whose commanded mode
    a fault of that wheel forbids does the first mode of the model's fallback order that no
    fault of that wheel forbids (a wheel all of whose modes are forbidden stops). ``action``
    itself when it is available."""
    fallbacks = _FALLBACKS[behaviour]
    forbidden: dict[int, set[str]] = {}
    for fault in faults:
        forbidden.setdefault(fault.wheel, set()).add(fault.mode.letter)
    letters = list(action.code)
    for wheel, letter in enumerate(letters):
        banned = forbidden.get(wheel)
        if banned is None or letter not in banned:
            continue
        letters[wheel] = next(
            (m.letter for m in fallbacks[Mode[letter]] if m.letter not in banned), "S"
        )
    return parse_action("".join(letters))


def _model(name: str) -> FaultBehaviour[Action, Fault]:
    def model(action: Action, faults: frozenset[Fault]) -> Action:
        return effective(action, faults, name)

    model.__doc__ = f"The {name!r} fault behaviour: {_DESCRIPTIONS[name]}."
    return FaultBehaviour(name, _DESCRIPTIONS[name], model)


BEHAVIOURS: tuple[FaultBehaviour[Action, Fault], ...] = tuple(_model(n) for n in _FALLBACKS)
"""The four-wheel robot's fault-behaviour models, the default first.

``stall`` (the default) is what a skid-steer drive most plausibly does. Each wheel has its own
motor, driver channel and (usually worm or high-ratio, hence not back-drivable) gearbox. A
wheel that "cannot go forward" has lost that half of its driver (a failed H-bridge leg, a
broken encoder channel that the controller trips on, a burnt winding): it gives no torque that
way and its gearbox holds it, so kinematically it is a stopped wheel, and the other wheel of
its side drags the robot around it (a skid-steer robot already skids: its side's drive is the
sum of its two wheels). A wheel that "cannot stop" has a driver stuck on (a welded relay, a
runaway controller); it keeps running in the direction the drive runs when enabled, forward.
So ``FFFF`` under ``FL:F`` performs ``SFFF`` (an arc to the left, not a straight move), and
``SSSS`` under ``FL:S`` performs ``FSSS`` (a turn to the right, not a wait). When the fallback
is forbidden too (two faults on one wheel), the wheel does the mode it still can.

``runaway-backward`` is ``stall`` with a stuck-on driver running backward; ``reverse`` models a
stuck direction line: a wheel commanded a direction it cannot go turns the other way."""
