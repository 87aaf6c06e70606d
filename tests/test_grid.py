"""Plain grid A* (MovingAI rules): hand-checked costs, errors, and an independent Dijkstra."""

from __future__ import annotations

import heapq
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.errors import ProblemError
from selfrepair.search.astar import PlanStatus
from selfrepair.search.grid import grid_astar
from selfrepair.search.problem import SQRT2, OctileCost
from selfrepair.world.maze import Maze, parse_maze

BACKENDS = ["python", pytest.param("numba", marks=NUMBA)]

OPEN_3X3 = parse_maze("...\n...\n...\n")
CORNER = parse_maze(".#\n..\n")
DIAGONAL_WALLS = parse_maze(".#\n#.\n")
BENT = parse_maze("....\n.##.\n....\n")
POST = parse_maze(".....\n.#...\n.....\n")

# maze, start, goal, connectivity, (straight, diagonal) optimum checked by hand
ZOO = [
    (OPEN_3X3, (0, 0), (2, 2), 8, (0, 2), "two diagonals"),
    (OPEN_3X3, (0, 0), (2, 2), 4, (4, 0), "four straights"),
    (OPEN_3X3, (0, 0), (2, 1), 8, (1, 1), "one diagonal and one straight"),
    (CORNER, (0, 0), (1, 1), 8, (2, 0), "no corner cutting past the wall at (1,0)"),
    (BENT, (0, 0), (3, 2), 8, (5, 0), "every diagonal near the block would graze it"),
    (BENT, (0, 1), (3, 1), 4, (5, 0), "around the wall block"),
    (POST, (0, 0), (2, 2), 8, (4, 0), "the post at (1,1) blocks both diagonal steps"),
    (POST, (2, 0), (4, 2), 8, (0, 2), "two diagonals beside the post"),
]  # fmt: skip


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case", ZOO, ids=[c[5] for c in ZOO])
def test_zoo_optimal_costs(case: tuple, backend: str) -> None:
    maze, start, goal, connectivity, (straight, diagonal), _why = case
    result = grid_astar(maze, start, goal, connectivity=connectivity, backend=backend)
    assert result.status is PlanStatus.SOLVED
    assert result.cost == OctileCost(straight, diagonal)
    assert result.path[0] == start and result.path[-1] == goal
    assert_valid_path(maze, result.path, connectivity)


@pytest.mark.parametrize("backend", BACKENDS)
def test_diagonal_walls_block_the_only_way(backend: str) -> None:
    result = grid_astar(DIAGONAL_WALLS, (0, 0), (1, 1), backend=backend)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.path == () and result.cost is None


@pytest.mark.parametrize("backend", BACKENDS)
def test_budgets(backend: str) -> None:
    result = grid_astar(BENT, (0, 1), (3, 1), max_expansions=2, backend=backend)
    assert result.status is PlanStatus.BUDGET_EXHAUSTED and result.expansions == 2
    timed = grid_astar(BENT, (0, 1), (3, 1), time_limit=0.0, backend=backend)
    assert timed.status is PlanStatus.BUDGET_EXHAUSTED


def test_start_equal_goal() -> None:
    result = grid_astar(OPEN_3X3, (1, 1), (1, 1))
    assert result.status is PlanStatus.SOLVED
    assert result.path == ((1, 1),) and result.cost == OctileCost(0, 0)


