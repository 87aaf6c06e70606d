"""The bridge to unified-planning (UP): a :class:`~selfrepair.baselines.pddl.PddlTask` as a UP
problem, plans both ways, and LPG-adapt as a UP ``PlanRepairer`` engine. Needs the ``pddl`` extra
(``pip install 'selfrepair[pddl]'``); :mod:`selfrepair.baselines.lpg` imports this module only
when called.

Problems are built with UP's Python API from the task's atoms, the same data the PDDL text is
written from, because UP's ``PDDLReader`` takes minutes on the larger mazes (150 s for the 2 MB
``wide-long`` problem); the tests check that the two routes give the same problem.

Everything runs in UP's global environment (UP 1.3 does not carry a private one through its PDDL
reader and plan validator). :func:`environment` registers the repaired LPG engine there by name,
and :func:`quiet` switches UP's credits banner off while an engine is made: library code never
prints.

Why :class:`LpgAdaptRepairer` and not up-lpg's own ``lpg-repairer``: in up-lpg 0.1.3 that engine
never hands the plan to LPG. Its ``_repair`` appends ``-input_plan FILE`` to ``self._options``,
which ``_get_cmd`` never reads (it reads ``self.parameter``), so LPG plans from scratch; and its
``plan_to_file`` writes the action name where the parameters belong (``(ffff ffff)`` instead of
``(ffff c3_4 north c3_3)``). It also takes no time limit. :class:`LpgAdaptRepairer` is the same
engine with those three things fixed, reached through UP's ``PlanRepairer`` operation mode.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import IO, Any

import unified_planning.model as up_model
from unified_planning.engines import PlanGenerationResult
from unified_planning.environment import Environment, get_environment
from unified_planning.plans import ActionInstance, PlanKind, SequentialPlan
from up_lpg.lpg_planner import LPGPlanRepairer

from selfrepair.baselines.pddlschema import (
    HEADING_NAMES,
    MODE_NAMES,
    PREDICATES,
    WHEEL_NAMES,
    PddlTask,
)
from selfrepair.baselines.pddltext import parse_pddl_plan, step_pddl
from selfrepair.errors import ProblemError
from selfrepair.geometry import Pose
from selfrepair.robots.four_wheel import Action

__all__ = [
    "LPG_ADAPT_ENGINE",
    "LpgAdaptRepairer",
    "environment",
    "from_up_plan",
    "plan_lines",
    "quiet",
    "to_up_plan",
    "up_problem",
]

LPG_ADAPT_ENGINE = "selfrepair-lpg-adapt"
"""The name :class:`LpgAdaptRepairer` is registered under in :func:`environment`'s factory."""

_TYPES = ("cell", "heading", "wheel", "mode")


def environment() -> Environment:
    """UP's global environment, with :class:`LpgAdaptRepairer` registered by name (once).

    It is not put on UP's preference list, so UP never picks it unasked.
    """
    env = get_environment()
    factory = env.factory
    if LPG_ADAPT_ENGINE not in factory.engines:
        factory.add_engine(LPG_ADAPT_ENGINE, __name__, LpgAdaptRepairer.__name__)
        factory.preference_list = [n for n in factory.preference_list if n != LPG_ADAPT_ENGINE]
    return env


@contextmanager
def quiet(env: Environment) -> Iterator[None]:
    """Switch off UP's credits banner (printed on stdout when an engine is made) for a while."""
    stream = env.credits_stream
    env.credits_stream = None
    try:
        yield
    finally:
        env.credits_stream = stream


class _WrittenProblem(up_model.Problem):  # type: ignore[misc]
    """A UP problem whose ``initial_values`` are only those set explicitly (the true atoms).

    UP 1.3's ``PDDLWriter`` asks for ``initial_values``, which enumerates every grounding of every
    fluent to print the true ones: 677,604 groundings on the 15 x 15 maze (about 40 s), tens of
    millions on the 61 x 61 one. PDDL's initial state is closed-world, so the true atoms are all a
    writer needs. Only for problems handed to a PDDL planner: UP's own simulator and validator need
    every value, and get them from a plain problem.
    """

    @property
    def initial_values(self) -> dict[object, Any]:
        return dict(self.explicit_initial_values)


