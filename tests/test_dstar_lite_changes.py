"""D* Lite kept between changes (:class:`selfrepair.search.dstar.DStarLite`): faults that come
and go, cells that become blocked or free, a robot that moves on. After every change the plan
costs what A* from scratch finds on the changed map (pure-Python reference), and the compiled
backend returns the same plan, cost and expansions as the reference (property tests over random
mazes, routes and update sequences); hand-made cases with known answers; misuse raises."""

from __future__ import annotations

import dataclasses
from fractions import Fraction
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.search.astar import PlanStatus
from selfrepair.search.dstar import DStarLite
from selfrepair.search.lattice import plan, plan_cost
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze

FAULT_TEXTS = ["", "FL:F", "FL:F,RR:B", "FR:F,FR:B", "RL:B", "FL:S,FR:S", "FL:F,FR:F,RL:F,RR:F"]

Event = tuple[str, Any]


@st.composite
def scenarios(draw: st.DrawFn) -> tuple[dict[str, Any], list[Event]]:
    """A random maze, route, clearance weight and goal heading, and a sequence of changes:
    ``("faults", text)``, ``("cells", (blocked, freed))`` and ``("move", steps)``."""
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    h, w = draw(st.integers(3, 8)), draw(st.integers(3, 8))
    walls = rng.random((h, w)) < draw(st.sampled_from([0.0, 0.15, 0.3]))
    free = [(int(x), int(y)) for y, x in zip(*np.nonzero(~walls), strict=True)]
    if len(free) < 2:
        walls[:] = False
        free = [(0, 0), (w - 1, h - 1)]
    start = free[draw(st.integers(0, len(free) - 1))]
    goal = free[draw(st.integers(0, len(free) - 1))]
    setup = {
        "walls": walls,
        "start": Pose(*start, draw(st.sampled_from(list(Heading)))),
        "goal": goal,
        "goal_heading": draw(st.sampled_from([None, None, Heading.S])),
        "weight": draw(st.sampled_from([Fraction(0), Fraction(0), Fraction(1, 2), Fraction(2)])),
    }
    cells = st.tuples(st.integers(0, w - 1), st.integers(0, h - 1))
    event = st.one_of(
        st.tuples(st.just("faults"), st.sampled_from(FAULT_TEXTS)),
        st.tuples(
            st.just("cells"),
            st.tuples(st.lists(cells, max_size=3), st.lists(cells, max_size=3)),
        ),
        st.tuples(st.just("move"), st.integers(1, 3)),
    )
    return setup, draw(st.lists(event, min_size=1, max_size=6))


def _run(
    setup: dict[str, Any], events: list[Event], backend: str
) -> list[tuple[Any, ...]]:  # fmt: skip
    """Apply ``events`` to a search; after each, the plan, its expansions and the number of
    vertex updates the change made."""
    search = DStarLite.create(
        FOUR_WHEEL, setup["walls"], setup["start"], setup["goal"],
        goal_heading=setup["goal_heading"], clearance_weight=setup["weight"], backend=backend,
    )  # fmt: skip
    pose = setup["start"]
    found = search.plan()
    out = [(found.status, found.actions, found.scaled_cost, found.expansions, pose, 0)]
    for kind, value in events:
        updates = 0
        if kind == "faults":
            updates = search.update_faults(FOUR_WHEEL.parse_faults(value))
        elif kind == "cells":
            blocked, freed = value
            free = [c for c in freed if c not in blocked]
            updates = search.update_cells(blocked=blocked, freed=free)
        else:
            for action in found.actions[:value]:
                pose = FOUR_WHEEL.apply(pose, action)
            search.move_start(pose)
        found = search.plan()
        row = (found.status, found.actions, found.scaled_cost, found.expansions, pose, updates)
        out.append(row)
    return out


