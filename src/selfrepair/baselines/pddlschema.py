"""The four-wheel robot's PDDL vocabulary (encoding in :mod:`selfrepair.baselines.pddl`): the
constants, the predicates, one action schema per action with its shape, the parameters of a
plan step, and the :class:`PddlTask` an export makes."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import ACTIONS, Action, Mode, Motion, Wheel

__all__ = [
    "DOMAIN_NAME",
    "HEADING_NAMES",
    "MODE_NAMES",
    "PREDICATES",
    "PROBE_POSES",
    "REPRESENTATIVE",
    "VARIABLE_TYPES",
    "WHEEL_NAMES",
    "Atom",
    "PddlTask",
    "Schema",
    "Shape",
    "cell_name",
    "parameter_bindings",
    "schema",
    "static_predicates",
    "step_parameters",
]

DOMAIN_NAME = "four-wheel"

HEADING_NAMES: dict[Heading, str] = {
    Heading.N: "north",
    Heading.E: "east",
    Heading.S: "south",
    Heading.W: "west",
}
"""The PDDL constant of each heading."""

WHEEL_NAMES: dict[Wheel, str] = {w: w.name.lower() for w in Wheel}
"""The PDDL constant of each wheel: ``fl fr rl rr``."""

MODE_NAMES: dict[Mode, str] = {m: m.letter.lower() for m in (Mode.F, Mode.S, Mode.B)}
"""The PDDL constant of each wheel command: ``f s b``."""

Atom = tuple[str, ...]
"""A PDDL atom as its predicate and arguments, e.g. ``("robot-at", "c3_4")``; in a schema the
arguments may be variables such as ``"?c"``."""


class Shape(Enum):
    """How a motion changes the state, which decides its schema's parameters (module docstring)."""

    WAIT = "wait"
    TURN = "turn"
    MOVE = "move"
    ARC = "arc"


PROBE_POSES = tuple(Pose(0, 0, heading) for heading in Heading)
REPRESENTATIVE: dict[Motion, Action] = {}
"""One action of each motion (the first in ``ACTIONS`` order): what shapes and facts are
computed with."""
for _action in ACTIONS:
    REPRESENTATIVE.setdefault(four_wheel.motion(_action), _action)


def _shape_of(motion: Motion) -> Shape:
    """The shape of ``motion``, from where the world model says it ends and what it sweeps."""
    action = REPRESENTATIVE[motion]
    stays = all(
        four_wheel.step(p, action)[0].cell == p.cell
        and four_wheel.swept_cells(p, action) == (p.cell,)
        for p in PROBE_POSES
    )
    turns = any(four_wheel.step(p, action)[0].heading != p.heading for p in PROBE_POSES)
    if stays:
        return Shape.TURN if turns else Shape.WAIT
    return Shape.ARC if turns else Shape.MOVE


_SHAPES: dict[Motion, Shape] = {m: _shape_of(m) for m in four_wheel.MOTIONS}

_PARAMETERS: dict[Shape, tuple[tuple[str, str], ...]] = {
    Shape.WAIT: (),
    Shape.TURN: (("?h", "heading"), ("?g", "heading")),
    Shape.MOVE: (("?c", "cell"), ("?h", "heading"), ("?d", "cell")),
    Shape.ARC: (("?c", "cell"), ("?h", "heading"), ("?d", "cell"), ("?g", "heading")),
}

_STATIC: dict[Shape, tuple[tuple[str, tuple[str, ...]], ...]] = {
    Shape.WAIT: (),
    Shape.TURN: (("", ("?h", "?g")),),
    Shape.MOVE: (("", ("?c", "?h", "?d")),),
    Shape.ARC: (("", ("?c", "?h", "?d")), ("-heading", ("?h", "?g"))),
}
"""Each shape's static predicates as (suffix to the motion name, variables). An arc's fact is split
in two, its cells and its heading change, because LPG-td 1.4 crashes in plan-adaptation mode on any
fact with four arguments; the heading change does not depend on the cell (the world model acts the
same in every cell), so the conjunction says exactly what one four-argument fact would."""

VARIABLE_TYPES = {"?c": "cell", "?d": "cell", "?h": "heading", "?g": "heading"}


def static_predicates(motion: Motion) -> tuple[tuple[str, tuple[str, ...]], ...]:
    return tuple((motion.name + suffix, args) for suffix, args in _STATIC[_SHAPES[motion]])


