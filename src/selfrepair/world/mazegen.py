"""Seeded maze generator with a corridor-width parameter: perfect or braided mazes.

Layout: the grid is a lattice of *rooms* of ``corridor x corridor`` free cells separated by walls
one cell thick, with a wall border all round. Room ``(i, j)`` covers the cells
``x = 1 + i * (corridor + 1) ... + corridor - 1`` (and likewise for ``y``). Carving a passage
between two neighbouring rooms frees the ``corridor``-wide gap of wall between them, so every
corridor is exactly ``corridor`` cells wide: every free cell lies in a free ``corridor x corridor``
square, and no ``(corridor + 1) x (corridor + 1)`` square is free, because one always contains a
lattice corner, which stays wall. Columns and rows that do not fit a whole room (when
``width - 1`` or ``height - 1`` is not a multiple of ``corridor + 1``) stay wall at the right and
bottom edge.

A *perfect* maze (``braid = 0``) is a spanning tree of the rooms, drawn with a randomised
depth-first search: exactly one path between any two free cells and many dead ends. *Braiding*
then opens one extra passage at a share ``braid`` of the dead ends, which creates loops (so a
blocked or hard passage has a detour) and removes that many dead ends. Every free cell stays
connected. The same seed and options always give the same maze.
"""

from __future__ import annotations

import numpy as np

from selfrepair.errors import ProblemError
from selfrepair.limits import MAX_CELLS, check_limit
from selfrepair.world.maze import Maze

__all__ = ["generate_maze", "room_grid_shape"]

Room = tuple[int, int]
_DIRECTIONS: tuple[Room, ...] = ((0, -1), (1, 0), (0, 1), (-1, 0))


def room_grid_shape(width: int, height: int, corridor: int) -> tuple[int, int]:
    """How many rooms fit across and down: ``((width - 1) // (corridor + 1), ...)``."""
    return (width - 1) // (corridor + 1), (height - 1) // (corridor + 1)


def generate_maze(
    width: int,
    height: int,
    *,
    corridor: int = 1,
    braid: float = 0.0,
    seed: int | np.random.Generator,
    name: str = "",
    max_cells: int | None = MAX_CELLS,
) -> Maze:
    """A ``width x height`` maze with ``corridor``-wide passages; see the module docstring.

    ``seed`` is an integer or a :class:`numpy.random.Generator` (which is advanced). ``braid`` in
    ``[0, 1]`` is the share of dead ends that get an extra passage. Raises
    :class:`~selfrepair.errors.ProblemError` when the options cannot give a maze with at least
    two rooms, and :class:`~selfrepair.errors.LimitError` before any work when
    ``width * height`` exceeds ``max_cells`` (``None``: no limit).
    """
    check_limit(
        width * height,
        max_cells,
        name="max_cells",
        what="cells",
        detail=f"width {width} x height {height}",
        source="maze generator",
    )
    _check_options(width, height, corridor, braid)
    rng = np.random.default_rng(seed)
    nx, ny = room_grid_shape(width, height, corridor)
    passages = _spanning_tree(nx, ny, rng)
    if braid > 0:
        passages |= _braid_passages(nx, ny, passages, braid, rng)
    return Maze(_carve(width, height, corridor, nx, ny, passages), name=name)


def _check_options(width: int, height: int, corridor: int, braid: float) -> None:
    if corridor < 1:
        raise ProblemError(f"expected a corridor width of at least 1, got {corridor}")
    if not 0.0 <= braid <= 1.0:
        raise ProblemError(f"expected a braid share between 0 and 1, got {braid}")
    nx, ny = room_grid_shape(width, height, corridor)
    if nx < 1 or ny < 1 or nx * ny < 2:
        need = 2 * corridor + 3
        raise ProblemError(
            f"expected a maze of at least {need}x{corridor + 2} or {corridor + 2}x{need} cells "
            f"for corridor width {corridor}, got {width}x{height}"
        )


def _neighbours(room: Room, nx: int, ny: int) -> list[Room]:
    i, j = room
    return [
        (i + di, j + dj) for di, dj in _DIRECTIONS if 0 <= i + di < nx and 0 <= j + dj < ny
    ]


def _edge(a: Room, b: Room) -> frozenset[Room]:
    return frozenset((a, b))


def _spanning_tree(nx: int, ny: int, rng: np.random.Generator) -> set[frozenset[Room]]:
    """A uniformly seeded randomised depth-first search (recursive backtracker), iteratively."""
    start = (int(rng.integers(nx)), int(rng.integers(ny)))
    visited = {start}
    stack = [start]
    passages: set[frozenset[Room]] = set()
    while stack:
        room = stack[-1]
        options = [n for n in _neighbours(room, nx, ny) if n not in visited]
        if not options:
            stack.pop()
            continue
        nxt = options[int(rng.integers(len(options)))]
        passages.add(_edge(room, nxt))
        visited.add(nxt)
        stack.append(nxt)
    return passages


def _braid_passages(
    nx: int, ny: int, passages: set[frozenset[Room]], braid: float, rng: np.random.Generator
) -> set[frozenset[Room]]:
    """Extra passages that open ``round(braid * dead ends)`` of the tree's dead ends."""
    degree: dict[Room, int] = {(i, j): 0 for i in range(nx) for j in range(ny)}
    for edge in passages:
        for room in edge:
            degree[room] += 1
    dead_ends = [room for room, d in sorted(degree.items()) if d == 1]
    order = rng.permutation(len(dead_ends))
    quota = round(braid * len(dead_ends))
    extra: set[frozenset[Room]] = set()
    carved = set(passages)  # every passage so far, tree and extra: one set, updated in place
    opened = 0
    for index in order:
        if opened >= quota:
            break
        room = dead_ends[int(index)]
        if degree[room] != 1:
            continue  # an earlier extra passage already opened it
        closed = [n for n in _neighbours(room, nx, ny) if _edge(room, n) not in carved]
        if not closed:
            continue
        # Prefer joining two dead ends: one passage then removes both.
        paired = [n for n in closed if degree[n] == 1]
        pool = paired or closed
        other = pool[int(rng.integers(len(pool)))]
        extra.add(_edge(room, other))
        carved.add(_edge(room, other))
        degree[room] += 1
        degree[other] += 1
        opened += 1
    return extra


def _carve(
    width: int, height: int, corridor: int, nx: int, ny: int, passages: set[frozenset[Room]]
) -> np.ndarray:
    pitch = corridor + 1
    walls = np.ones((height, width), dtype=bool)
    # the rooms' interiors at once: columns and rows inside one of the nx (ny) rooms
    xs = np.arange(width) - 1
    ys = np.arange(height) - 1
    in_x = (xs >= 0) & (xs < nx * pitch) & (xs % pitch < corridor)
    in_y = (ys >= 0) & (ys < ny * pitch) & (ys % pitch < corridor)
    walls[np.ix_(in_y, in_x)] = False
    for edge in passages:
        (ai, aj), (bi, _) = sorted(edge)
        x0, y0 = 1 + ai * pitch, 1 + aj * pitch
        if bi != ai:  # horizontal neighbours: open the wall column between them
            walls[y0 : y0 + corridor, x0 + corridor] = False
        else:
            walls[y0 + corridor, x0 : x0 + corridor] = False
    return walls
