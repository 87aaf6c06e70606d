"""Property tests: the lattice planner against an independent brute-force Dijkstra.

The brute force knows nothing of the planner: it tries all 81 actions with ``four_wheel.step`` at
every pose, keeps those available under the faults whose swept cells are free, and prices them with
the cost formula written out here again. Both backends must agree with it and with each other.
"""

from __future__ import annotations

import heapq
import itertools
from fractions import Fraction

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import HEURISTICS, plan, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.maze import Maze, clearance_map


def brute_force_cost(problem: PlanningProblem) -> Fraction | None:
    """Dijkstra over every pose with all 81 actions; ``None`` if the goal cannot be reached."""
    maze = problem.maze
    clearance = clearance_map(maze)

    def cost_of(action: four_wheel.Action, swept: tuple[tuple[int, int], ...]) -> Fraction:
        shortfall = sum(max(0, problem.clearance_radius - int(clearance[y, x])) for x, y in swept)
        return action.duration + problem.clearance_weight * shortfall

    best: dict[Pose, Fraction] = {problem.start: Fraction(0)}
    tie = itertools.count()
    heap = [(Fraction(0), next(tie), problem.start)]
    done: set[Pose] = set()
    while heap:
        g, _, pose = heapq.heappop(heap)
        if pose in done:
            continue
        done.add(pose)
        if pose.cell == problem.goal and problem.goal_heading in (None, pose.heading):
            return g
        for action in four_wheel.ACTIONS:
            if not four_wheel.available(action, problem.faults):
                continue
            end, swept, _ = four_wheel.step(pose, action)
            if not all(maze.is_free(x, y) for x, y in swept):
                continue
            new = g + cost_of(action, swept)
            if end not in best or new < best[end]:
                best[end] = new
                heapq.heappush(heap, (new, next(tie), end))
    return None


@st.composite
def problems(draw: st.DrawFn) -> PlanningProblem:
    width = draw(st.integers(2, 6))
    height = draw(st.integers(1, 5))
    density = draw(st.sampled_from([0.0, 0.15, 0.3]))
    seed = draw(st.integers(0, 2**32 - 1))
    walls = np.random.default_rng(seed).random((height, width)) < density
    free = [(x, y) for y in range(height) for x in range(width) if not walls[y, x]]
    if len(free) < 1:
        walls[0, 0] = False
        free = [(0, 0)]
    start = draw(st.sampled_from(free))
    goal = draw(st.sampled_from(free))
    faults = frozenset(draw(st.lists(st.sampled_from(four_wheel.SINGLE_FAULTS), max_size=3)))
    return PlanningProblem(
        maze=Maze(walls),
        start=Pose(start[0], start[1], draw(st.sampled_from(list(Heading)))),
        goal=goal,
        goal_heading=draw(st.none() | st.sampled_from(list(Heading))),
        faults=faults,
        clearance_weight=draw(st.sampled_from([Fraction(0), Fraction(1, 3), Fraction(2), 1])),
        clearance_radius=draw(st.integers(0, 3)),
    )


def assert_plan_re_simulates(problem: PlanningProblem, actions: tuple, poses: tuple) -> None:
    pose = problem.start
    assert poses[0] == pose
    for action, expected in zip(actions, poses[1:], strict=True):
        assert four_wheel.available(action, problem.faults)
        pose, swept, _ = four_wheel.step(pose, action)
        assert all(problem.maze.is_free(x, y) for x, y in swept)
        assert pose == expected
    assert pose.cell == problem.goal
    assert problem.goal_heading in (None, pose.heading)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems(), st.sampled_from(sorted(HEURISTICS)))
def test_lattice_astar_equals_brute_force_dijkstra(
    problem: PlanningProblem, heuristic: str
) -> None:
    expected = brute_force_cost(problem)
    result = plan(problem, heuristic=heuristic, backend="python")
    if expected is None:
        assert result.status is PlanStatus.UNSOLVABLE
        return
    assert result.status is PlanStatus.SOLVED
    assert result.cost == expected
    assert_plan_re_simulates(problem, result.actions, result.poses)
    assert result.duration == sum((a.duration for a in result.actions), Fraction(0))
    if problem.clearance_weight == 0:
        assert result.cost == result.duration


@NUMBA
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems(), st.sampled_from(sorted(HEURISTICS)))
def test_numba_backend_agrees_with_the_reference(problem: PlanningProblem, heuristic: str) -> None:
    reference = plan(problem, heuristic=heuristic, backend="python")
    compiled = plan(problem, heuristic=heuristic, backend="numba")
    assert compiled.status is reference.status
    assert compiled.cost == reference.cost
    assert compiled.actions == reference.actions  # same keys, same successor order
    assert compiled.poses == reference.poses
    assert compiled.expansions == reference.expansions


@settings(max_examples=60, deadline=None)
@given(problems())
def test_heuristics_are_consistent(problem: PlanningProblem) -> None:
    """h(a) <= cost(a -> b) + h(b) for every executable pruned action, and h(goal) = 0."""
    actions = planning_actions(FOUR_WHEEL, problem.faults)
    clearance = clearance_map(problem.maze)
    for name, fn in HEURISTICS.items():
        bound = fn(problem.maze, problem.goal, FOUR_WHEEL, actions)
        assert bound.distance[problem.goal[1], problem.goal[0]] == 0, name

        def h(cell: tuple[int, int], bound=bound) -> Fraction | None:
            d = int(bound.distance[cell[1], cell[0]])
            return None if d < 0 else bound.rate * d

        for x, y in problem.maze.free_cells():
            for heading in Heading:
                pose = Pose(x, y, heading)
                for action in actions:
                    end, swept, duration = four_wheel.step(pose, action)
                    if not problem.maze.all_free(swept):
                        continue
                    penalty = sum(
                        max(0, problem.clearance_radius - int(clearance[cy, cx]))
                        for cx, cy in swept
                    )
                    cost = duration + Fraction(problem.clearance_weight) * penalty
                    h_start, h_end = h(pose.cell), h(end.cell)
                    if h_start is None:
                        assert h_end is None, name  # unreachable stays unreachable
                        continue
                    if h_end is not None:
                        assert h_start <= cost + h_end, name


@NUMBA
@settings(max_examples=40, deadline=None)
@given(problems())
def test_bfs_kernel_equals_python_bfs(problem: PlanningProblem) -> None:
    from selfrepair.search.lattice import bfs_distances

    python = bfs_distances(problem.maze, problem.goal, backend="python")
    compiled = bfs_distances(problem.maze, problem.goal, backend="numba")
    assert np.array_equal(python, compiled)