PREDICATES: tuple[tuple[str, tuple[tuple[str, str], ...]], ...] = (
    ("robot-at", (("?c", "cell"),)),
    ("facing", (("?h", "heading"),)),
    ("healthy", (("?w", "wheel"), ("?m", "mode"))),
    *(
        (name, tuple((v, VARIABLE_TYPES[v]) for v in args))
        for m in four_wheel.MOTIONS
        for name, args in static_predicates(m)
    ),
)
"""Every predicate of the domain with its typed parameters: the state, the wheel health, and the
static predicates of the motions (one per motion, two per arc)."""


def cell_name(cell: Cell) -> str:
    """The PDDL object of a cell, e.g. ``c3_4`` for ``(3, 4)``."""
    return f"c{cell[0]}_{cell[1]}"


def _cost_units(action: Action) -> int:
    units = four_wheel.duration(action) * four_wheel.TICKS_DENOMINATOR
    if units.denominator != 1:  # pragma: no cover - guaranteed by the world model
        raise ProblemError(f"the duration of {action} is not a whole number of thirds of a tick")
    return int(units)


# --- schemas ------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Schema:
    """One of the 81 actions as a PDDL action schema (see the module docstring).

    ``cost`` is the action's duration in thirds of a tick; ``name`` its code in lower case.
    """

    action: Action
    motion: str
    shape: Shape
    parameters: tuple[tuple[str, str], ...]
    precondition: tuple[Atom, ...]
    add: tuple[Atom, ...]
    delete: tuple[Atom, ...]
    cost: int

    @property
    def name(self) -> str:
        """The schema's PDDL name, e.g. ``ffff``."""
        return self.action.code.lower()


def _build_schema(action: Action) -> Schema:
    motion = four_wheel.motion(action)
    shape = _SHAPES[motion]
    parameters = _PARAMETERS[shape]
    health = tuple(
        ("healthy", WHEEL_NAMES[w], MODE_NAMES[m])
        for w, m in zip(Wheel, action.wheels, strict=True)
    )
    state: tuple[Atom, ...] = ()
    add: tuple[Atom, ...] = ()
    delete: tuple[Atom, ...] = ()
    if shape in (Shape.MOVE, Shape.ARC):
        state = (("robot-at", "?c"), ("facing", "?h"))
        add, delete = (("robot-at", "?d"),), (("robot-at", "?c"),)
    elif shape is Shape.TURN:
        state = (("facing", "?h"),)
    if shape in (Shape.TURN, Shape.ARC):
        add, delete = (*add, ("facing", "?g")), (*delete, ("facing", "?h"))
    static = tuple((name, *args) for name, args in static_predicates(motion))
    return Schema(
        action=action,
        motion=motion.name,
        shape=shape,
        parameters=parameters,
        precondition=health + state + static,
        add=add,
        delete=delete,
        cost=_cost_units(action),
    )


_SCHEMAS: dict[Action, Schema] = {a: _build_schema(a) for a in ACTIONS}


def schema(action: Action) -> Schema:
    """The PDDL schema of ``action``."""
    return _SCHEMAS[action]


def parameter_bindings(pose: Pose, end: Pose) -> dict[str, str]:
    """The schema variables of a step from ``pose`` to ``end``, as PDDL object names."""
    return {
        "?c": cell_name(pose.cell),
        "?h": HEADING_NAMES[pose.heading],
        "?d": cell_name(end.cell),
        "?g": HEADING_NAMES[end.heading],
    }


def step_parameters(shape: Shape, pose: Pose, end: Pose) -> tuple[str, ...]:
    """The parameters of a step of ``shape`` from ``pose`` to ``end``: PDDL object names."""
    bindings = parameter_bindings(pose, end)
    return tuple(bindings[v] for v, _ in _PARAMETERS[shape])


@dataclass(frozen=True, slots=True)
class PddlTask:
    """A planning problem in PDDL terms, ready to be written as text or handed to a planner.

    ``schemas`` are the actions of the domain (all 81 unless the export was asked for fewer),
    ``cells`` the cell objects (the maze's free cells), ``init`` the true atoms of the initial
    state (pose, wheel health, then the static geometry facts) and ``goal`` the goal atoms. With
    ``action_costs`` the domain has ``:action-costs`` and the problem minimises ``total-cost``.
    ``static_facts`` counts the geometry facts, ``ground_actions`` the action instances they allow
    (what a grounder instantiates at most: each schema over its motion's facts, a wait once).
    """

    name: str
    comment: str
    schemas: tuple[Schema, ...]
    cells: tuple[str, ...]
    init: tuple[Atom, ...]
    goal: tuple[Atom, ...]
    action_costs: bool
    static_facts: int
    ground_actions: int
