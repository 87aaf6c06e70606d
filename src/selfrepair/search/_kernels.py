"""Numba kernels for the planners: the same A* as :func:`selfrepair.search.astar.astar`, compiled.

Optional: without numba, :data:`NUMBA` is false and the ``"auto"`` backend uses pure Python.
Everything that defines the problem (motion geometry, durations, heuristic bounds) is computed in
Python from the robot's :class:`~selfrepair.robots.domain.Domain` and passed in as integer tables;
the kernels only search.

Layout: the grid is padded by one wall cell on every side and flattened, so a cell is one integer
``p = (y + 1) * (width + 2) + (x + 1)`` and every motion is a fixed integer offset; a lattice
state is ``4 * p + heading``. The open list is an indexed 4-ary heap keyed ``(f, h, counter)``
per state (decrease-key instead of lazy deletion). It pops exactly the entries that the
lazy-deletion heap of :func:`selfrepair.search.astar.astar` pops, in the same order, so both
backends return the same plan.

Kernels are resumable: all search state lives in arrays, and a call stops after a given number of
expansions so that the Python wrapper can look at the clock between calls.
"""

from __future__ import annotations

import threading
import time
from fractions import Fraction
from functools import lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import Domain
from selfrepair.search.astar import PlanStatus
from selfrepair.search.problem import CellBound, PlanningProblem
from selfrepair.world.maze import Maze

try:
    from numba import njit

    NUMBA = True
except ImportError:  # pragma: no cover - depends on the environment
    NUMBA = False

    def njit(*args: Any, **kwargs: Any) -> Any:  # type: ignore[no-redef]
        """Stand-in so the module imports without numba (its kernels are then never called)."""
        if args and callable(args[0]):
            return args[0]
        return lambda f: f


__all__ = ["CHUNK", "NUMBA", "bfs_padded", "grid_search", "plan_lattice"]

CHUNK = 1 << 15
"""Expansions per kernel call when a time limit is set (between two looks at the clock)."""

_PAUSED, _SOLVED, _UNSOLVABLE = 0, 1, 2
_SIZE, _COUNTER, _EXPANSIONS, _FOUND = 0, 1, 2, 3


# --- indexed 4-ary heap ----------------------------------------------------------------------
# Slot arrays hn (node), hf, hh, hc (keys f, h, counter) in heap order; pos[node] is the slot.
# Children of slot i are 4i+1 .. 4i+4: half the levels of a binary heap, so fewer cache misses.


@njit(cache=True, inline="always")
def _less(f1: Any, h1: Any, c1: int, f2: Any, h2: Any, c2: int) -> bool:
    if f1 != f2:
        return bool(f1 < f2)
    if h1 != h2:
        return bool(h1 < h2)
    return c1 < c2


@njit(cache=True)
def _sift_up(
    hn: Any, hf: Any, hh: Any, hc: Any, pos: Any, i: int, node: int, f: Any, h: Any, c: int
) -> None:
    while i > 0:
        up = (i - 1) >> 2
        if not _less(f, h, c, hf[up], hh[up], hc[up]):
            break
        moved = hn[up]
        hn[i], hf[i], hh[i], hc[i] = moved, hf[up], hh[up], hc[up]
        pos[moved] = i
        i = up
    hn[i], hf[i], hh[i], hc[i] = node, f, h, c
    pos[node] = i


@njit(cache=True, inline="always")
def _push(
    flag: Any,
    hn: Any,
    hf: Any,
    hh: Any,
    hc: Any,
    pos: Any,
    size: int,
    node: int,
    f: Any,
    h: Any,
    c: int,
) -> int:
    """Insert ``node`` (flag 0 to 1, open) or lower its key if open; returns the new size."""
    if flag[node] == 0:
        flag[node] = 1
        _sift_up(hn, hf, hh, hc, pos, size, node, f, h, c)
        return size + 1
    _sift_up(hn, hf, hh, hc, pos, pos[node], node, f, h, c)
    return size


