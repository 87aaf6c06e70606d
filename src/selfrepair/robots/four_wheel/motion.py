"""The four-wheel robot's actions and what each does: wheels, wheel modes, the 81 actions, their
nine motions (the motion table of :mod:`selfrepair.robots.four_wheel`), durations and swept cells.

The one definition of what an action does; nobody re-derives motion.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from enum import Enum, IntEnum
from fractions import Fraction

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Heading, Pose, make_pose, relative_cell

__all__ = [
    "ACTIONS",
    "MOTIONS",
    "TICKS_DENOMINATOR",
    "Action",
    "Mode",
    "Motion",
    "MotionKind",
    "Wheel",
    "apply",
    "duration",
    "motion",
    "parse_action",
    "step",
    "swept_cells",
]

TICKS_DENOMINATOR = 3
"""Every duration is a whole multiple of ``1 / TICKS_DENOMINATOR`` ticks."""


class Wheel(IntEnum):
    """The four wheels, in the order their commands are written."""

    FL = 0
    FR = 1
    RL = 2
    RR = 3


class Mode(IntEnum):
    """One wheel's command: forward, stop or backward."""

    F = 1
    S = 0
    B = -1

    @property
    def letter(self) -> str:
        """The command's letter in an action code."""
        return self.name


_MODE_BY_LETTER = {"F": Mode.F, "S": Mode.S, "B": Mode.B}


class MotionKind(Enum):
    """The four classes of motion that the 81 actions fall into."""

    WAIT = "wait"
    STRAIGHT = "straight"
    ARC = "arc"
    TURN = "turn"


@dataclass(frozen=True, slots=True)
class Motion:
    """The geometric effect of an action, in the robot's own frame.

    ``forward`` counts cells along the heading, ``lateral`` cells to the right (negative: left),
    ``rotation`` quarter turns clockwise (negative: anticlockwise). ``swept`` lists every cell the
    motion passes through as ``(forward, lateral)`` offsets, the start cell first; all of them must
    be free and inside the grid for the motion to be executable.
    """

    kind: MotionKind
    forward: int
    lateral: int
    rotation: int
    swept: tuple[Cell, ...]

    @property
    def name(self) -> str:
        """A readable label such as ``"arc-forward-left"`` or ``"turn-right"``."""
        if self.kind is MotionKind.WAIT:
            return "wait"
        if self.kind is MotionKind.TURN:
            return "turn-left" if self.rotation < 0 else "turn-right"
        direction = "forward" if self.forward > 0 else "backward"
        if self.kind is MotionKind.STRAIGHT:
            return direction
        side = "left" if self.lateral < 0 else "right"
        return f"arc-{direction}-{side}"


def _sign(value: int) -> int:
    return (value > 0) - (value < 0)


def _derive_motion(left: int, right: int) -> tuple[Motion, Fraction]:
    """The motion table of the module docstring, applied to one pair of side drives."""
    rotation = -1 if right > left else 1
    if left == right == 0:
        return Motion(MotionKind.WAIT, 0, 0, 0, ((0, 0),)), Fraction(1)
    if left == right:
        d = _sign(left)
        return Motion(MotionKind.STRAIGHT, d, 0, 0, ((0, 0), (d, 0))), Fraction(2, abs(left))
    if left * right > 0:
        d = _sign(left)
        lateral = -1 if abs(left) < abs(right) else 1
        swept = ((0, 0), (d, 0), (0, lateral), (d, lateral))
        return Motion(MotionKind.ARC, d, lateral, rotation, swept), Fraction(2)
    return Motion(MotionKind.TURN, 0, 0, rotation, ((0, 0),)), Fraction(4, abs(left - right))


