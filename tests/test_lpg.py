"""LPG-adapt repair and plain LPG planning (:mod:`selfrepair.baselines.lpg`).

The tests that run LPG need the ``pddl`` extra and are skipped with that reason without it (pytest
-ra lists the reason); the misuse tests run everywhere. No test asserts a time: LPG's speed is
measured by ``benchmarks/lpg.py``.
"""

from __future__ import annotations

import sys
from dataclasses import replace

import pytest

import selfrepair.baselines
from extras import LPG
from selfrepair.baselines import lpg
from selfrepair.baselines.lpg import LpgStatus, lpg_adapt_repair, lpg_available, lpg_plan
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import parse_faults
from selfrepair.search.lattice import plan, plan_cost
from selfrepair.search.problem import PlanningProblem
from selfrepair.world import bundled
from selfrepair.world.maze import parse_maze

needs_lpg = LPG

U_TURN = parse_maze(".....\n.###.\n.....\n", name="u-turn")


def narrow_short_after(steps: int, faults: str) -> tuple[PlanningProblem, tuple]:
    """The first route of narrow-short, ``steps`` into its plan, with ``faults`` now known."""
    route = bundled.bundled_routes("narrow-short")[0]
    healthy = PlanningProblem(bundled.load_bundled("narrow-short"), route.start, route.goal)
    result = plan(healthy)
    now = replace(healthy, start=result.poses[steps], faults=parse_faults(faults))
    return now, result.actions[steps:]


@needs_lpg
def test_repair_keeps_the_plan_and_the_result_re_simulates() -> None:
    problem, remaining = narrow_short_after(2, "FR:B")  # forbids the fbfb turns
    result = lpg_adapt_repair(problem, remaining, time_limit_s=30, seed=1)
    assert result.status is LpgStatus.SOLVED, result.message
    assert result.input_steps == len(remaining)
    assert result.duration == plan_cost(problem, result.actions)
    assert result.seed == 1 and result.lpg_time_s is not None and result.wall_time_ns > 0
    assert result.message == ""


@needs_lpg
def test_repair_is_deterministic_for_a_seed() -> None:
    problem, remaining = narrow_short_after(2, "FR:B")
    first = lpg_adapt_repair(problem, remaining, time_limit_s=30, seed=3)
    second = lpg_adapt_repair(problem, remaining, time_limit_s=30, seed=3)
    assert first.status is LpgStatus.SOLVED
    assert first.actions == second.actions


@needs_lpg
def test_a_plan_with_no_available_step_is_planned_from_scratch() -> None:
    problem = PlanningProblem(U_TURN, Pose(0, 0, Heading.E), (4, 2))
    remaining = plan(problem).actions  # every step needs FL forward
    faulty = replace(problem, faults=parse_faults("FL:F"))
    result = lpg_adapt_repair(faulty, remaining, time_limit_s=30)
    assert result.status is LpgStatus.SOLVED, result.message
    assert "LPG planned from scratch" in result.message
    plan_cost(faulty, result.actions)  # raises unless it re-simulates


@needs_lpg
def test_plain_planning() -> None:
    problem = PlanningProblem(U_TURN, Pose(4, 2, Heading.W), (0, 0), goal_heading=Heading.S)
    result = lpg_plan(problem, time_limit_s=30)
    assert result.status is LpgStatus.SOLVED, result.message
    assert result.input_steps == 0
    assert result.duration == plan_cost(problem, result.actions) >= plan(problem).duration


@needs_lpg
def test_unreachable_goal_is_no_plan() -> None:
    maze = parse_maze("..#..\n..#..\n")
    problem = PlanningProblem(maze, Pose(0, 0, Heading.E), (4, 0))
    result = lpg_plan(problem, time_limit_s=30)
    assert result.status is LpgStatus.NO_PLAN
    assert "cannot be reached" in result.message


@needs_lpg
def test_time_limit_is_a_status() -> None:
    """LPG needs far more than a fraction of a second on narrow-long (see benchmarks/lpg.py)."""
    route = bundled.bundled_routes("narrow-long")[0]
    problem = PlanningProblem(bundled.load_bundled("narrow-long"), route.start, route.goal)
    result = lpg_plan(problem, time_limit_s=0.2)
    assert result.status is LpgStatus.TIMEOUT
    assert result.actions == () and "0.2 s" in result.message


