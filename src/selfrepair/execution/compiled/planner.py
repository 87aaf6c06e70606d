"""Replanning inside the compiled mission loop: the lattice planner's numba kernel
(:func:`selfrepair.search._kernels._lattice`) called from the mission kernel, so a replan there is
one call, as a table hit is.

:func:`kernel_planner` makes, per (mission map, goal, known faults, cost settings), the arrays
:func:`selfrepair.search._kernels.plan_lattice` makes before it searches (the same motion table,
heuristic bound, penalties and neighbourhood masks, from the same cached helpers), and
:func:`plan_in_kernel` runs the same search over them: the same pops in the same order, so the
same plan and the same number of expansions as :func:`selfrepair.search.lattice.plan` with the
compiled backend (the property test of the compiled loop compares whole missions).

A problem the kernel does not take (an objective term, a python backend, a problem too large for
its integers) has no kernel planner: the mission kernel then asks the driver, which calls the
mission's planner in Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.execution.result import MissionSpec
from selfrepair.jit import no_refcount
from selfrepair.repair.lookups import action_index
from selfrepair.search import _kernels as kn
from selfrepair.search.backend import use_numba
from selfrepair.search.heuristics import heuristic_bound
from selfrepair.search.lattice import _setup, cost_scale
from selfrepair.search.problem import PlanningProblem

__all__ = ["KernelPlanner", "cached_planner", "kernel_planner", "plan_in_kernel"]

Int64s = npt.NDArray[np.int64]


@dataclass(frozen=True, slots=True, eq=False)
class KernelPlanner:
    """The lattice search's inputs for one (map, goal, known faults, cost settings): the motion
    table ``mt``, heuristic distances ``hdist``, penalties ``pen``, neighbourhood masks ``nbr``,
    ``par = (rnum, rden, wmul, goal cell, goal heading, shift, padded width)`` and the domain's
    action index of each planning move (``moves``); ``states`` the lattice's size."""

    mt: Int64s
    hdist: npt.NDArray[np.int32]
    pen: Int64s
    nbr: npt.NDArray[np.uint16]
    par: Int64s
    moves: Int64s
    states: int


def _key(spec: MissionSpec, known: frozenset[Any]) -> tuple[Any, ...]:
    return (spec.maze, spec.goal, spec.goal_heading, known, Fraction(spec.clearance_weight),
            spec.clearance_radius, spec.heuristic, spec.backend, spec.domain)  # fmt: skip


def kernel_planner(spec: MissionSpec, known: frozenset[Any]) -> KernelPlanner | None:
    """The :class:`KernelPlanner` of ``spec``'s replans under ``known`` (made on first use and
    kept, emptied by a cold run like the planner's own caches), or ``None`` when the kernel does
    not take them (see the module docstring)."""
    return _PLANNERS.get(_key(spec, known), lambda: _make(spec, known))


def cached_planner(spec: MissionSpec, known: frozenset[Any]) -> KernelPlanner | None:
    """:func:`kernel_planner` if it is made already, else ``None`` (without making it: a cold
    run's first replan pays for it, as the Python planner's does)."""
    key = _key(spec, known)
    return _PLANNERS.get(key, lambda: None) if key in _PLANNERS else None


