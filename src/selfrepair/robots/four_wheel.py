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
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum, IntEnum
from fractions import Fraction

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Heading, Pose, make_pose, relative_cell
from selfrepair.robots.domain import Domain, FaultBehaviour

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

_LETTERS = ("S", "F", "B")
"""A mode's letter by its value (``F`` = 1, ``S`` = 0, ``B`` = -1 counts from the end)."""

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
    return _apply(pose, action), swept_cells(pose, action), _DURATION[action.code]


# --- faults ---------------------------------------------------------------------------------


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
    if not sep or wheel_text not in Wheel.__members__ or mode_text not in _MODE_BY_LETTER:
        raise InputError(
            f"expected a fault WHEEL:MODE with WHEEL in FL, FR, RL, RR and MODE in F, S, B "
            f"(e.g. FL:F), got {text.strip()!r}",
            source=source,
        )
    return Fault(Wheel[wheel_text], _MODE_BY_LETTER[mode_text])


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
        m = _MOTION[action.code]
        current = best.get(m)
        if current is None or _DURATION[action.code] < _DURATION[current.code]:
            best[m] = action
    return best


# --- what a fault really does ---------------------------------------------------------------

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
            (m.letter for m in fallbacks[_MODE_BY_LETTER[letter]] if m.letter not in banned), "S"
        )
    return _ACTION_BY_CODE["".join(letters)]


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


# --- the domain value ---------------------------------------------------------------------------


def _apply(pose: Pose, action: Action) -> Pose:
    dx, dy, heading, _ = _STEPS[action.code][pose.heading]
    return make_pose(pose.x + dx, pose.y + dy, heading)


def _level(action: Action) -> int:
    return 1 if _MOTION[action.code].kind is MotionKind.ARC else 0


def _parse_action(text: str) -> Action:
    return parse_action(text)


def _format_action(action: Action) -> str:
    return action.code


def _parse_faults(text: str) -> FaultSet:
    return parse_faults(text)


def _wheel_modes(action: Action) -> tuple[object, ...]:
    """What a watching teammate sees: each wheel's mode (the wheel view of diagnosis)."""
    return action.wheels


_CLASS_OF = {code: m.name for code, m in _MOTION.items()}
"""Each action code's motion class (its motion's name, made once rather than per call)."""


def _motion_class(action: Action) -> str:
    return _CLASS_OF[action.code]


FOUR_WHEEL: Domain[Action, Fault] = Domain(
    name="four-wheel",
    actions=ACTIONS,
    apply=_apply,
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
