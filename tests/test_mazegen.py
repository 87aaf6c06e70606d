"""The seeded maze generator: determinism, connectivity, corridor width, perfect vs braided."""

from __future__ import annotations

import hashlib
from collections import deque

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.errors import LimitError, ProblemError
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze, room_grid_shape

options = st.fixed_dictionaries(
    {
        "corridor": st.integers(1, 3),
        "width": st.integers(9, 30),
        "height": st.integers(9, 30),
        "braid": st.sampled_from([0.0, 0.3, 1.0]),
        "seed": st.integers(0, 2**32),
    }
)


def components(maze: Maze) -> int:
    """Number of 4-connected components of free cells."""
    seen: set[tuple[int, int]] = set()
    count = 0
    for cell in maze.free_cells():
        if cell in seen:
            continue
        count += 1
        seen.add(cell)
        queue = deque([cell])
        while queue:
            x, y = queue.popleft()
            for n in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
                if n not in seen and maze.is_free(*n):
                    seen.add(n)
                    queue.append(n)
    return count


def free_square_exists(maze: Maze, size: int) -> np.ndarray:
    """Boolean map: is the ``size x size`` square with top-left corner (x, y) all free?"""
    free = ~maze.walls
    h, w = free.shape
    out = np.zeros((max(h - size + 1, 0), max(w - size + 1, 0)), dtype=bool)
    for y in range(out.shape[0]):
        for x in range(out.shape[1]):
            out[y, x] = free[y : y + size, x : x + size].all()
    return out


def room_edges(maze: Maze, corridor: int) -> int:
    """Open passages between neighbouring rooms (the room graph's edge count)."""
    nx, ny = room_grid_shape(maze.width, maze.height, corridor)
    pitch = corridor + 1
    edges = 0
    for i in range(nx):
        for j in range(ny):
            x0, y0 = 1 + i * pitch, 1 + j * pitch
            if i + 1 < nx and maze.is_free(x0 + corridor, y0):
                edges += 1
            if j + 1 < ny and maze.is_free(x0, y0 + corridor):
                edges += 1
    return edges


@settings(max_examples=40, deadline=None)
@given(options)
def test_same_seed_same_maze(opts: dict) -> None:
    assert generate_maze(**opts) == generate_maze(**opts)
    generator_opts = {**opts, "seed": np.random.default_rng(opts["seed"])}
    assert generate_maze(**generator_opts) == generate_maze(**opts)


def test_different_seeds_differ() -> None:
    mazes = {generate_maze(31, 31, seed=s) for s in range(5)}
    assert len(mazes) == 5


@settings(max_examples=40, deadline=None)
@given(options)
def test_every_free_cell_is_connected_and_border_is_wall(opts: dict) -> None:
    maze = generate_maze(**opts)
    assert (maze.width, maze.height) == (opts["width"], opts["height"])
    assert components(maze) == 1
    walls = maze.walls
    assert walls[0, :].all() and walls[-1, :].all() and walls[:, 0].all() and walls[:, -1].all()


@settings(max_examples=40, deadline=None)
@given(options)
def test_corridors_are_exactly_corridor_wide(opts: dict) -> None:
    maze = generate_maze(**opts)
    c = opts["corridor"]
    squares = free_square_exists(maze, c)
    covered = np.zeros_like(maze.walls)
    for y, x in zip(*np.nonzero(squares), strict=True):
        covered[y : y + c, x : x + c] = True
    assert np.array_equal(covered, ~maze.walls)  # every free cell lies in a free c x c square
    assert not free_square_exists(maze, c + 1).any()  # and no wider opening exists


@settings(max_examples=40, deadline=None)
@given(options)
def test_perfect_maze_is_a_tree_and_braiding_adds_loops(opts: dict) -> None:
    c = opts["corridor"]
    nx, ny = room_grid_shape(opts["width"], opts["height"], c)
    perfect = generate_maze(**{**opts, "braid": 0.0})
    assert room_edges(perfect, c) == nx * ny - 1
    braided = generate_maze(**{**opts, "braid": 1.0})
    if nx >= 2 and ny >= 2:  # a leaf room then has a neighbour it is not joined to
        assert room_edges(braided, c) > room_edges(perfect, c)
    else:  # a single row or column of rooms: the tree is a path and no loop can be added
        assert room_edges(braided, c) == room_edges(perfect, c)
    assert (perfect.walls | ~braided.walls).all()  # braiding only removes walls


def test_full_braid_leaves_no_dead_end_room() -> None:
    maze = generate_maze(41, 41, braid=1.0, seed=3)
    for x, y in maze.free_cells():
        if x % 2 == 1 and y % 2 == 1:  # room cells for corridor 1
            steps = ((1, 0), (-1, 0), (0, 1), (0, -1))
            exits = sum(maze.is_free(x + dx, y + dy) for dx, dy in steps)
            assert exits >= 2, (x, y)


def test_wide_corridors_fill_a_matching_size() -> None:
    maze = generate_maze(25, 25, corridor=2, seed=1)
    assert room_grid_shape(25, 25, 2) == (8, 8)
    assert len(maze.free_cells()) == 8 * 8 * 4 + (8 * 8 - 1) * 2


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"width": 10, "height": 10, "corridor": 0}, "corridor width"),
        ({"width": 10, "height": 10, "braid": 1.5}, "braid share"),
        ({"width": 4, "height": 4}, "at least"),
        ({"width": 3, "height": 3, "corridor": 1}, "at least"),
        ({"width": 8, "height": 8, "corridor": 3}, "at least 9x5"),
    ],
)
def test_bad_options_raise_problem_error(kwargs: dict, message: str) -> None:
    with pytest.raises(ProblemError, match=message):
        generate_maze(**kwargs, seed=0)


def test_a_maze_over_the_cell_limit_is_refused_before_any_work() -> None:
    with pytest.raises(LimitError, match="max-cells"):
        generate_maze(15, 15, seed=0, max_cells=224)
    assert generate_maze(15, 15, seed=0, max_cells=225).width == 15
    # `maze generate --width 1000000000 --height 15` ran 207 s into a MemoryError.
    with pytest.raises(LimitError, match=r"15,000,000,000 \(width 1000000000 x height 15\)"):
        generate_maze(1_000_000_000, 15, seed=0)


# Digests of mazes made by the generator before braiding became linear-time (commit 0e75591):
# speed-ups must give the same maze for the same seed and options.
KNOWN_DIGESTS = [
    (41, 31, 1, 0.0, 3, "327b5743fcdd207e"),
    (41, 31, 1, 0.3, 3, "32eb6b976288913e"),
    (64, 48, 2, 1.0, 11, "dc553c4a64a39930"),
    (101, 77, 3, 0.5, 2024, "3ce7aae3b9ea151b"),
    (256, 256, 1, 0.1, 7, "a0e5d56e0e356ffe"),
]


@pytest.mark.parametrize(("width", "height", "corridor", "braid", "seed", "digest"), KNOWN_DIGESTS)
def test_generator_output_is_unchanged(
    width: int, height: int, corridor: int, braid: float, seed: int, digest: str
) -> None:
    maze = generate_maze(width, height, corridor=corridor, braid=braid, seed=seed)
    assert hashlib.sha256(maze.walls.tobytes()).hexdigest()[:16] == digest