def _make(spec: MissionSpec, known: frozenset[Any]) -> KernelPlanner | None:
    domain = spec.domain
    if spec.objective is not None or not use_numba(spec.backend, domain):
        return None
    weight = Fraction(spec.clearance_weight)
    maze = spec.maze
    problem = PlanningProblem(maze, spec.start, spec.goal, spec.goal_heading, known, weight,
                              spec.clearance_radius, domain)  # fmt: skip
    setup = _setup(domain, known)
    moves = setup.actions
    bound, largest = heuristic_bound(problem, spec.heuristic, moves, setup.rate, "numba")
    scale = cost_scale(domain, weight)
    height, width = maze.walls.shape
    pw = width + 2
    n_states = 4 * (height + 2) * pw
    wmul = weight.numerator * (scale // weight.denominator)
    pen, pen_max = kn._padded_penalty(maze, spec.clearance_radius) if wmul else (kn._NO_PENALTY, 0)
    hdist = bound.padded.ravel().view()
    rnum, rden = bound.rate.numerator * scale, bound.rate.denominator
    common = math.gcd(rnum, rden)
    rnum, rden = rnum // common, rden // common
    try:
        motion = kn._cached(
            kn._MOTIONS, (domain, (domain, known), pw, scale),
            lambda: kn._motion(domain, moves, pw, scale),
        )  # fmt: skip
        mt = motion.table
        hmax = (int(hdist.max(initial=0)) if largest is None else largest) * rnum // rden
        shift = hmax.bit_length()
        kn._check_int64(motion.dur_max, mt.shape[2] - kn._SW, pen_max, wmul, hmax, shift,
                        n_states, len(moves))  # fmt: skip
    except OverflowError:
        return None
    goal_cell = (spec.goal[1] + 1) * pw + spec.goal[0] + 1
    goal_head = -1 if spec.goal_heading is None else int(spec.goal_heading)
    of = action_index(domain).of
    arrays = (
        mt,
        hdist,
        np.asarray(pen, dtype=np.int64),
        kn._neighbourhoods(maze),
        np.array([rnum, rden, wmul, goal_cell, goal_head, shift, pw], dtype=np.int64),
        np.array([of(a) for a in motion.moves.tolist()], dtype=np.int64),
    )
    for array in arrays:  # read-only, whatever the helpers hand over: one kernel signature
        array.setflags(write=False)
    return KernelPlanner(*arrays, n_states)


_PLANNERS: BoundedCache[tuple[Any, ...], KernelPlanner | None] = BoundedCache(
    "compiled-loop planners", 64, kind=CacheKind.PLAN, per_map=True
)


@no_refcount
def plan_in_kernel(
    mt: Any, hdist: Any, pen: Any, nbr: Any, ppar: Any, moves: Any, rec: Any, gen: Any,
    heap: Any, scal: Any, par: Any, extra: Any, x: int, y: int, h: int, budget: int, out: Any,
    off: int,
) -> Any:  # fmt: skip
    """Plan from ``(x, y, h)`` (see the module docstring); the actions' indices go to
    ``out[off:]`` when they fit. Returns ``(status, length, expansions)``: status 0 solved, 1
    unsolvable, 2 budget spent, 3 solved but ``out`` too short for its ``length`` actions, 4 the
    heap is full (the caller grows it and plans again). ``rec`` and ``gen`` are the search
    records and their generation (reused from plan to plan, as the planner's own scratch is);
    ``scal``, ``par`` and ``extra`` scratch of 4, 9 and 6 words (``extra``: the lattice
    kernel's step-term parameters, all 0: no term, so it also stands in for the term's arrays,
    which the kernel then never reads). Allocates nothing (compiled
    without reference counting, like the search kernels)."""
    rnum, rden, wmul, goal_cell, goal_head, shift, pw = (
        ppar[0], ppar[1], ppar[2], ppar[3], ppar[4], ppar[5], ppar[6],
    )  # fmt: skip
    start_cell = (y + 1) * pw + x + 1
    start = 4 * start_cell + h
    if start_cell == goal_cell and (goal_head < 0 or h == goal_head):
        return 0, 0, 0
    if hdist[start_cell] < 0:
        return 1, 0, 0
    opened = 2 * gen[0] + 1
    if opened + 1 > kn._LATTICE_MARK_MAX:
        rec[:, kn._WORD] = 0
        gen[0] = 0
        opened = 1
    gen[0] += 1
    h0 = hdist[start_cell] * rnum // rden
    rec[start, kn._G] = 0
    rec[start, kn._WORD] = opened << kn._MOVE_BITS
    rec[start, kn._SLOT] = 0
    heap[kn._BASE, 0] = (h0 << shift) | h0
    heap[kn._BASE, 1] = start
    for i in range(1, 4):
        heap[kn._BASE + i, 0] = kn._NO_KEY
    scal[0], scal[1], scal[2], scal[3] = 1, 0, 0, -1
    par[0], par[1], par[2], par[3], par[4] = rnum, rden, wmul, goal_cell, goal_head
    par[5], par[6], par[7], par[8] = budget, opened, shift, 0
    code = kn._lattice(
        nbr, pen, hdist, mt, par, rec, heap, scal, extra, extra, extra, extra, extra, extra, extra,
        extra, extra, extra, extra, extra, extra,
    )  # fmt: skip
    expansions = scal[kn._EXPANSIONS]
    if code == kn._GROW:
        return 4, 0, expansions
    if code == kn._UNSOLVABLE:
        return 1, 0, expansions
    if code != kn._SOLVED:
        return 2, 0, expansions
    goal = scal[kn._FOUND]
    n = 0
    s = goal
    while s != start:  # the length first (as _walk_lattice walks), then the moves from the end
        pm = rec[s, kn._WORD] & kn._MOVE_MASK
        head = pm >> 8
        s = 4 * ((s >> 2) - mt[head, pm & 255, kn._DCELL]) + head
        n += 1
    if off + n > out.shape[0]:
        return 3, n, expansions
    s = goal
    for i in range(n - 1, -1, -1):
        pm = rec[s, kn._WORD] & kn._MOVE_MASK
        head = pm >> 8
        k = pm & 255
        out[off + i] = moves[k]
        s = 4 * ((s >> 2) - mt[head, k, kn._DCELL]) + head
    return 0, n, expansions


def new_records(states: int) -> tuple[Int64s, Int64s, Int64s, Int64s, Int64s, Int64s]:
    """Search records for ``states`` lattice states, their generation, a first heap, and the
    kernel's scratch words (see :func:`plan_in_kernel`)."""
    rec = np.zeros((states, 3), dtype=np.int64)
    heap = np.empty((kn._FIRST_HEAP, 2), dtype=np.int64)
    scratch = (np.zeros(4, dtype=np.int64), np.zeros(9, dtype=np.int64),
               np.zeros(6, dtype=np.int64))  # fmt: skip
    return rec, np.zeros(1, dtype=np.int64), heap, *scratch
