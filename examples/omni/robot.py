"""An omnidirectional robot on four mecanum wheels: a robot that selfrepair does not ship.

This one file is all selfrepair needs to plan, execute, repair, generate replacement tables for,
and run experiments with a new robot (see docs/extending.md). Load it with
``selfrepair --plugin examples/omni/robot.py ...`` on the command line, ``plugins = ["robot.py"]``
in an experiment file, or ``load_plugin("examples/omni/robot.py")`` in Python.

The robot. Four mecanum wheels (front-left, front-right, rear-left, rear-right) each spin forward
(F), stop (S) or backward (B). Ten commands move it, in its own frame (heading = "forward"):

==================  =======================  =====================================  ========
action              wheels FL FR RL RR        motion                                 duration
==================  =======================  =====================================  ========
``fwd``             F  F  F  F               one cell forward                       1
``back``            B  B  B  B               one cell backward                      1
``right``           F  B  B  F               one cell to the right (strafe)         1
``left``            B  F  F  B               one cell to the left (strafe)          1
``fwd-right``       F  S  S  F               diagonal, forward and right            3/2
``fwd-left``        S  F  F  S               diagonal, forward and left             3/2
``back-right``      S  B  B  S               diagonal, backward and right           3/2
``back-left``       B  S  S  B               diagonal, backward and left            3/2
``turn-right``      F  B  F  B               quarter turn clockwise in place        1
``turn-left``       B  F  B  F               quarter turn anticlockwise in place    1
==================  =======================  =====================================  ========

A diagonal move sweeps its start cell, the two cells beside the diagonal and the end cell (it
cannot cut a corner), so every footprint holds a 4-connected path from start to end and the exact
grid-distance heuristic stays admissible (``footprint_connected=True``). Faults are wheel faults
as for the four-wheel robot, but with two modes: ``FL:F`` (front-left cannot spin forward) or
``FL:B``; a fault disables every action that needs that wheel command. 8 single faults, 28 pairs.
"""

from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Pose, relative_cell
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import register_domain

WHEELS = ("FL", "FR", "RL", "RR")

# name: (wheel commands FL FR RL RR, cells forward, cells right, quarter turns clockwise, duration)
_TABLE: dict[str, tuple[str, int, int, int, Fraction]] = {
    "fwd": ("FFFF", 1, 0, 0, Fraction(1)),
    "back": ("BBBB", -1, 0, 0, Fraction(1)),
    "right": ("FBBF", 0, 1, 0, Fraction(1)),
    "left": ("BFFB", 0, -1, 0, Fraction(1)),
    "fwd-right": ("FSSF", 1, 1, 0, Fraction(3, 2)),
    "fwd-left": ("SFFS", 1, -1, 0, Fraction(3, 2)),
    "back-right": ("SBBS", -1, 1, 0, Fraction(3, 2)),
    "back-left": ("BSSB", -1, -1, 0, Fraction(3, 2)),
    "turn-right": ("FBFB", 0, 0, 1, Fraction(1)),
    "turn-left": ("BFBF", 0, 0, -1, Fraction(1)),
}
ACTIONS: tuple[str, ...] = tuple(_TABLE)
FAULTS: tuple[str, ...] = tuple(f"{w}:{m}" for w in WHEELS for m in "FB")


def apply(pose: Pose, action: str) -> Pose:
    """Where ``action`` takes the robot from ``pose`` (on an open plane)."""
    _, forward, right, turn, _ = _TABLE[action]
    x, y = relative_cell(pose, forward, right)
    return Pose(x, y, pose.heading.rotated(turn))


def footprint(pose: Pose, action: str) -> tuple[Cell, ...]:
    """The cells ``action`` needs free from ``pose``, the start cell first."""
    _, forward, right, _, _ = _TABLE[action]
    cells = [pose.cell]
    if forward and right:  # a diagonal passes both cells beside it
        cells += [relative_cell(pose, forward, 0), relative_cell(pose, 0, right)]
    if forward or right:
        cells.append(relative_cell(pose, forward, right))
    return tuple(cells)


def duration(action: str) -> Fraction:
    """How many ticks ``action`` takes."""
    return _TABLE[action][4]


def available(action: str, faults: frozenset[str]) -> bool:
    """Whether no fault forbids a wheel command that ``action`` gives."""
    wheels = _TABLE[action][0]
    return all(f"{w}:{c}" not in faults for w, c in zip(WHEELS, wheels, strict=True))


def parse_action(text: str) -> str:
    """An action name such as ``fwd-left`` (case-insensitive)."""
    name = text.strip().lower()
    if name not in _TABLE:
        raise InputError(f"expected an omni action ({', '.join(ACTIONS)}), got {text!r}")
    return name


def parse_faults(text: str) -> frozenset[str]:
    """A comma-separated fault set such as ``FL:F,RR:B`` (``""``: no fault)."""
    if not text.strip():
        return frozenset()
    out = set()
    for item in text.split(","):
        fault = item.strip().upper()
        if fault not in FAULTS:
            raise InputError(f"expected an omni fault WHEEL:F or WHEEL:B, got {item.strip()!r}")
        out.add(fault)
    return frozenset(out)


def format_faults(faults: Iterable[str]) -> str:
    """A fault set in canonical order (wheel, then F before B)."""
    return ",".join(sorted(faults, key=FAULTS.index))


def motion_class(action: str) -> str:
    """Every action has its own effect here, so its class is its name."""
    return action


def level(action: str) -> int:
    """Diagonals combine two straight moves: complex (1); the rest primitive (0)."""
    forward, right = _TABLE[action][1:3]
    return 1 if forward and right else 0


OMNI: Domain[str, str] = register_domain(
    Domain(
        name="omni",
        actions=ACTIONS,
        apply=apply,
        footprint=footprint,
        duration=duration,
        available=available,
        parse_action=parse_action,
        format_action=str,
        faults=FAULTS,
        parse_faults=parse_faults,
        format_faults=format_faults,
        motion_class=motion_class,
        level=level,
        footprint_connected=True,
        description="omnidirectional robot on four mecanum wheels: 10 actions, 8 wheel faults",
    )
)
"""The omnidirectional robot, registered as ``omni`` when this file is loaded."""