def _check_against_astar(setup: dict[str, Any], events: list[Event]) -> None:
    search = DStarLite.create(
        FOUR_WHEEL, setup["walls"], setup["start"], setup["goal"],
        goal_heading=setup["goal_heading"], clearance_weight=setup["weight"], backend="python",
    )  # fmt: skip
    pose, faults = setup["start"], frozenset[Any]()
    found = search.plan()
    for kind, value in [("faults", ""), *events]:
        if kind == "faults":
            faults = FOUR_WHEEL.parse_faults(value)
            search.update_faults(faults)
        elif kind == "cells":
            blocked, freed = value
            search.update_cells(blocked=blocked, freed=[c for c in freed if c not in blocked])
        else:
            for action in found.actions[:value]:
                pose = FOUR_WHEEL.apply(pose, action)
            search.move_start(pose)
        found = search.plan()
        walls = search.walls
        if walls[pose.y, pose.x] or walls[setup["goal"][1], setup["goal"][0]]:
            assert found.status is PlanStatus.UNSOLVABLE and found.actions == ()
            continue
        problem = PlanningProblem(
            Maze(walls), pose, setup["goal"], setup["goal_heading"], faults, setup["weight"]
        )
        fresh = plan(problem, backend="python")
        assert found.status is fresh.status
        if fresh.status is PlanStatus.SOLVED:
            assert found.cost == fresh.cost == plan_cost(problem, found.actions)
            assert found.scaled_cost == found.cost * search.scale
        else:
            assert found.actions == () and found.cost is None


@settings(max_examples=60, deadline=None)
@given(scenarios())
def test_after_every_change_the_plan_costs_what_astar_from_scratch_costs(
    scenario: tuple[dict[str, Any], list[Event]],
) -> None:
    _check_against_astar(*scenario)


@NUMBA
@settings(max_examples=60, deadline=None)
@given(scenarios())
def test_the_compiled_search_gives_the_reference_plans_costs_and_expansions(
    scenario: tuple[dict[str, Any], list[Event]],
) -> None:
    setup, events = scenario
    assert _run(setup, events, "numba") == _run(setup, events, "python")


def _corridor(backend: str) -> DStarLite:
    walls = np.ones((3, 7), dtype=bool)
    walls[1, :] = False  # one row of 7 free cells, y = 1
    return DStarLite.create(FOUR_WHEEL, walls, Pose(0, 1, Heading.E), (6, 1), backend=backend)


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_a_blocked_corridor_has_no_plan_until_the_cell_is_free_again(backend: str) -> None:
    search = _corridor(backend)
    assert search.backend == backend
    first = search.plan()
    assert first.status is PlanStatus.SOLVED and first.cost == 6  # six cells forward, 1 tick each
    assert all(FOUR_WHEEL.format_action(a) == "FFFF" for a in first.actions)
    assert search.update_cells(blocked=[(3, 1)]) > 0
    assert search.plan().status is PlanStatus.UNSOLVABLE
    assert search.walls[1, 3]
    assert search.update_cells(blocked=[(3, 1)]) == 0  # already blocked: nothing to do
    search.update_cells(freed=[(3, 1)])
    again = search.plan()
    assert (again.status, again.actions, again.cost) == (first.status, first.actions, first.cost)


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_a_robot_that_drove_on_plans_the_rest(backend: str) -> None:
    search = _corridor(backend)
    first = search.plan()
    pose = Pose(0, 1, Heading.E)
    for action in first.actions[:2]:
        pose = FOUR_WHEEL.apply(pose, action)
    search.move_start(pose)
    rest = search.plan()
    assert rest.actions == first.actions[2:] and rest.cost == 4
    assert rest.expansions == 0  # nothing changed on the way: the search is kept


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_a_blocked_goal_or_start_means_no_plan(backend: str) -> None:
    search = _corridor(backend)
    search.update_cells(blocked=[(6, 1)])
    assert search.plan().status is PlanStatus.UNSOLVABLE
    search.update_cells(freed=[(6, 1)], blocked=[(0, 1)])
    assert search.plan().status is PlanStatus.UNSOLVABLE
    search.update_cells(freed=[(0, 1)])
    assert search.plan().cost == 6


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_a_cell_blocked_far_from_the_route_costs_few_expansions(backend: str) -> None:
    """The point of D* Lite: a local change is repaired locally (here a cell blocked in the far
    corner of wide-long, off the route), a lost action everywhere (the fault case) is not."""
    maze = load_bundled("wide-long")
    route = bundled_routes("wide-long")[0]
    search = DStarLite.create(FOUR_WHEEL, maze, route.start, route.goal, backend=backend)
    first = search.plan()
    far = max(
        maze.free_cells(), key=lambda c: abs(c[0] - route.goal[0]) + abs(c[1] - route.goal[1])
    )
    search.update_cells(blocked=[far])
    local = search.plan()
    assert local.cost == first.cost and local.expansions < first.expansions // 10
    search.update_faults(FOUR_WHEEL.parse_faults("FL:F"))
    lost = search.plan()
    fresh = plan(
        PlanningProblem(search_maze(search), route.start, route.goal, faults=search.faults)
    )
    assert lost.cost == fresh.cost and lost.expansions > 10 * local.expansions