@njit(cache=True, inline="always")
def _pop(hn: Any, hf: Any, hh: Any, hc: Any, pos: Any, size: int) -> int:
    """Remove and return the minimum node; ``size`` is the heap size before the pop."""
    top = hn[0]
    size -= 1
    if size > 0:
        node, f, h, c = hn[size], hf[size], hh[size], hc[size]
        i = 0
        while True:
            first = 4 * i + 1
            if first >= size:
                break
            child = first
            for other in range(first + 1, min(first + 4, size)):
                if _less(hf[other], hh[other], hc[other], hf[child], hh[child], hc[child]):
                    child = other
            if not _less(hf[child], hh[child], hc[child], f, h, c):
                break
            moved = hn[child]
            hn[i], hf[i], hh[i], hc[i] = moved, hf[child], hh[child], hc[child]
            pos[moved] = i
            i = child
        hn[i], hf[i], hh[i], hc[i] = node, f, h, c
        pos[node] = i
    return int(top)


# --- breadth-first distances ---------------------------------------------------------------


@njit(cache=True)
def _bfs(pw: int, goal: int, dist: Any, queue: Any) -> None:
    """Breadth-first search on ``dist``: -1 marks an unvisited free cell, -2 a wall."""
    dist[goal] = 0
    queue[0] = goal
    head, tail = 0, 1
    while head < tail:
        p = queue[head]
        head += 1
        d = dist[p] + 1
        q = p - pw
        if dist[q] == -1:
            dist[q] = d
            queue[tail] = q
            tail += 1
        q = p + 1
        if dist[q] == -1:
            dist[q] = d
            queue[tail] = q
            tail += 1
        q = p + pw
        if dist[q] == -1:
            dist[q] = d
            queue[tail] = q
            tail += 1
        q = p - 1
        if dist[q] == -1:
            dist[q] = d
            queue[tail] = q
            tail += 1


@lru_cache(maxsize=16)
def _bfs_template(maze: Maze) -> npt.NDArray[np.int32]:
    """-1 on free cells and -2 on walls and the border: the starting state of :func:`_bfs`."""
    out = np.where(_padded_free(maze) != 0, -1, -2).astype(np.int32)
    out.setflags(write=False)
    return out


_local = threading.local()


def _buffers(tag: str, n: int, spec: tuple[tuple[str, Any], ...]) -> dict[str, Any]:
    """Scratch arrays of length ``n`` kept per thread and reused across searches.

    Fresh arrays would cost a page fault per touched page on every query, which for the
    million-state lattice of a 512x512 map is as slow as the search itself. Only the last size
    per ``tag`` is kept. Callers must reset what they read before writing (the ``flag`` arrays).
    """
    cache = getattr(_local, "buffers", None)
    if cache is None:
        cache = _local.buffers = {}
    entry = cache.get(tag)
    if entry is None or entry[0] != n:
        entry = (n, {name: np.empty(n, dtype=dtype) for name, dtype in spec})
        cache[tag] = entry
    return entry[1]


@lru_cache(maxsize=16)
def _padded_free(maze: Maze) -> npt.NDArray[np.uint8]:
    free = np.zeros((maze.height + 2, maze.width + 2), dtype=np.uint8)
    free[1:-1, 1:-1] = ~maze.walls
    out = free.ravel()
    out.setflags(write=False)
    return out


@lru_cache(maxsize=16)
def _neighbourhoods(maze: Maze) -> npt.NDArray[np.uint16]:
    """Per padded cell: bit ``3 * (dy + 1) + (dx + 1)`` is set when the cell ``(dx, dy)`` away is
    free."""
    free = np.zeros((maze.height + 4, maze.width + 4), dtype=np.uint16)
    free[2:-2, 2:-2] = ~maze.walls
    h, w = maze.height + 2, maze.width + 2
    mask = np.zeros((h, w), dtype=np.uint16)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            bit = np.uint16(1 << (3 * (dy + 1) + dx + 1))
            mask |= free[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w] * bit
    out = mask.ravel()
    out.setflags(write=False)
    return out


