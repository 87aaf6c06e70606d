"""Reachability on a team's maze: 4-connected components and step distances.

A robot with healthy wheels reaches exactly the cells of its own 4-connected component (a turn
in place needs only its own cell), so scenario checks, random scenarios and the team engine's
drive decisions all use these two functions.
"""

from __future__ import annotations

from collections import deque

from selfrepair.errors import InputError
from selfrepair.geometry import Cell
from selfrepair.world.maze import Maze

__all__ = ["components", "grid_distances", "largest_area"]


def components(maze: Maze) -> dict[Cell, int]:
    """The 4-connected component number of every free cell (numbered in the maze's cell order)."""
    label: dict[Cell, int] = {}
    number = 0
    for cell in maze.free_cells():
        if cell in label:
            continue
        for reached in grid_distances(maze, cell):
            label[reached] = number
        number += 1
    return label


def grid_distances(
    maze: Maze, start: Cell, blocked: frozenset[Cell] = frozenset()
) -> dict[Cell, int]:
    """4-connected step distances from ``start`` over free cells not in ``blocked``."""
    distances = {start: 0}
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for nxt in ((x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y)):
            if nxt not in distances and nxt not in blocked and maze.is_free(*nxt):
                distances[nxt] = distances[(x, y)] + 1
                queue.append(nxt)
    return distances


def largest_area(maze: Maze) -> list[Cell]:
    """The cells of the maze's largest 4-connected component, sorted (the first such component
    in cell order on a tie)."""
    comp = components(maze)
    if not comp:
        raise InputError(f"maze {maze.name or '?'} has no free cell")
    sizes: dict[int, int] = {}
    for number in comp.values():
        sizes[number] = sizes.get(number, 0) + 1
    best = max(sorted(sizes), key=lambda k: sizes[k])
    return sorted(c for c, n in comp.items() if n == best)