@needs_lpg
def test_too_many_objects_for_lpg_is_an_error_status() -> None:
    corridor = parse_maze("." * 1990 + "\n")  # 1990 cells and 11 constants: one too many
    problem = PlanningProblem(corridor, Pose(0, 0, Heading.E), (1989, 0))
    result = lpg_plan(problem, time_limit_s=30)
    assert result.status is LpgStatus.ERROR and result.lpg_time_s is None
    assert "at most 2000 objects" in result.message and "2001" in result.message


@needs_lpg
@pytest.mark.slow
def test_the_object_limit_is_lpgs() -> None:
    """One cell fewer, LPG runs and solves the corridor: the limit is not too strict."""
    corridor = parse_maze("." * 1989 + "\n")
    problem = PlanningProblem(corridor, Pose(0, 0, Heading.E), (3, 0))
    result = lpg_plan(problem, time_limit_s=60)
    assert result.status is LpgStatus.SOLVED, result.message


@needs_lpg
def test_failures_inside_up_are_an_error_status(monkeypatch: pytest.MonkeyPatch) -> None:
    from selfrepair.baselines import unified

    def broken(*args: object, **kwargs: object) -> None:
        raise OSError("no LPG binary")

    monkeypatch.setattr(unified, "to_up_plan", broken)
    problem, remaining = narrow_short_after(2, "FR:B")
    result = lpg_adapt_repair(problem, remaining, time_limit_s=5)
    assert result.status is LpgStatus.ERROR
    assert result.message == "LPG call failed: OSError: no LPG binary"


@needs_lpg
def test_a_plan_that_does_not_re_simulate_is_not_solved(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(problem: PlanningProblem, actions: object) -> None:
        raise ProblemError("action 0 (FFFF) at 1,1,E sweeps a wall or leaves the grid")

    monkeypatch.setattr(lpg, "plan_cost", refuse)
    problem, remaining = narrow_short_after(2, "FR:B")
    result = lpg_adapt_repair(problem, remaining, time_limit_s=30)
    assert result.status is LpgStatus.ERROR and result.actions == ()
    assert result.message.startswith("LPG's plan does not re-simulate: action 0 (FFFF)")


@needs_lpg
def test_already_at_the_goal() -> None:
    problem = PlanningProblem(U_TURN, Pose(4, 2, Heading.S), (4, 2))
    result = lpg_adapt_repair(problem, (), time_limit_s=5)
    assert (result.status, result.actions, result.lpg_time_s) == (LpgStatus.SOLVED, (), None)


@pytest.mark.parametrize(
    ("limit", "seed", "options", "message"),
    [
        (0, 0, {}, "time_limit_s"),
        (1e9, 0, {}, "time_limit_s"),
        (1, -1, {}, "seed"),
        (1, 0, {"-seed": "2"}, "other than -cputime"),
        (1, 0, {"noise": "0.3"}, "got 'noise'"),
    ],
)
def test_misuse_raises(limit: float, seed: int, options: dict, message: str) -> None:
    problem = PlanningProblem(U_TURN, Pose(0, 0, Heading.E), (4, 2))
    with pytest.raises(ProblemError, match=message):
        lpg_adapt_repair(problem, (), time_limit_s=limit, seed=seed, options=options)


@needs_lpg
def test_options_reach_lpg() -> None:
    problem = PlanningProblem(U_TURN, Pose(0, 0, Heading.E), (4, 2))
    result = lpg_plan(problem, time_limit_s=30, options={"-bogus": ""})
    assert result.status is LpgStatus.ERROR  # LPG prints its usage and exits non-zero
    problem, _ = narrow_short_after(0, "FL:F")  # LPG's best-first search instead of local search
    result = lpg_plan(problem, time_limit_s=30, options={"-onlybestfirst": ""})
    assert result.status is LpgStatus.SOLVED, result.message


def test_missing_extra_raises_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "selfrepair.baselines.unified", None)
    # ``from selfrepair.baselines import unified`` reads the package attribute first, which an
    # earlier import of the module has set: remove it too, as in a process without the extra
    monkeypatch.delattr(selfrepair.baselines, "unified", raising=False)
    assert not lpg_available()
    problem = PlanningProblem(U_TURN, Pose(0, 0, Heading.E), (4, 2))
    with pytest.raises(ProblemError, match=r"pip install 'selfrepair\[pddl\]'"):
        lpg_plan(problem, time_limit_s=1)
