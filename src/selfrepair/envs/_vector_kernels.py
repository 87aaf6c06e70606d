"""The kernels of the vector environment (:mod:`selfrepair.envs.vector`): N robots, one call.

:func:`step_robots` advances every robot of a batch by one command, exactly as
:meth:`FaultyMazeEnv.step <selfrepair.envs.env.FaultyMazeEnv.step>` and the
:class:`~selfrepair.execution.simulator.Simulator` behind it do, over integer arrays that the
vector environment tabulates from the domain (motion from the move table of
:mod:`selfrepair.execution.moves`, availability and blocking faults per fault set from
``Domain.available`` and ``Domain.blocking``); it writes the observations, rewards, flags and
outcome codes into arrays handed in and never allocates. It is plain Python that numba compiles:
:data:`STEP_PYTHON` is the function itself (the reference, and what runs without numba),
:data:`STEP_NUMBA` its compiled twin (``None`` without numba); a test runs both on the same
batches and compares every array.

Intermittent faults draw at every step from ``numpy.random.default_rng([seed, event, step])``
(:mod:`selfrepair.execution.faults`). :func:`intermittent_draws_numpy` asks numpy for exactly
those draws; :func:`intermittent_draws_numba` computes the same numbers in the kernel with the
compiled mission loop's draw (:mod:`selfrepair.execution.compiled.draws`: numpy's
``SeedSequence`` mixing and one output of its ``PCG64`` generator), turned into a double as
``Generator.random`` does. A property test checks them against numpy.

Layout. Per robot, one row of ``state`` (int64, the ``_X`` .. ``_SEED`` columns below), its known
faults as a bit mask over ``domain.faults`` (uint64), its elapsed ticks (float64, summed in the
single environment's order so the floats agree bit for bit) and ``current``: the id of the fault
set active at the robot's (step, time), which holds until the robot's clock moves. Per robot and
schedule event, one row of ``events`` (the ``_BIT`` .. ``_TICK`` columns; times already in the
event's clock, ticks as time units) and its probability in ``chance``; ``subsets[r, m]`` is the
fault-set id of the events in bit mask ``m``. Per fault-set id, ``set_bits`` (the faults as a bit
mask), ``avail[id, a]`` (whether action ``a`` is available) and ``blocking[id, a]`` (the faults
that forbid it on their own, as a mask). The maze cells of every robot live in one flat byte
buffer ``grid`` (1 free, 0 wall, padded with walls at least as wide as the view radius and the
robot's reach); cell ``(x, y)`` of robot ``r`` is ``grid[state[r, _BASE] + y * state[r, _STRIDE]
+ x]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.execution.compiled.draws import draw53
from selfrepair.jit import NUMBA, njit

__all__ = [
    "NUMBA",
    "OUTCOME_NAMES",
    "STEP_NUMBA",
    "STEP_PYTHON",
    "intermittent_draws_numba",
    "intermittent_draws_numpy",
    "uniform_numba",
]

# state columns (one int64 row per robot)
_X, _Y, _HEAD, _GX, _GY, _STEPS, _SIM, _UNITS, _LIMIT, _BASE, _STRIDE, _SENSES, _PENDING = range(13)
_EVENTS, _SEED, _HIDDEN = 13, 14, 15
STATE_COLUMNS = 16
# event columns (one int64 row per robot and schedule event)
_BIT, _AT, _END, _KIND, _TICK = range(5)
EVENT_COLUMNS = 5
PERMANENT, TRANSIENT, INTERMITTENT = 0, 1, 2
# move columns per action and heading
_DX, _DY, _NH, _UNITS_OF = range(4)
# outcome codes
RESET, MOVED, FAILED, COLLISION, BUMPED = 0, 1, 2, 3, 4
OUTCOME_NAMES = ("", "moved", "failed-attempt", "collision", "bumped")
"""The single environment's ``info["outcome"]`` text of each outcome code (0 is a reset)."""
# penalties
_FAULT_PENALTY, _BLOCKED_PENALTY, _GOAL_BONUS, _FAILED_TICKS = range(4)