def bfs_padded(maze: Maze, goal: Cell) -> npt.NDArray[np.int32]:
    """4-connected BFS distances to ``goal``, shape ``(height + 2, width + 2)``.

    Negative means unreachable: -1 for a free cell cut off from the goal, -2 for a wall or the
    border.
    """
    pw = maze.width + 2
    dist = _bfs_template(maze).copy()
    queue = _buffers("bfs", dist.size, (("queue", np.int32),))["queue"]
    _bfs(pw, (goal[1] + 1) * pw + goal[0] + 1, dist, queue)
    return dist.reshape(maze.height + 2, pw)


# --- robot lattice -------------------------------------------------------------------------


@njit(cache=True)
def _lattice(
    nbr: Any, pen: Any, hdist: Any, rnum: int, rden: int, wmul: int,
    dcell: Any, nhead: Any, dur: Any, need: Any, nsw: Any, sw: Any,
    goal_cell: int, goal_head: int, limit: int,
    flag: Any, g: Any, parent: Any, pmove: Any, pos: Any,
    hn: Any, hf: Any, hh: Any, hc: Any, scal: Any,
) -> int:  # fmt: skip
    size, counter, expansions = scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS]
    nmoves = dcell.shape[1]
    status = _UNSOLVABLE
    while size > 0:
        if expansions >= limit:
            status = _PAUSED
            break
        s = _pop(hn, hf, hh, hc, pos, size)
        size -= 1
        flag[s] = 2
        expansions += 1
        cell = s >> 2
        head = s & 3
        if cell == goal_cell and (goal_head < 0 or head == goal_head):
            scal[_FOUND] = s
            status = _SOLVED
            break
        gs = g[s]
        around = nbr[cell]
        for k in range(nmoves):
            mask = need[head, k]
            if around & mask != mask:
                continue
            nc = cell + dcell[head, k]
            ns = 4 * nc + nhead[head, k]
            state = flag[ns]
            if state == 2:
                continue
            gn = gs + dur[head, k]
            if wmul:
                penalty = 0
                for j in range(nsw[head, k]):
                    penalty += pen[cell + sw[head, k, j]]
                gn += wmul * penalty
            if state == 1 and gn >= g[ns]:
                continue
            d = hdist[nc]
            if d < 0:
                continue
            hv = d * rnum if rden == 1 else d * rnum // rden
            counter += 1
            g[ns] = gn
            parent[ns] = s
            pmove[ns] = k
            size = _push(flag, hn, hf, hh, hc, pos, size, ns, gn + hv, hv, counter)
    scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS] = size, counter, expansions
    return status


@njit(cache=True)
def _walk_back(parent: Any, start: int, goal: int) -> Any:
    n = 1
    s = goal
    while s != start:
        s = parent[s]
        n += 1
    out = np.empty(n, dtype=np.int64)
    s = goal
    for i in range(n - 1, -1, -1):
        out[i] = s
        if i:
            s = parent[s]
    return out


