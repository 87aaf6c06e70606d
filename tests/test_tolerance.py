"""Plan tolerance (repair/tolerance.py): hand-made cases and agreement with a brute-force
re-simulation by the executor (a fault set appearing at a given step)."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.tolerance import mission_tolerance
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import FaultModel, PlanTolerance, fault_model
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.routes import random_routes

SINGLE = fault_model(FOUR_WHEEL, 1)
DOUBLE = fault_model(FOUR_WHEEL, 2)


def _resimulated(spec: MissionSpec, step: int, faults: frozenset[Any]) -> bool:
    """Whether the mission reaches the goal without a replan when ``faults`` appear (permanent,
    detected at once) before step ``step``: the executor, from the start."""
    schedule = FaultSchedule.permanent(faults, at=step)
    result = run_mission(_with(spec, schedule))
    return result.reached and all(r.repair.replans == 0 for r in result.repairs)


def _tolerance(spec: MissionSpec, model: FaultModel) -> tuple[Any, PlanTolerance]:
    initial, tolerance = mission_tolerance(spec, model)
    assert tolerance is not None
    return initial, tolerance


def _with(spec: MissionSpec, schedule: FaultSchedule) -> MissionSpec:
    from dataclasses import replace

    return replace(spec, schedule=schedule)


def test_fault_models_count_singles_and_pairs() -> None:
    assert len(SINGLE.fault_sets) == 12 and SINGLE.max_size == 1
    assert len(DOUBLE.fault_sets) == 12 + 66 and DOUBLE.max_size == 2
    assert len(fault_model(FOUR_WHEEL, 3).fault_sets) == 12 + 66 + 220
    with pytest.raises(ProblemError, match="at least 1"):
        fault_model(FOUR_WHEEL, 0)
    with pytest.raises(ProblemError, match="twice"):
        FaultModel((SINGLE.fault_sets[0], SINGLE.fault_sets[0]), "x")


def test_open_field_plan_is_single_fault_tolerant() -> None:
    """In an open field every faulty action has a replacement with flat recursion."""
    import numpy as np

    maze = Maze(np.zeros((9, 9), dtype=bool))
    spec = MissionSpec(maze, Pose(4, 4, Heading.E), (6, 4))
    initial, tolerance = _tolerance(spec, SINGLE)
    assert tolerance.tolerant and tolerance.share == 1
    assert tolerance.pairs == len(initial.actions) * 12
    assert tolerance.replan_steps == 0
    assert 0 < tolerance.met <= tolerance.pairs


def test_corridor_plan_and_the_executor_agree() -> None:
    """A one-cell corridor driven east (eight FFFF steps): with FL:F a slower forward motion
    (SFFS) replaces each step, so single faults are covered; with FL:F and FL:S together the
    front-left wheel can only go backward, no forward motion is left and the corridor leaves
    no room for the hand-written table's detours, so every step needs a replan."""
    import numpy as np

    walls = np.ones((3, 9), dtype=bool)
    walls[1, :] = False
    spec = MissionSpec(Maze(walls), Pose(0, 1, Heading.E), (8, 1))
    initial, tolerance = _tolerance(spec, DOUBLE)
    assert [FOUR_WHEEL.format_action(a) for a in initial.actions] == ["FFFF"] * 8
    fl_f = FOUR_WHEEL.parse_faults("FL:F")
    both = FOUR_WHEEL.parse_faults("FL:F,FL:S")
    assert all(fl_f not in s.uncovered and both in s.needs_replan for s in tolerance.steps)
    assert not tolerance.tolerant and tolerance.covered < tolerance.pairs
    single = _tolerance(spec, SINGLE)[1]
    assert single.tolerant and single.share == 1
    assert _resimulated(spec, 3, fl_f) and not _resimulated(spec, 3, both)


def test_bundled_route_agrees_with_the_executor_at_every_step() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(maze, route.start, route.goal, options=StrategyOptions(recursion="flat"))
    _, tolerance = _tolerance(spec, DOUBLE)
    assert not tolerance.tolerant  # the hand-written table with flat recursion misses pairs
    seen = []
    for step in tolerance.steps[::4]:
        for faults in DOUBLE.fault_sets[::5]:
            covered = faults not in step.uncovered
            assert covered == _resimulated(spec, step.step, faults)
            seen.append(covered)
    assert len(seen) > 50 and any(seen) and not all(seen)


@st.composite
def _missions(draw: st.DrawFn) -> tuple[MissionSpec, int, frozenset[Any]]:
    seed = draw(st.integers(0, 10_000))
    corridor = draw(st.sampled_from([1, 2]))
    side = draw(st.sampled_from([9, 11, 13]))
    maze = generate_maze(side, side, corridor=corridor, braid=0.3, seed=seed)
    route = random_routes(maze, 1, seed)[0]
    table = draw(st.sampled_from(["handwritten", "generated-indexed", "generated-agnostic"]))
    recursion = draw(st.sampled_from(["flat", "guarded", "layered", "primitive"]))
    rewrite = recursion != "primitive" and draw(st.booleans())
    options = StrategyOptions(table=table, recursion=recursion, rewrite=rewrite)
    spec = MissionSpec(maze, route.start, route.goal, options=options)
    faults = draw(st.sampled_from(DOUBLE.fault_sets))
    step = draw(st.integers(0, 60))
    return spec, step, faults


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_missions())
def test_covered_pairs_are_exactly_those_repaired_without_a_replan(
    mission: tuple[MissionSpec, int, frozenset[Any]],
) -> None:
    """A pair the checker calls covered is repaired without a replan when that fault set appears
    there (re-simulated from the start by the executor), and one it calls uncovered is not."""
    spec, step, faults = mission
    model = FaultModel((faults,), "one")
    initial, tolerance = _tolerance(spec, model)
    if not initial.actions:
        return
    step = min(step, len(initial.actions) - 1)
    covered = faults not in tolerance.steps[step].uncovered
    assert covered == _resimulated(spec, step, faults)


def test_cli_tolerance_text_json_and_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from selfrepair.cli import main

    route = ["narrow-short", "--start", "7,13,W", "--goal", "1,8"]
    assert main(["tolerance", *route, "--k", "1"]) == 0
    out = capsys.readouterr().out
    assert "240 of 240 (step, fault set) pairs covered (100.0%)" in out and "tolerant: yes" in out
    assert main(["tolerance", *route, "--k", "2", "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["pairs"] == 20 * 78 and data["covered"] < data["pairs"] and not data["tolerant"]
    assert len(data["steps"]) == 20 and "FL:S,FL:F" in data["steps"][0]["uncovered"]
    assert main(["tolerance", *route, "--fault-set", "FL:F,FL:S", "--summary"]) == 1
    assert "|@@@@@@@@@@@@@@@@@@@@|" in capsys.readouterr().out
    assert main(["tolerance", *route, "--fault-set", "FL:X"]) == 2
    assert "--fault-set" in capsys.readouterr().err
    assert main(["plan", *route, "--tolerance", "2", "--recursion", "guarded", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["tolerance"]["tolerant"] and data["tolerance"]["pairs"] == 20 * 78
