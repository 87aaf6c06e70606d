"""The PDDL export (:mod:`selfrepair.baselines.pddl`) on its own, without unified-planning."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.baselines import pddl
from selfrepair.baselines.lpg import lpg_actions, lpg_input_plan
from selfrepair.baselines.pddl import export_pddl
from selfrepair.baselines.pddlschema import PddlTask
from selfrepair.baselines.pddltext import (
    domain_text,
    parse_pddl_plan,
    plan_to_pddl,
    problem_text,
    write_pddl,
)
from selfrepair.errors import InputError, ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import ACTIONS, MotionKind, parse_action, parse_faults
from selfrepair.robots.registry import get_domain
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world import bundled
from selfrepair.world.maze import parse_maze

U_TURN = parse_maze(".....\n.###.\n.....\n", name="u-turn")
WIDE = parse_maze("......\n......\n..##..\n......\n", name="wide")


def u_problem(faults: str = "") -> PlanningProblem:
    return PlanningProblem(U_TURN, Pose(0, 0, Heading.E), (4, 2), faults=parse_faults(faults))


def schema_block(domain: str, code: str) -> str:
    blocks = [b for b in domain.split("  (:action ")[1:] if b.startswith(f"{code.lower()}\n")]
    assert len(blocks) == 1, f"expected one schema {code}"
    return blocks[0]


def test_domain_has_81_schemas_with_health_preconditions_and_costs_in_thirds() -> None:
    domain = domain_text(export_pddl(u_problem()))
    assert domain.count("(:action ") == 81
    assert ":action-costs" in domain and "(:functions (total-cost) - number)" in domain
    for action in ACTIONS:
        block = schema_block(domain, action.code)
        health = re.findall(r"\(healthy (\w+) (\w)\)", block)
        assert health == [
            (wheel, letter.lower())
            for wheel, letter in zip(("fl", "fr", "rl", "rr"), action.code, strict=True)
        ]
        units = action.duration * four_wheel.TICKS_DENOMINATOR
        assert f"(increase (total-cost) {units})" in block


def test_no_static_fact_has_four_arguments() -> None:
    """LPG-adapt crashes on them; an arc's fact is split into cells and heading."""
    task = export_pddl(PlanningProblem(WIDE, Pose(0, 0, Heading.E), (5, 3)))
    assert all(len(atom) <= 4 for atom in task.init)  # predicate + at most three arguments
    assert any(atom[0] == "arc-forward-left" for atom in task.init)
    assert ("arc-forward-left-heading", "north", "west") in task.init


def test_faults_are_missing_health_facts_not_missing_schemas() -> None:
    healthy = export_pddl(u_problem())
    faulty = export_pddl(u_problem("FL:F,RR:B"))
    assert [s.name for s in faulty.schemas] == [s.name for s in healthy.schemas]
    missing = set(healthy.init) - set(faulty.init)
    assert missing == {("healthy", "fl", "f"), ("healthy", "rr", "b")}
    assert "(healthy fl f)" not in problem_text(faulty)


def test_static_facts_follow_the_world_model() -> None:
    """Every moving fact is a step whose swept cells are free, and every such step has its fact."""
    problem = PlanningProblem(WIDE, Pose(0, 0, Heading.E), (5, 3))
    facts = set(export_pddl(problem).init)
    for motion in four_wheel.MOTIONS:
        if motion.kind in (MotionKind.WAIT, MotionKind.TURN):
            continue
        action = next(a for a in ACTIONS if a.motion == motion)
        for x, y in WIDE.free_cells():
            for heading in Heading:
                pose = Pose(x, y, heading)
                end, swept, _ = four_wheel.step(pose, action)
                atom = (motion.name, pddl.cell_name(pose.cell), pddl.HEADING_NAMES[heading])
                fact = (*atom, pddl.cell_name(end.cell))
                assert (fact in facts) == WIDE.all_free(swept), (motion.name, pose)


def test_goal_heading_and_start_are_in_the_problem() -> None:
    task = export_pddl(replace(u_problem(), goal_heading=Heading.S))
    assert ("robot-at", "c0_0") in task.init and ("facing", "east") in task.init
    assert task.goal == (("robot-at", "c4_2"), ("facing", "south"))


def test_without_costs_and_with_fewer_actions() -> None:
    actions = lpg_actions(frozenset())
    task = export_pddl(u_problem(), actions=actions, action_costs=False)
    domain, problem = domain_text(task), problem_text(task)
    assert domain.count("(:action ") == len(actions) == 8
    assert "total-cost" not in domain + problem and ":action-costs" not in domain
    assert problem.rstrip().endswith(")") and problem.count("(") == problem.count(")")