Array = npt.NDArray[Any]


def _step_robots(
    which: Array,
    actions: Array,
    state: Array,
    known: Array,
    elapsed: Array,
    current: Array,
    events: Array,
    chance: Array,
    draws: Array,
    subsets: Array,
    set_bits: Array,
    avail: Array,
    blocking: Array,
    effective: Array,
    moves: Array,
    durations: Array,
    footprints: Array,
    grid: Array,
    terms: Array,
    radius: int,
    failed_units: int,
    window: Array,
    heading: Array,
    goal: Array,
    fault_flags: Array,
    reward: Array,
    terminated: Array,
    truncated: Array,
    outcome: Array,
) -> None:
    """Advance robots ``which`` (indices) by one command each, or, for a robot whose
    ``_PENDING`` flag is set (just reset by the caller), observe it without a command (outcome
    ``RESET``; ``reward``, ``terminated`` and ``truncated`` are then not written). ``terms`` holds
    the fault penalty, blocked penalty, goal bonus and a failed attempt's ticks (floats);
    ``draws[r, j]`` the intermittent draw of event ``j`` at the robot's next step. See the module
    docstring for the layout.

    The observation arrays (``window``, ``heading``, ``goal``, ``fault_flags``) persist from one
    call to the next: a robot's window is rewritten only when its cell changed (or it was reset),
    its fault flags only when its known faults did; copying the whole window array is much
    cheaper than writing every window byte by byte."""
    side = 2 * radius + 1
    n_faults = fault_flags.shape[1]
    for k in range(which.shape[0]):
        r = which[k]
        x = state[r, _X]
        y = state[r, _Y]
        was_known = known[r]
        fresh = state[r, _PENDING] != 0
        if fresh:
            state[r, _PENDING] = 0
            outcome[r] = RESET
            known[r] = 0
            moved_clock = True
        else:
            a = actions[r]
            h = state[r, _HEAD]
            sid = current[r]
            gain = 0.0
            hidden = state[r, _HIDDEN] != 0
            if hidden:  # the wheels do what the fault-behaviour model says (-1: the command fails)
                a = effective[sid, a]
            # a failed attempt: with hidden faults, a domain without a model (naming no fault);
            # else a true fault forbids the action
            failed = a < 0 if hidden else avail[sid, a] == 0
            bumped = False
            if not failed:
                base = state[r, _BASE] + y * state[r, _STRIDE] + x
                stride = state[r, _STRIDE]
                free = True
                for c in range(footprints[a, h, 0]):
                    cx = footprints[a, h, 1 + 2 * c]
                    cy = footprints[a, h, 2 + 2 * c]
                    if grid[base + cy * stride + cx] == 0:
                        free = False
                        break
                if free:
                    outcome[r] = MOVED
                    x += moves[a, h, _DX]
                    y += moves[a, h, _DY]
                    state[r, _HEAD] = moves[a, h, _NH]
                    state[r, _UNITS] += moves[a, h, _UNITS_OF]
                    state[r, _SIM] += 1
                    gain = -durations[a]
                    elapsed[r] += durations[a]
                    moved_clock = True
                elif hidden:  # the motion stops at the wall: a bump
                    bumped = True
                else:  # the footprint is not free: refused, nothing changes
                    outcome[r] = COLLISION
                    gain = -terms[_BLOCKED_PENALTY]
                    elapsed[r] += 0.0
                    moved_clock = False
            if failed or bumped:  # one tick passes and the robot stays where it is
                outcome[r] = FAILED if failed else BUMPED
                state[r, _UNITS] += failed_units
                state[r, _SIM] += 1
                gain = -terms[_FAILED_TICKS] - terms[_FAULT_PENALTY if failed else _BLOCKED_PENALTY]
                elapsed[r] += terms[_FAILED_TICKS]
                moved_clock = True
                if failed and not hidden and state[r, _SENSES] == 0:
                    known[r] |= blocking[sid, a]  # the failure names the faults that forbid it
            state[r, _STEPS] += 1
            done = x == state[r, _GX] and y == state[r, _GY]
            if done:
                gain += terms[_GOAL_BONUS]
            reward[r] = gain
            terminated[r] = done
            truncated[r] = (not done) and state[r, _STEPS] >= state[r, _LIMIT]
        if moved_clock:  # the active fault set at the robot's new (step, time)
            step = state[r, _SIM]
            units = state[r, _UNITS]
            mask = 0
            for j in range(state[r, _EVENTS]):
                now = units if events[r, j, _TICK] != 0 else step
                if now < events[r, j, _AT]:
                    continue
                kind = events[r, j, _KIND]
                if (
                    kind == PERMANENT
                    or (kind == TRANSIENT and now < events[r, j, _END])
                    or (kind == INTERMITTENT and draws[r, j] < chance[r, j])
                ):
                    mask |= 1 << j
            current[r] = subsets[r, mask]
        if state[r, _SENSES] != 0:
            known[r] = set_bits[current[r]]
        if fresh or x != state[r, _X] or y != state[r, _Y]:  # the window moved with the robot
            state[r, _X] = x
            state[r, _Y] = y
            stride = state[r, _STRIDE]
            top = state[r, _BASE] + (y - radius) * stride + (x - radius)
            for row in range(side):
                start = top + row * stride
                for col in range(side):
                    window[r, row, col] = grid[start + col]
        heading[r] = state[r, _HEAD]
        goal[r, 0] = state[r, _GX] - x
        goal[r, 1] = state[r, _GY] - y
        bits = known[r]
        if fresh or bits != was_known:
            for f in range(n_faults):
                fault_flags[r, f] = (bits >> np.uint64(f)) & np.uint64(1)