def up_problem(
    task: PddlTask, *, env: Environment | None = None, for_writer: bool = False
) -> up_model.Problem:
    """``task`` as a UP problem, built directly (same names as the PDDL text, lower case).

    ``for_writer=True`` gives a problem that UP writes out as PDDL quickly but that UP's simulator
    and validator cannot use (see :class:`_WrittenProblem`); a PDDL planner engine needs it.
    """
    env = env or environment()
    types = {name: env.type_manager.UserType(name) for name in _TYPES}
    fluents = {
        name: up_model.Fluent(
            name,
            env.type_manager.BoolType(),
            [up_model.Parameter(var[1:], types[kind], env) for var, kind in params],
            env,
        )
        for name, params in PREDICATES
    }
    problem = (_WrittenProblem if for_writer else up_model.Problem)(task.name, env)
    for fluent in fluents.values():
        problem.add_fluent(fluent, default_initial_value=False)
    objects = _objects(task, types, env)
    problem.add_objects(objects.values())
    costs: dict[up_model.Action, Any] = {}
    for schema in task.schemas:
        action = up_model.InstantaneousAction(
            schema.name, {var[1:]: types[kind] for var, kind in schema.parameters}, env
        )
        args = {var: action.parameter(var[1:]) for var, _ in schema.parameters}

        def ground(atom: tuple[str, ...], args: dict[str, Any] = args) -> Any:
            return fluents[atom[0]](*(args[a] if a in args else objects[a] for a in atom[1:]))

        for atom in schema.precondition:
            action.add_precondition(ground(atom))
        for atom in schema.delete:
            action.add_effect(ground(atom), False)
        for atom in schema.add:
            action.add_effect(ground(atom), True)
        problem.add_action(action)
        costs[action] = env.expression_manager.Int(schema.cost)
    for atom in task.init:
        problem.set_initial_value(fluents[atom[0]](*(objects[a] for a in atom[1:])), True)
    for atom in task.goal:
        problem.add_goal(fluents[atom[0]](*(objects[a] for a in atom[1:])))
    if task.action_costs:
        problem.add_quality_metric(up_model.metrics.MinimizeActionCosts(costs, environment=env))
    return problem


def _objects(
    task: PddlTask, types: dict[str, up_model.Type], env: Environment
) -> dict[str, up_model.Object]:
    named = [
        *((name, "heading") for name in HEADING_NAMES.values()),
        *((name, "wheel") for name in WHEEL_NAMES.values()),
        *((name, "mode") for name in MODE_NAMES.values()),
        *((name, "cell") for name in task.cells),
    ]
    return {name: up_model.Object(name, types[kind], env) for name, kind in named}


def to_up_plan(problem: up_model.Problem, start: Pose, actions: Iterable[Action]) -> SequentialPlan:
    """A selfrepair plan (actions from ``start``) as a UP sequential plan of ``problem``.

    Raises :class:`ProblemError` if a step needs an action or a cell that ``problem`` lacks (a
    step that leaves the maze's free cells has no cell object to name).
    """
    steps = []
    pose = start
    for index, action in enumerate(actions):
        atom, pose = step_pddl(pose, action)
        if not problem.has_action(atom[0]) or not all(problem.has_object(a) for a in atom[1:]):
            raise ProblemError(
                f"step {index} ({' '.join(atom)}) names an action or cell that the problem lacks"
            )
        params = [problem.object(a) for a in atom[1:]]
        steps.append(ActionInstance(problem.action(atom[0]), params))
    return SequentialPlan(steps, environment=problem.environment)


def from_up_plan(plan: SequentialPlan, start: Pose) -> tuple[Action, ...]:
    """A UP sequential plan back into actions, re-simulated from ``start``.

    Raises :class:`~selfrepair.errors.InputError` (source ``<up plan>``, the line is the step
    number) if a step is not the action and parameters that re-simulation expects.
    """
    return parse_pddl_plan("\n".join(plan_lines(plan)), start, source="<up plan>")


class LpgAdaptRepairer(LPGPlanRepairer):  # type: ignore[misc]
    """up-lpg's ``lpg-repairer`` with its defects fixed (module docstring).

    Constructor parameters (UP passes an operation mode's ``params`` here): ``timeout`` is the
    wall-clock limit in seconds on the LPG process (UP kills it then); every other key is an LPG
    command-line option, e.g. ``{"-seed": "7", "-cputime": "2"}`` (an empty value for a flag).
    """

    def __init__(self, timeout: float | None = None, **options: Any) -> None:
        LPGPlanRepairer.__init__(self)
        self._timeout = timeout
        for key, value in options.items():
            self.parameter.append(str(key))
            if value != "":
                self.parameter.append(str(value))

    @property
    def name(self) -> str:
        return LPG_ADAPT_ENGINE

    def _repair(self, problem: Any, plan: Any) -> PlanGenerationResult:
        with tempfile.TemporaryDirectory() as tempdir:
            path = os.path.join(tempdir, "input_plan.SOL")
            self.plan_to_file(plan, path)
            base = list(self.parameter)
            self.parameter.extend(["-input_plan", path])
            try:
                return self.solve(problem, timeout=self._timeout)
            finally:
                self.parameter[:] = base

    def plan_to_file(self, plan: Any, out: str | IO[str]) -> None:
        """Write ``plan`` in LPG's plan format, ``0:   (ffff c3_4 north c3_3)  [1]``."""
        if plan.kind != PlanKind.SEQUENTIAL_PLAN:
            raise ProblemError(f"expected a sequential plan, got {plan.kind}")
        lines = [f"{i}:   ({_instance_text(a)})  [1]\n" for i, a in enumerate(plan.actions)]
        if isinstance(out, str):
            with open(out, "w", encoding="utf-8") as f:
                f.writelines(lines)
        else:
            out.writelines(lines)


def _instance_text(instance: ActionInstance) -> str:
    return " ".join([instance.action.name, *(str(p) for p in instance.actual_parameters)])


def plan_lines(plan: SequentialPlan) -> Sequence[str]:
    """The plan's steps as PDDL text lines, e.g. ``(ffff c3_4 north c3_3)``."""
    return [f"({_instance_text(a)})" for a in plan.actions]