def test_size_limit_is_checked_and_can_be_raised() -> None:
    problem = u_problem()
    with pytest.raises(ProblemError, match=r"15 cells, more than the PDDL export limit of 14"):
        export_pddl(problem, max_cells=14)
    assert export_pddl(problem, max_cells=15).cells


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"start": Pose(1, 1, Heading.N)}, "start"),
        ({"goal": (9, 9)}, "goal"),
        ({"clearance_weight": 1}, "clearance_weight"),
        ({"domain": get_domain("three-action")}, "four-wheel robot only, got domain"),
    ],
)
def test_problems_that_cannot_be_exported(change: dict, message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        export_pddl(replace(u_problem(), **change))


def test_sizes_in_the_module_docstring_are_those_of_the_bundled_mazes() -> None:
    doc = pddl.__doc__ or ""
    for name in bundled.maze_names():
        route = bundled.bundled_routes(name)[0]
        task = export_pddl(PlanningProblem(bundled.load_bundled(name), route.start, route.goal))
        row = re.search(rf"^    {name} +\S+ +([\d,]+) +([\d,]+) +([\d,]+) ", doc, re.M)
        assert row is not None, name
        numbers = [int(n.replace(",", "")) for n in row.groups()]
        assert numbers == [len(task.cells), task.static_facts, task.ground_actions], name


def test_write_pddl_writes_both_files(tmp_path: Path) -> None:
    task = export_pddl(u_problem())
    domain, problem = write_pddl(task, tmp_path / "out")
    assert domain.read_text(encoding="utf-8") == domain_text(task)
    assert problem.read_text(encoding="utf-8").startswith(";; 5x3 maze u-turn: start 0,0,E")


# --- plans ----------------------------------------------------------------------------------------


def test_plan_text_of_a_lattice_plan() -> None:
    problem = u_problem()
    result = plan(problem)
    text = plan_to_pddl(problem.start, result.actions)
    assert text.splitlines()[:5] == [
        "(ffff c0_0 east c1_0)",
        "(ffff c1_0 east c2_0)",
        "(ffff c2_0 east c3_0)",
        "(ffff c3_0 east c4_0)",
        "(fbfb east south)",
    ]
    assert text.splitlines()[-1] == f"; cost = {3 * result.duration} (thirds of a tick)"


@settings(max_examples=60)
@given(
    x=st.integers(-5, 5),
    y=st.integers(-5, 5),
    heading=st.sampled_from(list(Heading)),
    actions=st.lists(st.sampled_from(ACTIONS), max_size=12),
)
def test_plan_text_round_trips(x: int, y: int, heading: Heading, actions: list) -> None:
    start = Pose(abs(x), abs(y), heading)
    assert parse_pddl_plan(plan_to_pddl(start, actions), start) == tuple(actions)


def test_lpg_plan_format_is_read() -> None:
    text = "; LPG\n0:   (FFFF C0_0 EAST C1_0) [1]\n1: (SBFB EAST SOUTH)  [1]\n\n"
    assert parse_pddl_plan(text, Pose(0, 0, Heading.E)) == (
        parse_action("FFFF"),
        parse_action("SBFB"),
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("(ffff c0_0 east c1_0)\n(ffff c0_0 east c1_0)", r"<plan>:2: expected \(ffff c1_0 east"),
        ("(ffff c0_0 east c1_0)\n(xxxx)", r"<plan>:2: expected an action"),
        ("ffff c0_0 east c1_0", r"<plan>:1: expected a plan step"),
        ("()", r"<plan>:1: expected a plan step"),
    ],
)
def test_bad_plan_text_names_the_line(text: str, message: str) -> None:
    with pytest.raises(InputError, match=message):
        parse_pddl_plan(text, Pose(0, 0, Heading.E))


# --- what LPG is given (no unified-planning needed) -----------------------------------------------


def test_lpg_actions_are_the_fastest_per_motion_plus_the_plan_without_waits() -> None:
    faults = parse_faults("FL:F")
    plan_actions = (parse_action("FFFF"), parse_action("SSSS"), parse_action("FBFB"))
    chosen = lpg_actions(faults, plan_actions)
    fastest = {a for a in four_wheel.fastest_by_motion(faults).values()}
    assert set(chosen) == (
        {*fastest, *plan_actions} - {a for a in ACTIONS if a.motion.kind is MotionKind.WAIT}
    )
    assert list(chosen) == sorted(chosen, key=ACTIONS.index)


def test_lpg_input_plan_drops_waits_and_stops_before_leaving_the_maze() -> None:
    problem = u_problem()
    ffff, ssss = parse_action("FFFF"), parse_action("SSSS")
    steps, note = lpg_input_plan(problem, (ffff, ssss, ffff))
    assert steps == (ffff, ffff) and note == ""
    steps, note = lpg_input_plan(problem, (ffff,) * 6)
    assert steps == (ffff,) * 4
    assert "cut before step 4 (FFFF at 4,0,E)" in note


def test_the_task_value_is_frozen() -> None:
    task = export_pddl(u_problem())
    assert isinstance(task, PddlTask)
    with pytest.raises(AttributeError):
        task.name = "other"  # type: ignore[misc]
