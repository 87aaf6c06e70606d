"""The PDDL export cross-checked with unified-planning: its reader parses our files, and its plan
validator agrees with our world model on lattice plans, faulty plans and costs.

Needs the ``pddl`` extra; without it every test here is skipped with that reason (pytest -ra shows
it), never silently passed.
"""

# ruff: noqa: E402  (the extra is checked before the imports that need it)
from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from extras import need

need("unified_planning", "pddl")  # skips the module, or fails under SELFREPAIR_REQUIRE_EXTRAS=1
need("up_lpg", "pddl")

from unified_planning.engines import FailedValidationReason, ValidationResultStatus
from unified_planning.io import PDDLReader
from unified_planning.shortcuts import PlanValidator

from selfrepair.baselines.pddl import export_pddl
from selfrepair.baselines.pddltext import plan_to_pddl, write_pddl
from selfrepair.baselines.unified import (
    environment,
    from_up_plan,
    quiet,
    to_up_plan,
    up_problem,
)
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import SINGLE_FAULTS, parse_faults
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world import bundled
from selfrepair.world.maze import parse_maze

U_TURN = parse_maze(".....\n.###.\n.....\n", name="u-turn")
ROOM = parse_maze("......\n..#...\n......\n...#..\n......\n", name="room")


def small_problems() -> list[PlanningProblem]:
    """Small mazes with arcs (ROOM), U-turns (U_TURN) and a bundled maze's first route."""
    route = bundled.bundled_routes("narrow-short")[0]
    return [
        PlanningProblem(U_TURN, Pose(4, 2, Heading.W), (0, 0), goal_heading=Heading.S),
        PlanningProblem(ROOM, Pose(0, 0, Heading.S), (5, 4)),
        PlanningProblem(ROOM, Pose(5, 0, Heading.W), (0, 4), faults=parse_faults("FL:F")),
        PlanningProblem(bundled.load_bundled("narrow-short"), route.start, route.goal),
    ]


def validate(problem, up_plan):  # type: ignore[no-untyped-def]
    with (
        quiet(environment()),
        PlanValidator(problem_kind=problem.kind, plan_kind=up_plan.kind) as validator,
    ):
        return validator.validate(problem, up_plan)


EXAMPLES = (0, 2, 3)
"""The examples read back with UP's reader (a goal heading, arcs and a fault, a bundled maze)."""


@pytest.fixture(scope="module")
def parsed(tmp_path_factory: pytest.TempPathFactory) -> Callable[[int], Any]:
    """UP's reading of our files for example ``index``, parsed once per module (the reader takes
    seconds per problem)."""
    cache: dict[int, Any] = {}

    def get(index: int) -> Any:
        if index not in cache:
            directory = tmp_path_factory.mktemp(f"example{index}")
            domain, problem = write_pddl(export_pddl(small_problems()[index]), directory)
            cache[index] = PDDLReader().parse_problem(str(domain), str(problem))
        return cache[index]

    return get


@pytest.mark.parametrize("index", EXAMPLES)
def test_reader_parses_the_files_and_the_validator_accepts_lattice_plans(
    tmp_path: Path, parsed: Callable[[int], Any], index: int
) -> None:
    problem = small_problems()[index]
    result = plan(problem)
    assert result.actions, "the example needs a plan"
    up = parsed(index)
    assert len(up.actions) == 81
    plan_path = tmp_path / "plan.pddl"
    plan_path.write_text(plan_to_pddl(problem.start, result.actions), encoding="utf-8")
    up_plan = PDDLReader().parse_plan(up, str(plan_path))
    outcome = validate(up, up_plan)
    assert outcome.status is ValidationResultStatus.VALID
    (cost,) = outcome.metric_evaluations.values()
    assert cost == 3 * result.duration  # thirds of a tick


def conjuncts(expressions) -> list[str]:  # type: ignore[no-untyped-def]
    return sorted(str(c) for e in expressions for c in (e.args if e.is_and() else (e,)))


def shape(action) -> tuple:  # type: ignore[no-untyped-def]
    """An action's name, parameters, precondition conjuncts and effects, order aside."""
    return (
        action.name,
        [str(p) for p in action.parameters],
        conjuncts(action.preconditions),
        sorted(str(e) for e in action.effects),
    )


@pytest.mark.parametrize("index", EXAMPLES)
def test_problem_built_with_the_api_is_the_one_read_from_the_files(
    parsed: Callable[[int], Any], index: int
) -> None:
    built = up_problem(export_pddl(small_problems()[index]))
    read = parsed(index)

    def true_atoms(p) -> list[str]:  # type: ignore[no-untyped-def]
        return sorted(str(k) for k, v in p.explicit_initial_values.items() if v.is_true())

    assert true_atoms(built) == true_atoms(read)
    assert [shape(a) for a in built.actions] == [shape(a) for a in read.actions]
    assert conjuncts(built.goals) == conjuncts(read.goals)
    (built_costs,), (parsed_costs,) = built.quality_metrics, read.quality_metrics
    assert {a.name: str(c) for a, c in built_costs.costs.items()} == {
        a.name: str(c) for a, c in parsed_costs.costs.items()
    }


@pytest.mark.parametrize("fault", SINGLE_FAULTS, ids=str)
def test_validator_names_the_first_step_a_fault_forbids(fault: four_wheel.Fault) -> None:
    """A plan made before the fault still parses after it; the validator stops at its first
    step whose action the fault forbids (or accepts it if no step is forbidden)."""
    healthy = small_problems()[1]
    actions = plan(healthy).actions
    faulty = replace(healthy, faults=frozenset({fault}))
    up = up_problem(export_pddl(faulty))
    up_plan = to_up_plan(up, faulty.start, actions)
    outcome = validate(up, up_plan)
    forbidden = [i for i, a in enumerate(actions) if not four_wheel.available(a, faulty.faults)]
    if not forbidden:
        assert outcome.status is ValidationResultStatus.VALID
        return
    assert outcome.status is ValidationResultStatus.INVALID
    assert outcome.reason is FailedValidationReason.INAPPLICABLE_ACTION
    index = next(i for i, a in enumerate(up_plan.actions) if a is outcome.inapplicable_action)
    assert index == forbidden[0]


def test_validator_rejects_a_plan_that_stops_short_of_the_goal() -> None:
    problem = small_problems()[0]
    actions = plan(problem).actions[:-1]
    up = up_problem(export_pddl(problem))
    outcome = validate(up, to_up_plan(up, problem.start, actions))
    assert outcome.status is ValidationResultStatus.INVALID
    assert outcome.reason is FailedValidationReason.UNSATISFIED_GOALS


def test_up_plan_round_trip() -> None:
    problem = small_problems()[2]
    actions = plan(problem).actions
    up = up_problem(export_pddl(problem))
    up_plan = to_up_plan(up, problem.start, actions)
    assert str(up_plan.actions[0]).startswith(actions[0].code.lower() + "(")
    assert from_up_plan(up_plan, problem.start) == actions