STEP_PYTHON = _step_robots
"""The reference kernel: :func:`_step_robots` run by the interpreter."""

_OPTIONS: dict[str, Any] = {"cache": True, "nogil": True, "_nrt": False}
STEP_NUMBA = njit(**_OPTIONS)(_step_robots) if NUMBA else None
"""The compiled kernel (``None`` without numba); without numba's reference counting, as the
search kernels (it only reads and writes the arrays handed in)."""


def intermittent_draws_numpy(which: Array, state: Array, events: Array, draws: Array) -> None:
    """``draws[r, j]`` for robots ``which`` and their intermittent events ``j``: the draw of
    :meth:`FaultEvent.active <selfrepair.execution.faults.FaultEvent.active>` at the robot's next
    step (its step now when it is pending a reset, else one more), asked of numpy (the
    reference)."""
    for r in which.tolist():
        step = int(state[r, _SIM]) + (0 if state[r, _PENDING] else 1)
        seed = int(state[r, _SEED])
        for j in range(int(state[r, _EVENTS])):
            if events[r, j, _KIND] == INTERMITTENT:
                draws[r, j] = np.random.default_rng([seed, j, step]).random()


@njit(cache=True)
def uniform_numba(seed: int, index: int, step: int) -> float:  # pragma: no cover - compiled
    """``numpy.random.default_rng([seed, index, step]).random()`` for integers below 2**32: the
    compiled mission loop's draw (:func:`~selfrepair.execution.compiled.draws.draw53`) as a
    double, as ``Generator.random`` makes it."""
    return float(draw53(seed, index, step)) * (1.0 / 9007199254740992.0)


@njit(cache=True, nogil=True)
def _draws_numba(
    which: Array, state: Array, events: Array, draws: Array
) -> None:  # pragma: no cover - compiled
    for k in range(which.shape[0]):
        r = which[k]
        step = state[r, _SIM] + (0 if state[r, _PENDING] != 0 else 1)
        for j in range(state[r, _EVENTS]):
            if events[r, j, _KIND] == INTERMITTENT:
                draws[r, j] = uniform_numba(state[r, _SEED], j, step)


def intermittent_draws_numba(which: Array, state: Array, events: Array, draws: Array) -> None:
    """:func:`intermittent_draws_numpy` computed in the kernel (needs numba)."""
    _draws_numba(which, state, events, draws)