def test_octile_cost_value_and_text() -> None:
    assert OctileCost(3, 2).value == pytest.approx(3 + 2 * math.sqrt(2))
    assert str(OctileCost(3, 2)) == "3+2*sqrt2"
    assert str(OctileCost(4, 0)) == "4"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"start": (5, 0)}, "outside"),
        ({"goal": (1, 1)}, "wall"),
        ({"connectivity": 6}, "connectivity"),
        ({"backend": "gpu"}, "unknown backend"),
        ({"max_expansions": -3}, "max_expansions"),
        ({"time_limit": -0.5}, "time_limit"),
        ({"time_limit": float("nan")}, "time_limit"),
        ({"time_limit": 1e300}, "time_limit"),
    ],
)
def test_misuse_raises_problem_error(kwargs: dict, message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        grid_astar(
            BENT,
            kwargs.get("start", (0, 0)),
            kwargs.get("goal", (3, 2)),
            connectivity=kwargs.get("connectivity", 8),
            backend=kwargs.get("backend", "python"),
            max_expansions=kwargs.get("max_expansions"),
            time_limit=kwargs.get("time_limit"),
        )


def assert_valid_path(maze: Maze, path: tuple, connectivity: int) -> None:
    for (x0, y0), (x1, y1) in itertools.pairwise(path):
        dx, dy = x1 - x0, y1 - y0
        assert max(abs(dx), abs(dy)) == 1
        assert maze.is_free(x1, y1)
        if dx and dy:
            assert connectivity == 8
            assert maze.is_free(x0 + dx, y0) and maze.is_free(x0, y0 + dy)


def dijkstra(maze: Maze, start: tuple, goal: tuple, connectivity: int) -> float | None:
    """Textbook Dijkstra written independently of the planner."""
    steps = [(0, 1, 1.0), (0, -1, 1.0), (1, 0, 1.0), (-1, 0, 1.0)]
    if connectivity == 8:
        steps += [(dx, dy, SQRT2) for dx in (-1, 1) for dy in (-1, 1)]
    dist = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, (x, y) = heapq.heappop(heap)
        if (x, y) == goal:
            return d
        if d > dist[(x, y)]:
            continue
        for dx, dy, w in steps:
            nxt = (x + dx, y + dy)
            if not maze.is_free(*nxt):
                continue
            if dx and dy and not (maze.is_free(x + dx, y) and maze.is_free(x, y + dy)):
                continue
            if d + w < dist.get(nxt, math.inf):
                dist[nxt] = d + w
                heapq.heappush(heap, (d + w, nxt))
    return None


@st.composite
def grid_cases(draw: st.DrawFn) -> tuple[Maze, tuple, tuple, int]:
    width, height = draw(st.integers(1, 12)), draw(st.integers(1, 12))
    density = draw(st.sampled_from([0.0, 0.2, 0.35]))
    walls = np.random.default_rng(draw(st.integers(0, 2**32 - 1))).random((height, width)) < density
    free = [(x, y) for y in range(height) for x in range(width) if not walls[y, x]] or [(0, 0)]
    walls[free[0][1], free[0][0]] = False
    return (
        Maze(walls),
        draw(st.sampled_from(free)),
        draw(st.sampled_from(free)),
        draw(st.sampled_from([4, 8])),
    )


@settings(max_examples=200, deadline=None)
@given(grid_cases())
def test_grid_astar_equals_dijkstra(case: tuple) -> None:
    maze, start, goal, connectivity = case
    expected = dijkstra(maze, start, goal, connectivity)
    result = grid_astar(maze, start, goal, connectivity=connectivity, backend="python")
    if expected is None:
        assert result.status is PlanStatus.UNSOLVABLE
        return
    assert result.status is PlanStatus.SOLVED
    assert result.cost is not None
    assert result.cost.value == pytest.approx(expected, abs=1e-9)
    assert result.path[0] == start and result.path[-1] == goal
    assert_valid_path(maze, result.path, connectivity)
    if connectivity == 4:
        assert result.cost.diagonal == 0


@NUMBA
@settings(max_examples=200, deadline=None)
@given(grid_cases())
def test_numba_grid_agrees_with_the_reference(case: tuple) -> None:
    maze, start, goal, connectivity = case
    reference = grid_astar(maze, start, goal, connectivity=connectivity, backend="python")
    compiled = grid_astar(maze, start, goal, connectivity=connectivity, backend="numba")
    assert compiled.status is reference.status
    assert compiled.cost == reference.cost
    assert compiled.path == reference.path
    assert compiled.expansions == reference.expansions