@dataclass(frozen=True, slots=True, order=True)
class Action:
    """One command per wheel, written as a four-letter code such as ``"FBFB"``.

    Build one with :func:`parse_action`, or take it from :data:`ACTIONS`.
    """

    code: str

    def __post_init__(self) -> None:
        if len(self.code) != 4 or any(c not in _MODE_BY_LETTER for c in self.code):
            raise InputError(
                f"expected an action of four wheel commands from F, S, B, got {self.code!r}",
                source="<action>",
            )

    def __str__(self) -> str:
        return self.code

    @property
    def wheels(self) -> tuple[Mode, Mode, Mode, Mode]:
        """The command of each wheel, in :class:`Wheel` order."""
        a, b, c, d = (_MODE_BY_LETTER[ch] for ch in self.code)
        return (a, b, c, d)

    @property
    def left(self) -> int:
        """The left side's drive ``FL + RL``, from -2 to 2."""
        return _MODE_BY_LETTER[self.code[0]] + _MODE_BY_LETTER[self.code[2]]

    @property
    def right(self) -> int:
        """The right side's drive ``FR + RR``, from -2 to 2."""
        return _MODE_BY_LETTER[self.code[1]] + _MODE_BY_LETTER[self.code[3]]

    @property
    def motion(self) -> Motion:
        """Shorthand for :func:`motion`."""
        return _MOTION[self.code]

    @property
    def duration(self) -> Fraction:
        """Shorthand for :func:`duration`."""
        return _DURATION[self.code]


ACTIONS: tuple[Action, ...] = tuple(
    Action("".join(letters)) for letters in itertools.product("FSB", repeat=4)
)
"""All 81 actions, ``FFFF`` first, in lexicographic order of F < S < B per wheel."""

_MOTION: dict[str, Motion] = {}
_DURATION: dict[str, Fraction] = {}
for _action in ACTIONS:
    _MOTION[_action.code], _DURATION[_action.code] = _derive_motion(_action.left, _action.right)

_Step = tuple[int, int, Heading, tuple[Cell, ...]]


def _steps(motion: Motion) -> tuple[_Step, _Step, _Step, _Step]:
    """Per heading, ``motion`` from that heading in world offsets: the end cell's ``(dx, dy)``,
    the end heading and the swept cells, start cell first (what :func:`step` returns from the
    origin)."""
    out = []
    for heading in Heading:
        origin = Pose(0, 0, heading)
        dx, dy = relative_cell(origin, motion.forward, motion.lateral)
        swept = tuple(relative_cell(origin, f, r) for f, r in motion.swept)
        out.append((dx, dy, Heading((heading + motion.rotation) % 4), swept))
    return out[0], out[1], out[2], out[3]


_STEPS: dict[str, tuple[_Step, _Step, _Step, _Step]] = {
    code: _steps(m) for code, m in _MOTION.items()
}
"""The motion table of the module docstring per action code and heading, in world offsets: the
one definition of what an action does, read by :func:`step`, :func:`swept_cells` and the domain's
``apply`` (a dictionary read and additions per call; made once, at import, as :data:`MOTIONS`)."""

MOTIONS: tuple[Motion, ...] = tuple(dict.fromkeys(_MOTION[a.code] for a in ACTIONS))
"""The nine distinct motions, in order of first appearance in :data:`ACTIONS`."""

_ACTION_BY_CODE = {a.code: a for a in ACTIONS}


def parse_action(text: str, *, source: str = "<action>") -> Action:
    """Parse a four-letter action code (case-insensitive), e.g. ``"sfff"`` -> ``SFFF``."""
    action = _ACTION_BY_CODE.get(text.strip().upper())
    if action is None:
        raise InputError(
            f"expected an action of four wheel commands from F, S, B (e.g. FFFF), got {text!r}",
            source=source,
        )
    return action


def motion(action: Action) -> Motion:
    """The geometric effect of ``action`` in the robot's frame."""
    return _MOTION[action.code]


def duration(action: Action) -> Fraction:
    """How many ticks ``action`` takes, exactly."""
    return _DURATION[action.code]


def swept_cells(pose: Pose, action: Action) -> tuple[Cell, ...]:
    """Every world cell ``action`` passes through when started at ``pose``, start cell first."""
    x, y = pose.x, pose.y
    return tuple([(x + dx, y + dy) for dx, dy in _STEPS[action.code][pose.heading][3]])


def step(pose: Pose, action: Action) -> tuple[Pose, tuple[Cell, ...], Fraction]:
    """Apply ``action`` at ``pose`` on an unbounded open plane.

    Returns the end pose, the swept cells (all must be free for the step to be executable in a
    maze) and the duration. Whether the cells are free is the caller's question: the model itself
    knows no walls.
    """
    return apply(pose, action), swept_cells(pose, action), _DURATION[action.code]


def apply(pose: Pose, action: Action) -> Pose:
    """The pose ``action`` ends in when started at ``pose`` (on an open plane)."""
    dx, dy, heading, _ = _STEPS[action.code][pose.heading]
    return make_pose(pose.x + dx, pose.y + dy, heading)