def search_maze(search: DStarLite) -> Maze:
    return Maze(search.walls)


def test_another_robot_and_a_goal_heading() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    search = DStarLite.create(
        THREE_ACTION, maze, route.start, route.goal, goal_heading=Heading.N, backend="python"
    )
    found = search.plan()
    fresh = plan(PlanningProblem(maze, route.start, route.goal, Heading.N, domain=THREE_ACTION))
    assert found.cost == fresh.cost
    search.update_faults(THREE_ACTION.parse_faults("L"))
    faulty = plan(
        PlanningProblem(
            maze, route.start, route.goal, Heading.N, THREE_ACTION.parse_faults("L"),
            domain=THREE_ACTION,
        )
    )  # fmt: skip
    assert search.plan().cost == faulty.cost


def test_misuse_raises() -> None:
    walls = np.zeros((3, 3), dtype=bool)
    with pytest.raises(ProblemError, match="backend"):
        DStarLite.create(FOUR_WHEEL, walls, Pose(0, 0, Heading.E), (2, 2), backend="fast")
    with pytest.raises(ProblemError, match="outside"):
        DStarLite.create(FOUR_WHEEL, walls, Pose(0, 0, Heading.E), (3, 2))
    search = DStarLite.create(FOUR_WHEEL, walls, Pose(0, 0, Heading.E), (2, 2))
    with pytest.raises(ProblemError, match="outside"):
        search.update_cells(blocked=[(5, 0)])
    with pytest.raises(ProblemError, match="both"):
        search.update_cells(blocked=[(1, 1)], freed=[(1, 1)])
    with pytest.raises(ProblemError, match="outside"):
        search.move_start(Pose(-1, 0, Heading.E))


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_the_strategy_runs_on_either_backend_with_the_same_result(backend: str) -> None:
    maze = load_bundled("wide-short")
    route = bundled_routes("wide-short")[1]
    results = []
    for chosen in ("python", backend):
        spec = MissionSpec(
            maze, route.start, route.goal, strategy="dstar-lite", backend=chosen,
            schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FR:F,RL:S"), at=2),
            clearance_weight=Fraction(1),
        )  # fmt: skip
        result = run_mission(spec)
        results.append((result.status, result.ticks, [s.action for s in result.steps]))
    assert results[0] == results[1] and results[0][0] == "reached"


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_the_strategy_drives_round_a_cell_blocked_on_its_route(backend: str) -> None:
    """In a changing world D* Lite sees the believed-blocked cells: it is asked for the repair
    (not a plain replan) and its kept search goes round them."""
    from selfrepair.world.events import WorldEvent, WorldSchedule

    maze = load_bundled("wide-short")
    route = bundled_routes("wide-short")[0]
    first = run_mission(MissionSpec(maze, route.start, route.goal, strategy="replan"))
    cell = first.steps[6].end.cell
    world = WorldSchedule((WorldEvent(cell, True, 2),))
    spec = MissionSpec(
        maze, route.start, route.goal, strategy="dstar-lite", world=world, backend=backend
    )
    result = run_mission(spec)
    assert result.reached and cell not in {s.end.cell for s in result.steps}
    assert any(r.repair.attempts == ("dstar-lite",) for r in result.repairs)
    replanned = run_mission(dataclasses.replace(spec, strategy="replan"))
    assert result.ticks == replanned.ticks  # both replan optimally round the believed cell
