"""The four-wheeled skid-steer robot: the single definition of what an action does.

Planner, simulator, table generator and checkers all call this module; nobody re-derives motion.

Coordinates and headings are those of :mod:`selfrepair.geometry`. An action is one command per
wheel in the order front-left, front-right, rear-left, rear-right; each command is F (+1), S (0)
or B (-1), written as a four-letter code such as ``"SFFF"``. With ``l = FL + RL`` and
``r = FR + RR``:

=================  ==========  ==========================================  ==================
condition          motion      pose change                                 duration (ticks)
=================  ==========  ==========================================  ==================
l = r = 0          WAIT        none                                        1
l = r != 0         STRAIGHT    one cell along sign(l) * heading            2 / abs(l)
same sign, l != r  ARC         one cell along sign(l) * heading and one    2
                               toward the slower side; heading turns 90
                               degrees, counter-clockwise if r > l
otherwise          TURN        heading turns 90 degrees in place,          4 / abs(l - r)
                               counter-clockwise if r > l
=================  ==========  ==========================================  ==================

Durations are exact :class:`fractions.Fraction` values (multiples of 1/3 tick).

The package: :mod:`~selfrepair.robots.four_wheel.motion` (wheels, modes, actions, motions,
durations, swept cells), :mod:`~selfrepair.robots.four_wheel.faults` (wheel faults, what they
forbid and what a faulty wheel really does), and here the robot as one
:class:`~selfrepair.robots.domain.Domain`, :data:`FOUR_WHEEL`.
"""

from __future__ import annotations

from selfrepair.robots.domain import Domain
from selfrepair.robots.four_wheel.faults import (
    BEHAVIOURS,
    DOUBLE_FAULTS,
    SINGLE_FAULTS,
    Fault,
    FaultSet,
    available,
    effective,
    fastest_by_motion,
    format_faults,
    parse_fault,
    parse_faults,
)
from selfrepair.robots.four_wheel.motion import (
    ACTIONS,
    MOTIONS,
    TICKS_DENOMINATOR,
    Action,
    Mode,
    Motion,
    MotionKind,
    Wheel,
    apply,
    duration,
    motion,
    parse_action,
    step,
    swept_cells,
)

__all__ = [
    "ACTIONS",
    "BEHAVIOURS",
    "DOUBLE_FAULTS",
    "FOUR_WHEEL",
    "MOTIONS",
    "SINGLE_FAULTS",
    "TICKS_DENOMINATOR",
    "Action",
    "Fault",
    "FaultSet",
    "Mode",
    "Motion",
    "MotionKind",
    "Wheel",
    "available",
    "duration",
    "effective",
    "fastest_by_motion",
    "format_faults",
    "motion",
    "parse_action",
    "parse_fault",
    "parse_faults",
    "step",
    "swept_cells",
]


def _level(action: Action) -> int:
    return 1 if motion(action).kind is MotionKind.ARC else 0


def _parse_action(text: str) -> Action:
    return parse_action(text)


def _format_action(action: Action) -> str:
    return action.code


def _parse_faults(text: str) -> FaultSet:
    return parse_faults(text)


def _wheel_modes(action: Action) -> tuple[object, ...]:
    """What a watching teammate sees: each wheel's mode (the wheel view of diagnosis)."""
    return action.wheels


_CLASS_OF = {a.code: motion(a).name for a in ACTIONS}
"""Each action code's motion class (its motion's name, made once rather than per call)."""


def _motion_class(action: Action) -> str:
    return _CLASS_OF[action.code]


FOUR_WHEEL: Domain[Action, Fault] = Domain(
    name="four-wheel",
    actions=ACTIONS,
    apply=apply,
    footprint=swept_cells,
    duration=duration,
    available=available,
    parse_action=_parse_action,
    format_action=_format_action,
    faults=SINGLE_FAULTS,
    parse_faults=_parse_faults,
    format_faults=format_faults,
    motion_class=_motion_class,
    level=_level,
    fault_sets=tuple(frozenset({f}) for f in SINGLE_FAULTS) + DOUBLE_FAULTS,
    footprint_connected=True,
    fault_parts=lambda fault: (fault.wheel.name, fault.mode.letter),
    wait_actions=(parse_action("SSSS"),),
    behaviours=BEHAVIOURS,
    actuators=_wheel_modes,
    description="four-wheeled skid-steer robot: 81 actions, 12 wheel faults (e.g. FL:F)",
)
"""The four-wheel skid-steer robot as a :class:`~selfrepair.robots.domain.Domain`. Levels: waits,
straight moves and in-place turns are primitive (0); arcs, which combine a move and a turn, are
complex (1). It waits with the all-stop ``SSSS`` first (the wheel pairs that cancel out, such as
``FFBB``, when a fault forbids stopping a wheel). Its fault-behaviour models are
:data:`BEHAVIOURS` (``stall`` by default)."""
