"""A small plug-in robot for the tests: a robot whose ``hop`` leaves the 3x3 cells around it.

Five actions in the robot's frame: ``step`` (one cell forward), ``hop`` (two cells forward, as
fast as a step), ``back`` (one cell backward, two ticks) and the quarter turns ``left`` and
``right``. Each action has one fault that forbids it, named by the action in capitals (``HOP``:
the robot cannot hop). The hop sweeps the cell it jumps over, so every footprint is 4-connected.

The compiled planner takes only robots whose moves stay within the 3x3 cells around the robot,
so this one plans on the pure-Python reference; and selfrepair ships no hand-written table for
it. Load it with ``--plugin tests/data/robots/hopper.py`` or ``load_plugin(...)``.
"""

from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Pose, relative_cell
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import register_domain

# name: (cells forward, quarter turns clockwise, duration)
_MOVES: dict[str, tuple[int, int, Fraction]] = {
    "step": (1, 0, Fraction(1)),
    "hop": (2, 0, Fraction(1)),
    "back": (-1, 0, Fraction(2)),
    "left": (0, -1, Fraction(1)),
    "right": (0, 1, Fraction(1)),
}
ACTIONS: tuple[str, ...] = tuple(_MOVES)
FAULTS: tuple[str, ...] = tuple(a.upper() for a in ACTIONS)


def apply(pose: Pose, action: str) -> Pose:
    """Where ``action`` takes the robot from ``pose``."""
    forward, turn, _ = _MOVES[action]
    x, y = relative_cell(pose, forward, 0)
    return Pose(x, y, pose.heading.rotated(turn))


def footprint(pose: Pose, action: str) -> tuple[Cell, ...]:
    """The start cell, every cell passed, the end cell."""
    forward = _MOVES[action][0]
    step = 1 if forward > 0 else -1
    return (pose.cell, *(relative_cell(pose, d, 0) for d in range(step, forward + step, step)))


def parse_action(text: str) -> str:
    """An action name (case-insensitive)."""
    name = text.strip().lower()
    if name not in _MOVES:
        raise InputError(f"expected a hopper action ({', '.join(ACTIONS)}), got {text!r}")
    return name


def parse_faults(text: str) -> frozenset[str]:
    """A comma-separated fault set such as ``HOP,LEFT`` (``""``: no fault)."""
    out = set()
    for item in filter(None, (part.strip().upper() for part in text.split(","))):
        if item not in FAULTS:
            raise InputError(f"expected a hopper fault ({', '.join(FAULTS)}), got {item!r}")
        out.add(item)
    return frozenset(out)


def format_faults(faults: Iterable[str]) -> str:
    """A fault set in the order of :data:`FAULTS`."""
    return ",".join(sorted(faults, key=FAULTS.index))


HOPPER: Domain[str, str] = register_domain(
    Domain(
        name="hopper",
        actions=ACTIONS,
        apply=apply,
        footprint=footprint,
        duration=lambda action: _MOVES[action][2],
        available=lambda action, faults: action.upper() not in faults,
        parse_action=parse_action,
        format_action=str,
        faults=FAULTS,
        parse_faults=parse_faults,
        format_faults=format_faults,
        motion_class=str,
        level=lambda action: 0,
        footprint_connected=True,
        description="test robot that hops two cells: 5 actions, 5 faults",
    )
)
