"""The four-wheel robot's PDDL as text: the domain and problem files of a
:class:`~selfrepair.baselines.pddlschema.PddlTask`, and plans written and read back one step per
line (format in :mod:`selfrepair.baselines.pddl`)."""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Sequence
from pathlib import Path

from selfrepair.baselines.pddlschema import (
    DOMAIN_NAME,
    HEADING_NAMES,
    MODE_NAMES,
    PREDICATES,
    WHEEL_NAMES,
    Atom,
    PddlTask,
    Schema,
    schema,
    step_parameters,
)
from selfrepair.errors import InputError
from selfrepair.geometry import Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import Action

__all__ = [
    "atom_text",
    "domain_text",
    "parse_pddl_plan",
    "plan_to_pddl",
    "problem_text",
    "step_pddl",
    "write_pddl",
]


def atom_text(atom: Atom) -> str:
    return f"({' '.join(atom)})"


def _typed(parameters: tuple[tuple[str, str], ...]) -> str:
    return " ".join(f"{v} - {t}" for v, t in parameters)


def _schema_text(s: Schema, action_costs: bool) -> str:
    effects = [f"(not {atom_text(a)})" for a in s.delete] + [atom_text(a) for a in s.add]
    if action_costs:
        effects.append(f"(increase (total-cost) {s.cost})")
    ticks = four_wheel.duration(s.action)
    return (
        f"  (:action {s.name}\n"
        f"    ; {s.motion}, {ticks} tick{'' if ticks == 1 else 's'}\n"
        f"    :parameters ({_typed(s.parameters)})\n"
        f"    :precondition (and {' '.join(atom_text(a) for a in s.precondition)})\n"
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
    pose = [atom_text(a) for a in task.init if a[0] in ("robot-at", "facing")]
    groups = [
        _packed([atom_text(a) for a in atoms], 4)
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
    lines.append(f"  (:goal (and {' '.join(atom_text(a) for a in task.goal)}))")
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
    s = schema(action)
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
        lines.append(atom_text(atom))
        units += schema(action).cost
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
                f"expected {atom_text(expected)} for step {len(actions) + 1} from {pose}, "
                f"got {atom_text(tuple(words))}",
                source=source,
                line=number,
            )
        actions.append(action)
        pose = end
    return tuple(actions)
