"""Plan repair with LPG-adapt (Fox, Gerevini, Long, Serina 2006), and plain LPG planning, through
unified-planning and the LPG-td 1.4 binary that the ``up-lpg`` wheel ships (``pddl`` extra).

:func:`lpg_adapt_repair` hands LPG the problem as it stands now (the robot's current pose as the
start, the known faults as missing ``(healthy W M)`` facts) together with the plan that was left
when the fault struck; LPG-adapt searches from that plan for a valid one, keeping as much of it as
it can. :func:`lpg_plan` asks LPG for a plan from scratch. Both return an :class:`LpgResult`:
time-outs and LPG failures are statuses, never exceptions, and a plan is only ``SOLVED`` after it
re-simulates in the maze under the known faults (:func:`selfrepair.search.lattice.plan_cost`).

What LPG is given, and why (each point found by running the binary)
    * No action costs: LPG-td 1.4 crashes (segmentation fault) on ``-input_plan`` whenever the
      problem has a numeric fluent, and ``total-cost`` is one; its plain search also fails to find
      a plan on a 15 x 15 maze with costs (and finds one without). LPG therefore looks for any
      valid plan; its duration is computed here, from the world model.
    * No waits: a schema whose effect is empty makes LPG's parser fail (``Null PLNODE!!!``), and a
      wait never helps reach a goal. Waits in the remaining plan are left out of the input plan.
    * Only the useful schemas: the fastest available action of each motion under the known faults
      (as the lattice planner prunes) plus every action of the remaining plan, so that LPG can keep
      the plan's steps as they are. The remaining plan's faulty steps stay in the input plan; LPG
      finds their schema inapplicable and repairs around them.
    * The input plan stops before the first step that would leave the maze's free cells (its
      parameters would name no cell); ``LpgResult.message`` says so when that happens.
    * No empty input plan: LPG-adapt crashes (segmentation fault) when no step of the input plan
      survives grounding, e.g. when the fault forbids every step. Then LPG plans from scratch
      (up-lpg's ``lpg`` engine) and ``LpgResult.message`` says so.
    * No fact with four arguments: LPG-adapt crashes on those too; the export splits an arc's
      fact in two (see :mod:`selfrepair.baselines.pddl`).
    * At most 2000 objects (:data:`LPG_MAX_OBJECTS`): LPG-td 1.4 is compiled with
      ``MAX_CONSTANTS`` 2000, so a maze with more than 1989 free cells (``wide-long`` has 2721)
      ends as ``ERROR`` at once, without running LPG.
    * ``-n 1`` (the first plan found), ``-seed`` (LPG is randomised; the seed is recorded) and
      ``-cputime`` (LPG's own CPU limit), under a wall-clock limit that UP enforces on the process.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from types import ModuleType
from typing import Any

from selfrepair.baselines.pddl import MAX_PDDL_CELLS, export_pddl
from selfrepair.baselines.pddlschema import HEADING_NAMES, MODE_NAMES, WHEEL_NAMES, PddlTask
from selfrepair.errors import InputError, ProblemError
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import Action, FaultSet, MotionKind
from selfrepair.search.lattice import plan_cost
from selfrepair.search.problem import PlanningProblem
from selfrepair.status import LpgStatus
from selfrepair.textio import JSONObject

__all__ = [
    "LPG_MAX_OBJECTS",
    "MAX_LPG_TIME_LIMIT",
    "LpgResult",
    "LpgStatus",
    "lpg_actions",
    "lpg_adapt_repair",
    "lpg_available",
    "lpg_input_plan",
    "lpg_plan",
]

LPG_MAX_OBJECTS = 2000
"""LPG-td 1.4 as shipped is compiled with ``MAX_CONSTANTS`` 2000: a problem with more objects (free
cells plus 11 constants) ends as ``ERROR`` without running LPG (LPG itself would stop with "too many
constants!" after UP spent seconds writing the problem)."""

MAX_LPG_TIME_LIMIT = 3600.0
"""Largest time limit (seconds) that :func:`lpg_adapt_repair` and :func:`lpg_plan` accept."""


@dataclass(frozen=True, slots=True)
class LpgResult:
    """The outcome of an LPG call.

    ``actions`` (empty unless solved) run from the problem's start and have been re-simulated in
    the maze under the known faults; ``duration`` is their total in ticks (0 unless solved).
    ``wall_time_ns`` is the whole call (export, UP problem, LPG, check), ``lpg_time_s`` the LPG
    process alone as UP timed it (``None`` if LPG did not run). ``input_steps`` counts the steps of
    the remaining plan handed to LPG-adapt (0 for plain planning); ``seed`` is LPG's seed.
    ``message`` explains anything but a clean solve.
    """

    status: LpgStatus
    actions: tuple[Action, ...]
    duration: Fraction
    wall_time_ns: int
    lpg_time_s: float | None
    seed: int
    input_steps: int
    message: str


def lpg_available() -> bool:
    """Whether the ``pddl`` extra (unified-planning and up-lpg) can be imported."""
    try:
        _bridge()
    except ProblemError:
        return False
    return True


def _bridge() -> ModuleType:
    try:
        from selfrepair.baselines import unified
    except ImportError as exc:
        raise ProblemError(
            f"LPG needs the pddl extra (pip install 'selfrepair[pddl]'): {exc}"
        ) from None
    return unified


def lpg_actions(faults: FaultSet, plan: Sequence[Action] = ()) -> tuple[Action, ...]:
    """The schemas LPG is given: the fastest available action of each motion under ``faults``
    and every action of ``plan``, waits left out (module docstring), in :data:`ACTIONS` order."""
    chosen = set(four_wheel.fastest_by_motion(faults).values()) | set(plan)
    return tuple(
        a for a in four_wheel.ACTIONS if a in chosen and a.motion.kind is not MotionKind.WAIT
    )


def lpg_input_plan(
    problem: PlanningProblem, remaining: Sequence[Action]
) -> tuple[tuple[Action, ...], str]:
    """The remaining plan as LPG-adapt gets it (waits left out, cut before the first step that
    leaves the maze's free cells) and a note on the cut (``""`` if none)."""
    steps: list[Action] = []
    pose = problem.start
    for index, action in enumerate(remaining):
        if action.motion.kind is MotionKind.WAIT:
            continue
        end, swept, _ = four_wheel.step(pose, action)
        if not problem.maze.all_free(swept):
            return tuple(steps), (
                f"the remaining plan was cut before step {index} ({action} at {pose}), which "
                "leaves the maze's free cells"
            )
        steps.append(action)
        pose = end
    return tuple(steps), ""


_OWN_OPTIONS = frozenset({"-o", "-f", "-n", "-out", "-input_plan", "-seed", "-cputime"})
"""The LPG options this module sets itself; ``options=`` may not name them."""


@dataclass(frozen=True, slots=True)
class _Call:
    """The settings of one LPG call, checked on construction."""

    time_limit_s: float
    seed: int
    options: dict[str, str]
    max_cells: int

    def __post_init__(self) -> None:
        if not 0 < self.time_limit_s <= MAX_LPG_TIME_LIMIT:
            raise ProblemError(
                f"time_limit_s must be above 0 and at most {MAX_LPG_TIME_LIMIT:g}, "
                f"got {self.time_limit_s}"
            )
        if not 0 <= self.seed < 2**31:
            raise ProblemError(f"seed must be from 0 to 2**31 - 1, got {self.seed}")
        for key, value in self.options.items():
            if not key.startswith("-") or key in _OWN_OPTIONS or not isinstance(value, str):
                raise ProblemError(
                    f"expected LPG options such as {{'-noise': '0.3'}} other than "
                    f"{', '.join(sorted(_OWN_OPTIONS))}, got {key!r}: {value!r}"
                )

    def lpg_options(self) -> dict[str, str]:
        """Seed, LPG's own CPU limit (not always honoured: UP's wall limit is the hard one) and
        the caller's options."""
        return {"-seed": str(self.seed), "-cputime": f"{self.time_limit_s:g}", **self.options}


def lpg_adapt_repair(
    problem: PlanningProblem,
    remaining_plan: Sequence[Action],
    *,
    time_limit_s: float,
    seed: int = 0,
    options: Mapping[str, str] | None = None,
    max_cells: int = MAX_PDDL_CELLS,
) -> LpgResult:
    """Repair ``remaining_plan`` (actions from ``problem.start``) with LPG-adapt.

    ``problem`` is the situation now: the current pose as ``start``, the goal, and the known
    faults. LPG runs through UP's ``PlanRepairer`` operation mode for at most ``time_limit_s``
    seconds with ``seed``; ``options`` are further LPG command-line options, e.g.
    ``{"-noise": "0.3"}`` (``""`` for a flag). Raises :class:`ProblemError` only for misuse: the
    ``pddl`` extra missing, a time limit outside (0, :data:`MAX_LPG_TIME_LIMIT`], a bad seed, an
    option this module sets itself, or a problem that
    :func:`~selfrepair.baselines.pddl.export_pddl` refuses (``max_cells``).
    """
    call = _Call(time_limit_s, seed, dict(options or {}), max_cells)
    return _run(problem, tuple(remaining_plan), call, repair=True)


def lpg_plan(
    problem: PlanningProblem,
    *,
    time_limit_s: float,
    seed: int = 0,
    options: Mapping[str, str] | None = None,
    max_cells: int = MAX_PDDL_CELLS,
) -> LpgResult:
    """Plan from scratch with LPG (UP's ``OneshotPlanner`` with up-lpg's ``lpg`` engine); the
    same arguments, limits, statuses and check as :func:`lpg_adapt_repair`. On mazes,
    ``options={"-onlybestfirst": ""}`` (LPG's best-first search instead of its local search) finds
    plans much sooner; see docs/baselines.md."""
    call = _Call(time_limit_s, seed, dict(options or {}), max_cells)
    return _run(problem, (), call, repair=False)


_Outcome = tuple[LpgStatus, tuple[Action, ...], Fraction, float | None, str]
"""Status, actions, duration, LPG process time and message of one call."""


def _run(
    problem: PlanningProblem, remaining: tuple[Action, ...], call: _Call, *, repair: bool
) -> LpgResult:
    t0 = time.perf_counter_ns()
    bridge = _bridge()
    steps, note = lpg_input_plan(problem, remaining) if repair else ((), "")
    task = export_pddl(
        problem,
        actions=lpg_actions(problem.faults, steps),
        action_costs=False,
        max_cells=call.max_cells,
    )
    notes = [note]
    if repair and not any(four_wheel.available(a, problem.faults) for a in steps):
        repair = False  # LPG-adapt crashes when no step of its input plan survives grounding
        notes.insert(0, "no step of the remaining plan is available: LPG planned from scratch")
    objects = len(task.cells) + len(HEADING_NAMES) + len(WHEEL_NAMES) + len(MODE_NAMES)
    if problem.at_goal(problem.start):
        outcome: _Outcome = (LpgStatus.SOLVED, (), Fraction(0), None, "already at the goal")
    elif objects > LPG_MAX_OBJECTS:
        message = (
            f"LPG-td 1.4 takes at most {LPG_MAX_OBJECTS} objects (its MAX_CONSTANTS); this "
            f"problem has {objects} ({len(task.cells)} free cells); LPG was not run"
        )
        outcome = (LpgStatus.ERROR, (), Fraction(0), None, message)
    else:
        outcome = _call(bridge, problem, task, steps, call, repair=repair)
    status, actions, duration, lpg_time, message = outcome
    return LpgResult(
        status=status,
        actions=actions,
        duration=duration,
        wall_time_ns=time.perf_counter_ns() - t0,
        lpg_time_s=lpg_time,
        seed=call.seed,
        input_steps=len(steps),
        message="; ".join(m for m in (message, *notes) if m),
    )


def _call(
    bridge: ModuleType,
    problem: PlanningProblem,
    task: PddlTask,
    steps: tuple[Action, ...],
    call: _Call,
    *,
    repair: bool,
) -> _Outcome:
    """Run LPG through UP; any failure inside UP or LPG becomes an ``ERROR`` outcome."""
    env = bridge.environment()
    up_problem = bridge.up_problem(task, env=env, for_writer=True)
    options = call.lpg_options()
    try:
        with bridge.quiet(env):
            if repair:
                up_plan = bridge.to_up_plan(up_problem, problem.start, steps)
                params: JSONObject = {"timeout": call.time_limit_s, **options}
                with env.factory.PlanRepairer(name=bridge.LPG_ADAPT_ENGINE, params=params) as lpg:
                    generated = lpg.repair(up_problem, up_plan)
            else:
                with env.factory.OneshotPlanner(name="lpg", params=options) as lpg:
                    generated = lpg.solve(up_problem, timeout=call.time_limit_s)
    except Exception as exc:  # UP and LPG failures are statuses, not exceptions
        message = f"LPG call failed: {type(exc).__name__}: {exc}"
        return LpgStatus.ERROR, (), Fraction(0), None, message
    return _interpret(bridge, problem, generated, call.time_limit_s)


def _interpret(
    bridge: ModuleType, problem: PlanningProblem, generated: Any, time_limit_s: float
) -> _Outcome:
    """UP's ``PlanGenerationResult`` as an outcome; a plan counts only if it re-simulates."""
    from unified_planning.engines import PlanGenerationResultStatus as Up

    metrics = generated.metrics or {}
    lpg_time = float(metrics["engine_internal_time"]) if "engine_internal_time" in metrics else None
    status = generated.status
    if status in (Up.SOLVED_SATISFICING, Up.SOLVED_OPTIMALLY) and generated.plan is not None:
        try:
            actions = bridge.from_up_plan(generated.plan, problem.start)
            duration = plan_cost(problem, actions)
        except (InputError, ProblemError) as exc:
            message = f"LPG's plan does not re-simulate: {exc}"
            return LpgStatus.ERROR, (), Fraction(0), lpg_time, message
        return LpgStatus.SOLVED, actions, duration, lpg_time, ""
    if status is Up.TIMEOUT or (
        status is Up.UNSOLVABLE_INCOMPLETELY and lpg_time is not None and lpg_time >= time_limit_s
    ):
        return LpgStatus.TIMEOUT, (), Fraction(0), lpg_time, f"no plan within {time_limit_s:g} s"
    if status in (Up.UNSOLVABLE_INCOMPLETELY, Up.UNSOLVABLE_PROVEN):
        return LpgStatus.NO_PLAN, (), Fraction(0), lpg_time, "LPG stopped without a plan"
    if any(_UNREACHABLE in line for line in _output(generated)):  # LPG exits with status 1
        message = "LPG's reachability analysis: the goal cannot be reached"
        return LpgStatus.NO_PLAN, (), Fraction(0), lpg_time, message
    message = f"LPG failed ({status.name}): {_last_output(generated)}"
    return LpgStatus.ERROR, (), Fraction(0), lpg_time, message


_UNREACHABLE = "Goals of the planning problem can not be reached"


def _output(generated: Any) -> list[str]:
    """The non-empty lines LPG wrote (stdout, then stderr)."""
    return [
        line.strip()
        for log in generated.log_messages or ()
        for line in log.message.splitlines()
        if line.strip()
    ]


def _last_output(generated: Any) -> str:
    """The last non-empty line LPG wrote, for an error message."""
    lines = _output(generated)
    return lines[-1] if lines else "no output"