@lru_cache(maxsize=64)
def _motion_tables(
    domain: Domain[Any, Any], moves: tuple[Any, ...], pw: int, scale: int
) -> tuple[npt.NDArray[np.int64], ...]:
    """Integer tables for every heading and action, derived with ``domain.step``.

    ``dcell``/``nhead``: end-cell offset and end heading; ``dur``: scaled duration; ``need``: the
    neighbourhood bits of the footprint cells; ``nsw``/``sw``: the footprint cells as offsets.
    Raises :class:`OverflowError` for an action that reaches beyond the 3x3 neighbourhood.
    """
    n = len(moves)
    dcell = np.zeros((4, n), dtype=np.int64)
    nhead = np.zeros((4, n), dtype=np.int64)
    dur = np.zeros((4, n), dtype=np.int64)
    need = np.zeros((4, n), dtype=np.int64)
    nsw = np.zeros((4, n), dtype=np.int64)
    width = max([len(domain.footprint(Pose(0, 0, h), a)) for a in moves for h in Heading] or [1])
    sw = np.zeros((4, n, width), dtype=np.int64)
    for heading in Heading:
        for k, action in enumerate(moves):
            end, swept, duration = domain.step(Pose(0, 0, heading), action)
            if max(abs(end.x), abs(end.y)) > 1:
                raise OverflowError("an action moves beyond the 3x3 neighbourhood")
            dcell[heading, k] = end.y * pw + end.x
            nhead[heading, k] = int(end.heading)
            scaled = Fraction(duration) * scale
            if scaled.denominator != 1:
                raise OverflowError(f"duration {duration} is not a multiple of 1/{scale}")
            dur[heading, k] = scaled.numerator
            nsw[heading, k] = len(swept)
            for j, (x, y) in enumerate(swept):
                if max(abs(x), abs(y)) > 1:
                    raise OverflowError("an action sweeps beyond the 3x3 neighbourhood")
                sw[heading, k, j] = y * pw + x
                need[heading, k] |= 1 << (3 * (y + 1) + x + 1)
    tables = (dcell, nhead, dur, need, nsw, sw)
    for table in tables:
        table.setflags(write=False)
    return tables


@lru_cache(maxsize=16)
def _padded_penalty(maze: Maze, radius: int) -> npt.NDArray[np.int64]:
    from selfrepair.world.maze import clearance_penalties

    padded = np.full((maze.height + 2, maze.width + 2), radius, dtype=np.int64)
    padded[1:-1, 1:-1] = clearance_penalties(maze, radius)
    out = padded.ravel()
    out.setflags(write=False)
    return out


_NO_PENALTY = np.zeros(1, dtype=np.int64)
_NO_PENALTY.setflags(write=False)

_LATTICE_BUFFERS = (
    ("flag", np.uint8), ("g", np.int64), ("parent", np.int32), ("pmove", np.int8),
    ("pos", np.int32), ("hn", np.int32), ("hf", np.int64), ("hh", np.int64), ("hc", np.int64),
)  # fmt: skip


