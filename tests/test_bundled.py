"""The four bundled mazes and their routes: sizes, character, and drivability of every route."""

from __future__ import annotations

from collections import deque
from pathlib import Path

import numpy as np
import pytest

from selfrepair.errors import InputError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import ACTIONS, MotionKind, step
from selfrepair.world import bundled
from selfrepair.world.maze import Maze, clearance_map, save_maze
from selfrepair.world.mazegen import generate_maze

NAMES = bundled.maze_names()


def fewest_actions(maze: Maze, start: Pose, goal: tuple[int, int]) -> int | None:
    """Breadth-first search over poses with the actions of a healthy robot.

    An action is executable when every swept cell is free; the route is done when the robot's cell
    is the goal, whatever its heading. Actions with the same motion have the same effect, so one
    action per motion suffices. Returns the fewest actions, or None when unreachable.
    """
    by_motion = {a.motion: a for a in ACTIONS if a.motion.kind is not MotionKind.WAIT}
    moves = list(by_motion.values())
    dist = {start: 0}
    queue = deque([start])
    while queue:
        pose = queue.popleft()
        if pose.cell == goal:
            return dist[pose]
        for action in moves:
            end, swept, _ = step(pose, action)
            if end not in dist and maze.all_free(swept):
                dist[end] = dist[pose] + 1
                queue.append(end)
    return None


def test_there_are_four_bundled_mazes() -> None:
    assert NAMES == ("narrow-short", "wide-short", "narrow-long", "wide-long")


@pytest.mark.parametrize("name", NAMES)
def test_maze_size_and_name(name: str) -> None:
    maze = bundled.load_bundled(name)
    assert 15 <= maze.width <= 64 and 15 <= maze.height <= 64
    assert maze.name == name
    assert bundled.resolve_maze(name) == maze


@pytest.mark.parametrize("name", NAMES)
def test_corridor_width_matches_the_catalogue(name: str) -> None:
    maze = bundled.load_bundled(name)
    corridor = bundled.describe(name).corridor
    free = ~maze.walls
    # Widest free square anywhere equals the corridor width (checked via the clearance of a
    # free square: a c x c free square exists, a (c+1) x (c+1) one does not).
    def has_square(size: int) -> bool:
        h, w = free.shape
        return any(
            free[y : y + size, x : x + size].all()
            for y in range(h - size + 1)
            for x in range(w - size + 1)
        )

    assert has_square(corridor) and not has_square(corridor + 1)
    assert clearance_map(maze)[free].max() == (corridor + 1) // 2


@pytest.mark.parametrize("name", NAMES)
def test_mazes_are_reproducible_from_the_recorded_command(name: str) -> None:
    header = bundled._data_text(f"{name}.routes").splitlines()[0]
    words = header.split()
    opts = {words[i].lstrip("-"): words[i + 1] for i in range(len(words)) if words[i][:2] == "--"}
    maze = generate_maze(
        int(opts["width"]),
        int(opts["height"]),
        corridor=int(opts["corridor"]),
        braid=float(opts["braid"]),
        seed=int(opts["seed"]),
    )
    assert maze == bundled.load_bundled(name)
    assert int(opts["corridor"]) == bundled.describe(name).corridor


def test_the_set_covers_narrow_wide_short_long_simple_complex() -> None:
    mazes = {n: bundled.load_bundled(n) for n in NAMES}
    corridors = {bundled.describe(n).corridor for n in NAMES}
    assert 1 in corridors and corridors & {2, 3}
    sizes = [m.width * m.height for m in mazes.values()]
    assert max(sizes) >= 8 * min(sizes)
    # Loops: a perfect maze's free cells form a tree of corridors; braided ones have cycles.
    loops = {n: _has_cycle(m, bundled.describe(n).corridor) for n, m in mazes.items()}
    assert loops == {"narrow-short": False, "wide-short": False, "narrow-long": True,
                     "wide-long": True}


def _has_cycle(maze: Maze, corridor: int) -> bool:
    """Whether the room graph (rooms of corridor x corridor cells) has more edges than a tree."""
    pitch = corridor + 1
    nx, ny = (maze.width - 1) // pitch, (maze.height - 1) // pitch
    edges = sum(
        maze.is_free(1 + i * pitch + corridor, 1 + j * pitch) for i in range(nx - 1)
        for j in range(ny)
    ) + sum(
        maze.is_free(1 + i * pitch, 1 + j * pitch + corridor) for i in range(nx)
        for j in range(ny - 1)
    )
    return bool(edges > nx * ny - 1)


@pytest.mark.parametrize("name", NAMES)
def test_four_routes_that_a_healthy_robot_can_drive(name: str) -> None:
    maze = bundled.load_bundled(name)
    routes = bundled.bundled_routes(name)
    assert len(routes) == 4 and len({r.name for r in routes}) == 4
    lengths = []
    for route in routes:
        assert maze.is_free(*route.start.cell) and maze.is_free(*route.goal)
        n = fewest_actions(maze, route.start, route.goal)
        assert n is not None, f"{name} {route.name} is not drivable"
        lengths.append(n)
    assert min(lengths) >= 20  # tens of actions at least
    assert lengths == sorted(lengths)  # routes are listed from short to long


def test_arcs_fit_only_in_wide_mazes() -> None:
    arcs = [a for a in ACTIONS if a.motion.kind is MotionKind.ARC]
    for name in NAMES:
        maze = bundled.load_bundled(name)
        poses = [Pose(x, y, h) for x, y in maze.free_cells() for h in Heading]
        fits = any(maze.all_free(step(p, a)[1]) for p in poses for a in arcs)
        assert fits is (bundled.describe(name).corridor > 1), name


def test_resolve_maze_from_files(tmp_path: Path) -> None:
    maze = generate_maze(15, 15, seed=2)
    path = tmp_path / "mine.maze"
    save_maze(maze, path)
    assert bundled.resolve_maze(str(path)) == maze
    movingai = Path(__file__).parent / "data" / "movingai" / "maze512-4-0.map"
    assert bundled.resolve_maze(str(movingai)).width == 512


def test_unknown_name_lists_the_known_ones() -> None:
    with pytest.raises(InputError) as info:
        bundled.resolve_maze("no-such-maze")
    message = str(info.value)
    assert "no-such-maze" in message
    assert all(n in message for n in NAMES)
    with pytest.raises(InputError, match="narrow-short"):
        bundled.load_bundled("nope")


def test_bundled_data_is_package_data() -> None:
    data = Path(bundled.__file__).parent.parent / "data" / "mazes"
    files = sorted(p.name for p in data.iterdir())
    assert files == sorted([f"{n}.maze" for n in NAMES] + [f"{n}.routes" for n in NAMES])
    assert all(np.array_equal(bundled.load_bundled(n).walls[0], np.ones(
        bundled.load_bundled(n).width, dtype=bool)) for n in NAMES)
