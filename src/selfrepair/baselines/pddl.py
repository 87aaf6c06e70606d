"""The four-wheel robot's planning problem as PDDL: a domain file, a problem file, and plans.

Everything geometric comes from the one world model, :mod:`selfrepair.robots.four_wheel`
(:data:`~selfrepair.robots.four_wheel.ACTIONS`, :func:`~selfrepair.robots.four_wheel.step`,
:func:`~selfrepair.robots.four_wheel.motion`, :func:`~selfrepair.robots.four_wheel.duration`): the
exporter only asks it where an action ends, which cells it sweeps and how long it takes, and writes
the answers down as facts.

Encoding (PDDL with ``:strips :typing :action-costs``)
    State: ``(robot-at ?c - cell)`` and ``(facing ?h - heading)``. The cells are the free cells of
    the maze (objects ``cX_Y``); the headings, wheels and wheel commands are domain constants
    (``north east south west``, ``fl fr rl rr``, ``f s b``).

    Faults are facts, not deleted actions: the initial state holds ``(healthy W M)`` for every wheel
    ``W`` and command ``M`` that no known fault forbids, and each of the 81 actions is a schema
    named by its code (``ffff``, ``sfbb``, ...) whose precondition asks ``(healthy W M)`` for each
    of its four wheel commands. A plan made before a fault therefore still parses after it, and a
    validator names its first step that a fault makes inapplicable.

    Geometry is static facts, a predicate per motion (named as
    :attr:`~selfrepair.robots.four_wheel.Motion.name`), computed with ``step`` on every free pose:

    ===============  ===============  ============================================  ===========
    motion shape     parameters       static facts                                  effect
    ===============  ===============  ============================================  ===========
    stays, no turn   none             none (the 9 waits)                            cost only
    stays and turns  ``?h ?g``        ``(turn-left ?h ?g)``                         heading
    moves, no turn   ``?c ?h ?d``     ``(forward ?c ?h ?d)``                        cell
    moves and turns  ``?c ?h ?d ?g``  ``(arc-forward-left ?c ?h ?d)`` and           both
                                      ``(arc-forward-left-heading ?h ?g)``
    ===============  ===============  ============================================  ===========

    A fact with a cell is listed only when every cell the motion sweeps from that pose is free, so
    the footprint is checked where it is computed, once. "Stays" means that from every probe pose
    the motion ends on its start cell and sweeps nothing else, so a turn needs no cell parameter. A
    fact on headings alone is computed on probe poses: the world model acts the same in every cell.
    An arc's fact is split in two (no fact has four arguments) because LPG-td 1.4's plan adaptation
    crashes on four-argument facts.

    Cost: ``(increase (total-cost) N)`` with ``N`` the action's duration in thirds of a tick
    (:data:`~selfrepair.robots.four_wheel.TICKS_DENOMINATOR`), and ``(:metric minimize
    (total-cost))``; a plan's total cost is its duration times three.

Size
    Why this shape: a grounder instantiates each schema over the tuples its static fact allows. With
    a pose per object and a ``(move-ok ?from ?to)`` fact per motion, the 54 in-place turn actions
    and 9 waits would ground to ``63 * 4 * free cells`` instances; here to 54 * 4 and 9. Ground
    instances (``PddlTask.ground_actions``) and problem-file sizes on the bundled mazes, all 81
    schemas (the domain file is 24 kB whatever the maze):

    ============  ======  ==========  ============  ==============  =============  ==========
    maze          cells   free cells  static facts  ground actions  pose encoding  problem.pddl
    ============  ======  ==========  ============  ==============  =============  ==========
    narrow-short  15x15   97          408           2,145           26,364         13 kB
    wide-short    25x25   382         5,348         17,725          113,764        189 kB
    narrow-long   49x49   1,167       4,752         23,865          317,724        152 kB
    wide-long     61x61   2,721       47,496        149,841         835,308        1.7 MB
    ============  ======  ==========  ============  ==============  =============  ==========

    A planner call need not take all 81 schemas: under known faults only the fastest available
    action of each motion can be useful (the lattice planner's own pruning), so
    :func:`export_pddl` takes ``actions=``; ``action_costs=False`` leaves costs out for planners
    that cannot take numeric fluents (see :mod:`selfrepair.baselines.lpg`).
    :data:`MAX_PDDL_CELLS` bounds the maze (width times height) to keep files and grounding in
    reach of a planner; ``max_cells=`` raises it.

Plans
    One step per line, IPC style: ``(ffff c3_4 north c3_3)``, the parameters those of the schema,
    computed by stepping from the start pose, and a closing comment with the total cost.
    :func:`parse_pddl_plan` reads that form and LPG's ``0: (FFFF C3_4 NORTH C3_3) [1]`` back into
    actions, checking each step's parameters against the poses it re-simulates from the start.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

from selfrepair.errors import InputError, ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import ACTIONS, Action, Fault, Mode, Motion, Wheel
from selfrepair.search.problem import PlanningProblem, check_search_inputs

__all__ = [
    "DOMAIN_NAME",
    "HEADING_NAMES",
    "MAX_PDDL_CELLS",
    "MODE_NAMES",
    "PREDICATES",
    "WHEEL_NAMES",
    "Atom",
    "PddlTask",
    "Schema",
    "Shape",
    "cell_name",
    "domain_text",
    "export_pddl",
    "parse_pddl_plan",
    "plan_to_pddl",
    "problem_text",
    "schema",
    "step_parameters",
    "step_pddl",
    "write_pddl",
]

DOMAIN_NAME = "four-wheel"

MAX_PDDL_CELLS = 4096
"""Largest maze (width times height, here 64 x 64) that :func:`export_pddl` accepts by default.
The bundled mazes are at most 61 x 61; a larger maze needs ``max_cells=`` (CLI: ``--max-cells``)."""

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


_PROBES = tuple(Pose(0, 0, heading) for heading in Heading)
_REPRESENTATIVE: dict[Motion, Action] = {}
for _action in ACTIONS:
    _REPRESENTATIVE.setdefault(four_wheel.motion(_action), _action)


def _shape_of(motion: Motion) -> Shape:
    """The shape of ``motion``, from where the world model says it ends and what it sweeps."""
    action = _REPRESENTATIVE[motion]
    stays = all(
        four_wheel.step(p, action)[0].cell == p.cell
        and four_wheel.swept_cells(p, action) == (p.cell,)
        for p in _PROBES
    )
    turns = any(four_wheel.step(p, action)[0].heading != p.heading for p in _PROBES)
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

_VARIABLE_TYPES = {"?c": "cell", "?d": "cell", "?h": "heading", "?g": "heading"}


def _static_predicates(motion: Motion) -> tuple[tuple[str, tuple[str, ...]], ...]:
    return tuple((motion.name + suffix, args) for suffix, args in _STATIC[_SHAPES[motion]])


PREDICATES: tuple[tuple[str, tuple[tuple[str, str], ...]], ...] = (
    ("robot-at", (("?c", "cell"),)),
    ("facing", (("?h", "heading"),)),
    ("healthy", (("?w", "wheel"), ("?m", "mode"))),
    *(
        (name, tuple((v, _VARIABLE_TYPES[v]) for v in args))
        for m in four_wheel.MOTIONS
        for name, args in _static_predicates(m)
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
    static = tuple((name, *args) for name, args in _static_predicates(motion))
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


# --- the task -----------------------------------------------------------------------------------


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


def _check_exportable(problem: PlanningProblem, max_cells: int) -> None:
    if problem.domain is not four_wheel.FOUR_WHEEL:
        raise ProblemError(
            f"the PDDL export knows the four-wheel robot only, got domain {problem.domain.name!r}"
        )
    maze = problem.maze
    if max_cells < 1:
        raise ProblemError(f"max_cells must be >= 1, got {max_cells}")
    if maze.width * maze.height > max_cells:
        raise ProblemError(
            f"the {maze.width}x{maze.height} maze has {maze.width * maze.height} cells, more than "
            f"the PDDL export limit of {max_cells}; raise it with max_cells= (CLI: --max-cells)"
        )
    # The planners' own start/goal checks (the backend argument is theirs and irrelevant here).
    check_search_inputs(
        maze,
        (("start", problem.start.cell), ("goal", problem.goal)),
        backend="python",
        max_expansions=None,
        time_limit=None,
    )
    if problem.clearance_weight:
        raise ProblemError(
            "the PDDL export encodes durations only; expected clearance_weight 0, "
            f"got {problem.clearance_weight}"
        )


def step_parameters(shape: Shape, pose: Pose, end: Pose) -> tuple[str, ...]:
    """The parameters of a step of ``shape`` from ``pose`` to ``end``: PDDL object names."""
    bindings = _bindings(pose, end)
    return tuple(bindings[v] for v, _ in _PARAMETERS[shape])


def _motion_facts(problem: PlanningProblem, motion: Motion) -> tuple[list[Atom], int]:
    """The static facts of one motion on the maze, from the world model's ``step``, and the
    number of ground instances they allow.

    A fact with a cell argument is listed for every free pose from which the motion sweeps only
    free cells; a fact on headings alone is listed once per start heading (from probe poses).
    """
    action = _REPRESENTATIVE[motion]
    facts: list[Atom] = []
    counts = []
    for name, args in _static_predicates(motion):
        on_cells = any(_VARIABLE_TYPES[v] == "cell" for v in args)
        starts = (
            [Pose(x, y, h) for x, y in problem.maze.free_cells() for h in Heading]
            if on_cells
            else _PROBES  # headings only: the same in every cell, one probe per heading
        )
        found = []
        for pose in starts:
            end, swept, _ = four_wheel.step(pose, action)
            if on_cells and not problem.maze.all_free(swept):
                continue
            bindings = _bindings(pose, end)
            found.append((name, *(bindings[v] for v in args)))
        facts += found
        counts.append(len(found))
    return facts, counts[0] if counts else 1  # the first fact pins a step down; a wait: once


def _bindings(pose: Pose, end: Pose) -> dict[str, str]:
    """The schema variables of a step from ``pose`` to ``end``, as PDDL object names."""
    return {
        "?c": cell_name(pose.cell),
        "?h": HEADING_NAMES[pose.heading],
        "?d": cell_name(end.cell),
        "?g": HEADING_NAMES[end.heading],
    }


def export_pddl(
    problem: PlanningProblem,
    *,
    name: str = "",
    actions: Iterable[Action] = ACTIONS,
    action_costs: bool = True,
    max_cells: int = MAX_PDDL_CELLS,
) -> PddlTask:
    """``problem`` (maze, start pose, goal cell and optional heading, known faults) in PDDL terms.

    ``actions`` chooses the schemas (default: all 81, in :data:`ACTIONS` order); a planner call
    may pass fewer, e.g. only the fastest available action of each motion. ``action_costs=False``
    leaves out costs and the metric (for planners that cannot take numeric fluents).

    Raises :class:`ProblemError` for another robot than the four-wheel one, a maze of more than
    ``max_cells`` cells (width times height, see :data:`MAX_PDDL_CELLS`), a start or goal outside
    the maze or in a wall, a non-zero clearance weight (the encoding's cost is duration only), or
    no action.
    """
    _check_exportable(problem, max_cells)
    chosen = set(actions)
    schemas = tuple(_SCHEMAS[a] for a in ACTIONS if a in chosen)
    if not schemas:
        raise ProblemError("expected at least one action to export")
    facts = {m: _motion_facts(problem, m) for m in four_wheel.MOTIONS}
    static = [f for fs, _ in facts.values() for f in fs]
    ground = sum(facts[four_wheel.motion(s.action)][1] for s in schemas)
    healthy = [
        ("healthy", WHEEL_NAMES[w], MODE_NAMES[m])
        for w in Wheel
        for m in MODE_NAMES
        if Fault(w, m) not in problem.faults
    ]
    start = problem.start
    init = [("robot-at", cell_name(start.cell)), ("facing", HEADING_NAMES[start.heading])]
    goal: list[Atom] = [("robot-at", cell_name(problem.goal))]
    if problem.goal_heading is not None:
        goal.append(("facing", HEADING_NAMES[problem.goal_heading]))
    maze = problem.maze
    heading = "" if problem.goal_heading is None else f",{problem.goal_heading.name}"
    comment = (
        f"{maze.width}x{maze.height} maze {maze.name or '(unnamed)'}: start {start}, goal "
        f"{problem.goal[0]},{problem.goal[1]}{heading}, known faults: "
        f"{four_wheel.format_faults(problem.faults) or 'none'}"
    )
    return PddlTask(
        name=_pddl_name(name or maze.name or "maze"),
        comment=comment,
        schemas=schemas,
        cells=tuple(cell_name(c) for c in maze.free_cells()),
        init=(*init, *healthy, *static),
        goal=tuple(goal),
        action_costs=action_costs,
        static_facts=len(static),
        ground_actions=ground,
    )


def _pddl_name(text: str) -> str:
    """A PDDL name from free text: letters, digits and ``-``, starting with a letter."""
    cleaned = re.sub(r"[^a-z0-9-]+", "-", text.lower()).strip("-")
    return cleaned if cleaned[:1].isalpha() else f"p-{cleaned}"


# --- text ---------------------------------------------------------------------------------------


def _atom(atom: Atom) -> str:
    return f"({' '.join(atom)})"


def _typed(parameters: tuple[tuple[str, str], ...]) -> str:
    return " ".join(f"{v} - {t}" for v, t in parameters)


def _schema_text(s: Schema, action_costs: bool) -> str:
    effects = [f"(not {_atom(a)})" for a in s.delete] + [_atom(a) for a in s.add]
    if action_costs:
        effects.append(f"(increase (total-cost) {s.cost})")
    ticks = four_wheel.duration(s.action)
    return (
        f"  (:action {s.name}\n"
        f"    ; {s.motion}, {ticks} tick{'' if ticks == 1 else 's'}\n"
        f"    :parameters ({_typed(s.parameters)})\n"
        f"    :precondition (and {' '.join(_atom(a) for a in s.precondition)})\n"
        f"    :effect (and {' '.join(effects)}))"
    )


def domain_text(task: PddlTask) -> str:
    """The domain file: the robot alone (no maze), with the task's schemas and cost option."""
    requirements = ":strips :typing" + (" :action-costs" if task.action_costs else "")
    headings = " ".join(HEADING_NAMES.values())
    wheels = " ".join(WHEEL_NAMES.values())
    modes = " ".join(MODE_NAMES.values())
    lines = [
        ";; The four-wheel skid-steer robot of selfrepair, from selfrepair.baselines.pddl.",
        ";; (healthy W M): wheel W can perform command M; a known fault removes that fact.",
        f"(define (domain {DOMAIN_NAME})",
        f"  (:requirements {requirements})",
        "  (:types cell heading wheel mode)",
        f"  (:constants {headings} - heading {wheels} - wheel {modes} - mode)",
        "  (:predicates",
        *(f"    ({name} {_typed(params)})" for name, params in PREDICATES),
        "  )",
    ]
    if task.action_costs:
        lines.append("  (:functions (total-cost) - number)")
    lines += [_schema_text(s, task.action_costs) for s in task.schemas]
    lines.append(")")
    return "\n".join(lines) + "\n"


def _packed(items: Sequence[str], per_line: int) -> list[str]:
    return ["    " + " ".join(items[i : i + per_line]) for i in range(0, len(items), per_line)]


def problem_text(task: PddlTask) -> str:
    """The problem file: the maze's cells, the start pose, wheel health, geometry and goal.

    The initial state has one line for the pose, then one group of lines per predicate.
    """
    pose = [_atom(a) for a in task.init if a[0] in ("robot-at", "facing")]
    groups = [
        _packed([_atom(a) for a in atoms], 4)
        for name, atoms in itertools.groupby(task.init, key=lambda a: a[0])
        if name not in ("robot-at", "facing")
    ]
    lines = [
        f";; {task.comment}",
        f"(define (problem {task.name})",
        f"  (:domain {DOMAIN_NAME})",
        "  (:objects",
        *_packed(task.cells, 12),
        "    - cell)",
        "  (:init",
        "    " + " ".join(pose),
        *(line for group in groups for line in group),
    ]
    if task.action_costs:
        lines.append("    (= (total-cost) 0)")
    lines[-1] += ")"
    lines.append(f"  (:goal (and {' '.join(_atom(a) for a in task.goal)}))")
    if task.action_costs:
        lines.append("  (:metric minimize (total-cost))")
    lines[-1] += ")"
    return "\n".join(lines) + "\n"


def write_pddl(task: PddlTask, directory: str | Path) -> tuple[Path, Path]:
    """Write ``domain.pddl`` and ``problem.pddl`` into ``directory`` (created if missing)."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    domain, problem = out / "domain.pddl", out / "problem.pddl"
    domain.write_text(domain_text(task), encoding="utf-8")
    problem.write_text(problem_text(task), encoding="utf-8")
    return domain, problem


# --- plans --------------------------------------------------------------------------------------


def step_pddl(pose: Pose, action: Action) -> tuple[Atom, Pose]:
    """One plan step as an atom, e.g. ``("ffff", "c3_4", "north", "c3_3")``, and its end pose."""
    end = four_wheel.step(pose, action)[0]
    s = _SCHEMAS[action]
    return (s.name, *step_parameters(s.shape, pose, end)), end


def plan_to_pddl(start: Pose, actions: Iterable[Action]) -> str:
    """A selfrepair plan (actions from ``start``) as a PDDL plan text, one step per line.

    The parameters follow from stepping on an open plane; whether each step is executable in a
    maze under some faults is the question a validator answers. The last line is a comment with
    the total cost in thirds of a tick.
    """
    lines = []
    pose = start
    units = 0
    for action in actions:
        atom, pose = step_pddl(pose, action)
        lines.append(_atom(atom))
        units += _SCHEMAS[action].cost
    lines.append(f"; cost = {units} (thirds of a tick)")
    return "\n".join(lines) + "\n"


_STEP = re.compile(r"^\s*(?:\d+(?:\.\d+)?\s*:\s*)?\(([^()]*)\)\s*(?:\[[^\]]*\])?\s*$")


def parse_pddl_plan(text: str, start: Pose, *, source: str = "<plan>") -> tuple[Action, ...]:
    """Read a PDDL plan back into actions, re-simulating from ``start``.

    Accepts the IPC form ``(ffff c3_4 north c3_3)`` and LPG's ``0: (FFFF C3_4 NORTH C3_3) [1]``,
    in any case; ``;`` starts a comment. Raises :class:`InputError` naming ``source`` and the line
    for a line that is not a step, an unknown action, or parameters other than those of the step
    re-simulated from ``start``.
    """
    actions: list[Action] = []
    pose = start
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split(";", 1)[0].strip()
        if not line:
            continue
        match = _STEP.match(line.lower())
        words = match.group(1).split() if match else []
        if not words:
            raise InputError(
                f"expected a plan step such as (ffff c3_4 north c3_3), got {line!r}",
                source=source,
                line=number,
            )
        try:
            action = four_wheel.parse_action(words[0])
        except InputError as exc:
            raise InputError(exc.reason, source=source, line=number) from None
        expected, end = step_pddl(pose, action)
        if tuple(words) != expected:
            raise InputError(
                f"expected {_atom(expected)} for step {len(actions) + 1} from {pose}, "
                f"got {_atom(tuple(words))}",
                source=source,
                line=number,
            )
        actions.append(action)
        pose = end
    return tuple(actions)