def plan_lattice(
    problem: PlanningProblem,
    moves: tuple[Any, ...],
    bound: CellBound,
    scale: int,
    max_expansions: int | None,
    deadline_ns: int | None,
) -> tuple[PlanStatus, tuple[Any, ...], tuple[Pose, ...], int, int]:
    """Run the lattice search over ``moves``; the arguments mean what they mean in
    :mod:`selfrepair.search.lattice`.

    Returns status, actions, poses, the scaled integer cost and the number of expansions. Raises
    :class:`OverflowError` when the problem does not fit the integer kernel (the caller then uses
    the pure-Python search).
    """
    maze = problem.maze
    pw = maze.width + 2
    n_states = 4 * (maze.height + 2) * pw
    weight = Fraction(problem.clearance_weight)
    wmul = weight.numerator * (scale // weight.denominator)
    pen = _padded_penalty(maze, problem.clearance_radius) if wmul else _NO_PENALTY
    hdist = bound.padded.ravel()
    rate = bound.rate * scale
    tables = _motion_tables(problem.domain, moves, pw, scale)
    _check_int64(tables[2], pen, wmul, hdist, rate, n_states)
    start_cell = (problem.start.y + 1) * pw + problem.start.x + 1
    start = 4 * start_cell + int(problem.start.heading)
    goal_cell = (problem.goal[1] + 1) * pw + problem.goal[0] + 1
    goal_head = -1 if problem.goal_heading is None else int(problem.goal_heading)
    if hdist[start_cell] < 0:
        return PlanStatus.UNSOLVABLE, (), (), 0, 0
    buf = _buffers("lattice", n_states, _LATTICE_BUFFERS)
    flag, g, parent, pmove, pos = buf["flag"], buf["g"], buf["parent"], buf["pmove"], buf["pos"]
    hn, hf, hh, hc = buf["hn"], buf["hf"], buf["hh"], buf["hc"]
    flag.fill(0)
    h0 = int(hdist[start_cell]) * rate.numerator // rate.denominator
    g[start], flag[start], pos[start] = 0, 1, 0
    hn[0], hf[0], hh[0], hc[0] = start, h0, h0, 0
    scal = np.array([1, 0, 0, -1], dtype=np.int64)
    nbr = _neighbourhoods(maze)

    def run(limit: int) -> int:
        kernel: Any = _lattice  # a numba dispatcher: typed loosely
        return int(
            kernel(
                nbr, pen, hdist, rate.numerator, rate.denominator, wmul, *tables,
                goal_cell, goal_head, limit,
                flag, g, parent, pmove, pos, hn, hf, hh, hc, scal,
            )
        )  # fmt: skip

    status = _drive(run, scal, max_expansions, deadline_ns)
    expansions = int(scal[_EXPANSIONS])
    if status is not PlanStatus.SOLVED:
        return status, (), (), 0, expansions
    path = _walk_back(parent, start, int(scal[_FOUND]))
    actions = tuple(moves[k] for k in pmove[path[1:]].tolist())
    cells, headings = (path >> 2) - pw - 1, (path & 3).tolist()
    xs, ys = (cells % pw).tolist(), (cells // pw).tolist()
    heading_of = tuple(Heading)
    poses = tuple(Pose(x, y, heading_of[h]) for x, y, h in zip(xs, ys, headings, strict=True))
    return status, actions, poses, int(g[path[-1]]), expansions


def _check_int64(
    dur: npt.NDArray[np.int64],
    pen: npt.NDArray[np.int64],
    wmul: int,
    hdist: npt.NDArray[np.int32],
    rate: Fraction,
    n_states: int,
) -> None:
    """Refuse problems whose scaled costs could overflow int64 or whose states overflow int32."""
    step_max = int(dur.max(initial=0)) + wmul * 4 * int(pen.max(initial=0))
    bound = step_max * n_states + int(hdist.max(initial=0)) * rate.numerator
    if bound >= 1 << 62 or wmul >= 1 << 62 or n_states >= 1 << 31:
        raise OverflowError("the problem is too large for the integer kernel")


def _drive(
    run: Any, scal: npt.NDArray[np.int64], max_expansions: int | None, deadline_ns: int | None
) -> PlanStatus:
    """Call a resumable kernel until it finishes, the node budget is spent or time is up."""
    budget = min(1 << 62, (1 << 62) if max_expansions is None else max_expansions)
    while True:
        limit = budget
        if deadline_ns is not None:
            if time.perf_counter_ns() >= deadline_ns:
                return PlanStatus.BUDGET_EXHAUSTED
            limit = min(budget, int(scal[_EXPANSIONS]) + CHUNK)
        code = run(limit)
        if code == _SOLVED:
            return PlanStatus.SOLVED
        if code == _UNSOLVABLE:
            return PlanStatus.UNSOLVABLE
        if int(scal[_EXPANSIONS]) >= budget:
            return PlanStatus.BUDGET_EXHAUSTED


# --- plain grid ----------------------------------------------------------------------------


@njit(cache=True)
def _grid(
    free: Any, pw: int, diagonal: bool, goal: int, limit: int,
    flag: Any, g: Any, parent: Any, pos: Any, hn: Any, hf: Any, hh: Any, hc: Any, scal: Any,
) -> int:  # fmt: skip
    size, counter, expansions = scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS]
    gx = goal % pw
    gy = goal // pw
    nmoves = 8 if diagonal else 4
    sqrt2 = np.sqrt(2.0)
    status = _UNSOLVABLE
    while size > 0:
        if expansions >= limit:
            status = _PAUSED
            break
        p = _pop(hn, hf, hh, hc, pos, size)
        size -= 1
        flag[p] = 2
        expansions += 1
        if p == goal:
            scal[_FOUND] = p
            status = _SOLVED
            break
        gp = g[p]
        ex = p % pw - gx  # offset of p from the goal; a neighbour adds (dx, dy)
        ey = p // pw - gy
        north, east, south, west = free[p - pw], free[p + 1], free[p + pw], free[p - 1]
        for k in range(nmoves):
            # N, E, S, W, then NE, SE, SW, NW (a diagonal needs both orthogonal cells free)
            if k == 0:
                ok, q, step, dx, dy = north, p - pw, 1.0, 0, -1
            elif k == 1:
                ok, q, step, dx, dy = east, p + 1, 1.0, 1, 0
            elif k == 2:
                ok, q, step, dx, dy = south, p + pw, 1.0, 0, 1
            elif k == 3:
                ok, q, step, dx, dy = west, p - 1, 1.0, -1, 0
            elif k == 4:
                ok, q, step, dx, dy = north and east, p - pw + 1, sqrt2, 1, -1
            elif k == 5:
                ok, q, step, dx, dy = south and east, p + pw + 1, sqrt2, 1, 1
            elif k == 6:
                ok, q, step, dx, dy = south and west, p + pw - 1, sqrt2, -1, 1
            else:
                ok, q, step, dx, dy = north and west, p - pw - 1, sqrt2, -1, -1
            if not ok or free[q] == 0:
                continue
            state = flag[q]
            if state == 2:
                continue
            gn = gp + step
            if state == 1 and gn >= g[q]:
                continue
            dx = abs(ex + dx)
            dy = abs(ey + dy)
            hv = (dx + dy) + (sqrt2 - 2.0) * min(dx, dy) if diagonal else float(dx + dy)
            counter += 1
            g[q] = gn
            parent[q] = p
            size = _push(flag, hn, hf, hh, hc, pos, size, q, gn + hv, hv, counter)
    scal[_SIZE], scal[_COUNTER], scal[_EXPANSIONS] = size, counter, expansions
    return status


_GRID_BUFFERS = (
    ("flag", np.uint8), ("g", np.float64), ("parent", np.int32), ("pos", np.int32),
    ("hn", np.int32), ("hf", np.float64), ("hh", np.float64), ("hc", np.int64),
)  # fmt: skip


def grid_search(
    maze: Maze,
    start: Cell,
    goal: Cell,
    connectivity: int,
    max_expansions: int | None,
    deadline_ns: int | None,
) -> tuple[PlanStatus, tuple[Cell, ...], int]:
    """Run the plain-grid search; returns status, path (start first) and expansions."""
    from selfrepair.search.problem import grid_heuristic

    pw = maze.width + 2
    n = (maze.height + 2) * pw
    if n >= 1 << 31:
        raise OverflowError("the grid is too large for the int32 kernel")
    free = _padded_free(maze)
    s = (start[1] + 1) * pw + start[0] + 1
    goal_p = (goal[1] + 1) * pw + goal[0] + 1
    buf = _buffers("grid", n, _GRID_BUFFERS)
    flag, g, parent, pos = buf["flag"], buf["g"], buf["parent"], buf["pos"]
    hn, hf, hh, hc = buf["hn"], buf["hf"], buf["hh"], buf["hc"]
    flag.fill(0)
    h0 = grid_heuristic(start, goal, connectivity)
    g[s], flag[s], pos[s] = 0.0, 1, 0
    hn[0], hf[0], hh[0], hc[0] = s, h0, h0, 0
    scal = np.array([1, 0, 0, -1], dtype=np.int64)
    diagonal = connectivity == 8

    def run(limit: int) -> int:
        return int(
            _grid(
                free, pw, diagonal, goal_p, limit,
                flag, g, parent, pos, hn, hf, hh, hc, scal,
            )
        )  # fmt: skip

    status = _drive(run, scal, max_expansions, deadline_ns)
    expansions = int(scal[_EXPANSIONS])
    if status is not PlanStatus.SOLVED:
        return status, (), expansions
    cells = _walk_back(parent, s, goal_p) - pw - 1
    xs, ys = (cells % pw).tolist(), (cells // pw).tolist()
    return status, tuple(zip(xs, ys, strict=True)), expansions
