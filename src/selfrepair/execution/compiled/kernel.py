"""The compiled mission loop: one numba kernel that runs a whole mission over integer arrays.

It is :func:`selfrepair.execution.executor.run_mission`'s loop (the executor's ``_loop``, the
:class:`~selfrepair.execution.stepper.Stepper` and the :class:`~selfrepair.execution.simulator.
Simulator`) for the ``replan`` strategy, the ``replacement`` strategy in every recursion mode
(with or without whole-plan rewriting; ``primitive``, which defers faulty complex actions, as the
:class:`~selfrepair.repair.strategies.replacement.DeferringRepairer`) and the ``lookahead``
strategy (its window, the stepper's horizon of ``before`` actions, and its fallbacks; the
window's search is the driver's, one ``NEED_WINDOW`` exit per window, since it plans to a goal
of its own), written over arrays so that no step and no warm table repair runs Python. The
Python loop is the reference: the property test of ``tests/test_compiled_loop.py`` runs both and
compares the traces step by step.

**Resumable.** All state lives in arrays handed in (``st`` holds the scalars). The kernel runs
until the mission ends or until it needs something only Python has, and then returns an *exit*
code with its arguments in ``st``; the driver (:mod:`selfrepair.execution.compiled.driver`)
supplies it and calls again, and the kernel resumes where it stopped. A repair interrupted by an
exit is retried from its start on the next call (it changes nothing before it completes), with its
clock still running: the latency of a repair covers whatever it needed. The exits:

* ``NEED_SET``: the look-ups of a known fault set not loaded yet;
* ``NEED_SLOT``: the neighbourhood mask of an (action, heading) not loaded yet;
* ``NEED_FILL``: a pattern met for the first time (the reference search answers it, as in the
  Python loop's compiled look-ups);
* ``NEED_PLAN``: a replan (the driver calls the mission's planner);
* ``GROW``: an output or queue array is full (``GROW_HEAP``: the planner's heap);
* ``NEED_GUARD``: a deferring mode's guard set or guarded look-ups not known yet (see below);
* ``NEED_WINDOW``: a lookahead window's search (the driver plans to the window's end pose);
* ``OFF_GRID``: a lookahead fallback would look an action up off the maze (an error).

A warm mission (every pattern it meets already answered) runs in one call except for its replans.

Layouts (all ``int64`` unless said): ``mv[a, h]`` the move of action ``a`` from heading ``h``
(``dx, dy, heading, units, n_cells, cells...`` as offsets into the free-cell buffer ``grid``,
uint8); ``avail[m, a]`` whether action ``a`` is available under the fault set of bit mask ``m``
(uint8) and ``block[m, a]`` the mask of the faults that make it fail; ``ev[e]`` fault event
``e`` of the schedule: ``bit, clock (0 step, 1 time units), kind (EV_PERMANENT, EV_TRANSIENT or
EV_INTERMITTENT), at, end, threshold`` (an intermittent event is active at a step when its draw,
:func:`~selfrepair.execution.compiled.draws.draw53`, is below the threshold); the look-up
hash ``ht`` (a row ``(k1, k2, value, 0)`` per slot, so one probe reads one cache line) maps
(known-set look-up id * slots + slot, masked occupancy code, or ``-1 - cell`` for a slot read by
cell) to an answer id or ``NO_ANSWER``; ``lk[sid, slot] = (mask, radius index)`` says how look-up
``sid`` reads a slot (its neighbourhood mask over the occupancy codes ``codes[radius index]``);
answer ``i``'s row ``ans[i] = (off, len, doff, dlen)`` places its actions,
``ans_act[off : off + len]``.

Deferring mode (``primitive``, the :class:`~selfrepair.repair.strategies.replacement.
DeferringRepairer`): answer ``i`` also lists the positions of its deferred actions,
``ans_dpos[doff : doff + dlen]``. The repairer's pending deferred actions
are ``pend[m] = (action + 1, guard id)`` by marker ``m`` (their distance from the end of the
queue; action 0: none pending), up to ``st[S_PEND_HI]``. Guard sets are ids (0: empty); the
guard hash ``gh`` (rows as ``ht``'s) maps ``(2 g, action)`` to the id of guard ``g`` with the
action added and ``(2 g + 1, look-up id under no guard)`` to the look-up id under guard ``g``;
a key not there yet is a ``NEED_GUARD`` exit.

Clock: repairs are timed with ``clock_gettime(CLOCK_MONOTONIC)``, the clock behind Python's
``time.perf_counter_ns`` on Linux, called from the kernel (:func:`clock_ns`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from selfrepair.execution.compiled.draws import draw53
from selfrepair.execution.compiled.planner import plan_in_kernel
from selfrepair.jit import NUMBA, njit, no_refcount

I64 = npt.NDArray[np.int64]
"""The loop's integer arrays: parameters, state, queues, trace and repair records, tables."""
U8 = npt.NDArray[np.uint8]
"""The free-cell bytes of the padded grid and the available-action flags."""
I32 = npt.NDArray[np.int32]
"""The compiled look-ups' answer actions."""
Deferring = tuple[I64, I64, I64]
"""The deferring mode's arrays: ``pend, gh, ans_dpos``."""
Kernels = tuple[npt.NDArray[np.generic], ...]
"""The arrays a compiled planner or search works in (int64 mostly; the planner also has int32
and uint16 ones), passed through as one tuple."""

__all__ = ["NUMBA", "clock_ns", "hash_get", "hash_put", "run_kernel", "warm_hits"]

# --- exit codes ------------------------------------------------------------------------------
DONE = 0
NEED_SET = 1
NEED_SLOT = 2
NEED_FILL = 3
NEED_PLAN = 4
GROW = 5
TOO_MANY = 6
NEED_PLANNER = 7
GROW_HEAP = 8
NEED_GUARD = 9
NEED_WINDOW = 10
OFF_GRID = 11

# --- mission ends (st[END]) ------------------------------------------------------------------
REACHED = 0
STEP_LIMIT = 1
FAILED = 2
COLLISION = 3

# --- step sources ----------------------------------------------------------------------------
SRC_PLAN = 0
SRC_REPLACEMENT = 1
SRC_REPLAN = 2
SRC_FAILED = 3
SRC_WAIT = 4
SRC_LOOKAHEAD = 5

# --- repair kinds (rp[i, RP_KIND]) -----------------------------------------------------------
K_HIT = 0
K_REWRITE = 1
K_REPLAN = 2
K_MISS = 3
K_DEFENSIVE = 4
K_WINDOW = 5

# --- repair statuses -------------------------------------------------------------------------
R_REPAIRED = 0
R_STUCK = 1
R_BUDGET = 2

EMPTY = -1
"""A free hash slot (and, for a look-up, a pattern not answered yet)."""
NO_ANSWER = -2
"""A pattern whose answer is "no valid candidate"."""
UNLOADED = -1
"""A mask not loaded yet."""
BY_CELL = -2
"""A slot whose codes do not fit 63 bits: answers are keyed by cell instead."""

# --- st: the scalar state --------------------------------------------------------------------
S_PHASE = 0  # 0: top of the loop; 1: inside a repair (retry it)
S_STEP = 1
S_UNITS = 2
S_X = 3
S_Y = 4
S_H = 5
S_KNOWN = 6
S_QLEN = 7
S_NSTEPS = 8
S_NREP = 9
S_WAITS = 10
S_EXEC_UNITS = 11
S_PENALTY = 12
S_T0 = 13
S_RACTION = 14  # the action being repaired (-1: the defensive replan)
S_TRIES = 15  # repairs asked in this question (at most MAX_REPAIRS_PER_STEP)
S_END = 16
S_ARG0 = 17
S_ARG1 = 18
S_ARG2 = 19
S_ARG3 = 20
S_ARG4 = 21
S_PLAN_READY = 22  # 1: the plan buffer holds the answer to the pending NEED_PLAN
S_PLAN_STATUS = 23
S_PLAN_LEN = 24
S_PLAN_ID = 25
S_NACT = 26  # used entries of rp_act
S_MOVED = 27  # moving steps (for the metrics)
S_FAIL_REP = 28  # the record of the repair that failed
S_PL_MASK = 29  # the known mask the loaded planner serves (-1: none)
S_PL_KERNEL = 30  # 1: the loaded planner runs in the kernel; 0: the driver plans
S_PLAN_EXP = 31  # expansions of the plan just made in the kernel
S_PEND_HI = 32  # deferring mode: the highest marker that may be pending (0: none)
S_EARLY_AT = 33  # lookahead: the step of the last early repair (-1: none)
S_LA_READY = 34  # lookahead: 1 when the window's search answered the pending NEED_WINDOW
S_LA_STATUS = 35
S_LA_LEN = 36
S_LA_EXP = 37
S_LA_ID = 38
S_SIZE = 39

# --- par: the mission's parameters -----------------------------------------------------------
P_STRATEGY = 0  # 0 replan, 1 replacement
P_REWRITE = 1
P_WIDTH = 2
P_HEIGHT = 3
P_STRIDE = 4
P_MARGIN = 5
P_GX = 6
P_GY = 7
P_GH = 8  # -1: any heading
P_LIMIT = 9
P_SENSE_NOW = 10
P_MAX_WAIT = 11
P_FAILED_UNITS = 12
P_NSLOTS = 13
P_WEIGHT = 14
P_MAX_TRIES = 15
P_BUDGET = 16
P_SEED = 17  # the mission's seed (intermittent draws)
P_DEFER = 18  # 1: the recursion mode defers faulty complex actions (primitive)
P_BEFORE = 19  # lookahead: actions after the front checked for known faults (the horizon)
P_WINDOW = 20  # lookahead: actions after the faulty one in the window
P_LONGEST = 21  # the longest answer of the look-ups so far (bounds what a rewrite splices)
P_SIZE = 22

# --- fault event kinds (ev[e, 2]) ------------------------------------------------------------
EV_TRANSIENT = 0
EV_PERMANENT = 1
EV_INTERMITTENT = 2

# --- trace rows (tr[i]) ----------------------------------------------------------------------
T_STEP, T_ACTION, T_X, T_Y, T_H, T_EX, T_EY, T_EH, T_UNITS, T_SOURCE, T_KNOWN = range(11)
T_COLS = 11

# --- repair rows (rp[i]) ---------------------------------------------------------------------
(
    RP_STEP, RP_X, RP_Y, RP_H, RP_ACTION, RP_KIND, RP_AID, RP_STATUS, RP_LATENCY, RP_CONSUMED,
    RP_ACT_OFF, RP_ACT_LEN, RP_SUBST, RP_PLAN, RP_KNOWN, RP_QLEN, RP_EXPANSIONS, RP_WINDOW,
    RP_PREFIX,
) = range(19)  # fmt: skip
RP_COLS = 19

# --- hash rows (ht[i], gh[i]), look-up slots (lk[sid, slot]), answers (ans[aid]) --------------
H_K1, H_K2, H_V = range(3)
H_COLS = 4  # 32-byte rows: a probe reads one cache line
LK_MASK, LK_R = range(2)
A_OFF, A_LEN, A_DOFF, A_DLEN = range(4)
A_COLS = 4

_MUL1 = np.int64(-7046029254386353131)  # 0x9E3779B97F4A7C15 as a signed 64-bit integer
_MUL2 = np.int64(-4658895280553007687)  # 0xBF58476D1CE4E5B9


if NUMBA:
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def _clock_intrinsic(typingctx: Any) -> Any:
        """``clock_gettime(CLOCK_MONOTONIC)`` in nanoseconds (the clock of
        ``time.perf_counter_ns`` on Linux), as a call to the C library from compiled code."""
        sig = types.int64()

        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            i64, i32 = ir.IntType(64), ir.IntType(32)
            spec = cgutils.alloca_once(builder, ir.ArrayType(i64, 2))  # type: ignore[no-untyped-call]
            fnty = ir.FunctionType(i32, [i32, spec.type])
            fn = cgutils.get_or_insert_function(builder.module, fnty, "clock_gettime")  # type: ignore[no-untyped-call]
            builder.call(fn, [ir.Constant(i32, 1), spec])
            zero = ir.Constant(i32, 0)
            sec = builder.load(builder.gep(spec, [zero, zero]))
            nsec = builder.load(builder.gep(spec, [zero, ir.Constant(i32, 1)]))
            return builder.add(builder.mul(sec, ir.Constant(i64, 1_000_000_000)), nsec)

        return sig, codegen

    _now = cast(Callable[[], int], _clock_intrinsic)
else:  # pragma: no cover - without numba the kernel is never called
    _now = time.perf_counter_ns


@njit(cache=True)
def clock_ns() -> int:
    """The kernel's clock, callable from Python (for checks against ``perf_counter_ns``)."""
    return _now()


@njit(cache=True, inline="always")
def _hash(k1: int, k2: int, cap: int) -> int:
    return int(((k1 * _MUL1) ^ (k2 * _MUL2) ^ ((k2 >> 29) * _MUL1)) & (cap - 1))


@njit(cache=True)
def hash_get(ht: I64, k1: int, k2: int) -> int:
    """The value under ``(k1, k2)`` in the hash table ``ht``, or ``EMPTY``."""
    return _hash_get(ht, k1, k2)


@njit(cache=True, inline="always")
def _hash_get(ht: I64, k1: int, k2: int) -> int:
    """:func:`hash_get`, inlined into the kernels (no call, no reference counting)."""
    cap = ht.shape[0]
    i = _hash(k1, k2, cap)
    while True:
        row = ht[i]
        if row[H_K1] == EMPTY:
            return EMPTY
        if row[H_K1] == k1 and row[H_K2] == k2:
            return row[H_V]  # type: ignore[no-any-return]
        i = (i + 1) & (cap - 1)


@njit(cache=True)
def hash_put(ht: I64, k1: int, k2: int, value: int) -> None:
    """Store ``value`` under ``(k1, k2)`` in ``ht`` (the caller keeps it at most half full)."""
    cap = ht.shape[0]
    i = _hash(k1, k2, cap)
    while ht[i, H_K1] != EMPTY and not (ht[i, H_K1] == k1 and ht[i, H_K2] == k2):
        i = (i + 1) & (cap - 1)
    ht[i, H_K1] = k1
    ht[i, H_K2] = k2
    ht[i, H_V] = value


@njit(cache=True, inline="always")
def _true_mask(ev: I64, step: int, units: int, seed: int) -> int:
    """The mask of the faults active at the start of step ``step``, ``units`` time units in
    (:meth:`~selfrepair.execution.faults.FaultSchedule.active_faults`): an intermittent event
    ``e`` from its start on when the draw of ``[seed, e, step]`` is below its probability."""
    mask = 0
    for e in range(ev.shape[0]):
        now = step if ev[e, 1] == 0 else units
        if now < ev[e, 3]:
            continue
        kind = ev[e, 2]
        if kind == EV_PERMANENT or (kind == EV_TRANSIENT and now < ev[e, 4]) or (
            kind == EV_INTERMITTENT and draw53(seed, e, step) < ev[e, 5]
        ):
            mask |= 1 << ev[e, 0]
    return mask


@njit(cache=True, inline="always")
def _lookup(
    st: I64, par: I64, set_of: I64, lk: I64, codes: I64, ht: I64, known: int, a: int,
    x: int, y: int, h: int,
) -> int:  # fmt: skip
    """The answer id of action ``a`` from pose ``(x, y, h)`` under the known mask, ``NO_ANSWER``,
    or an exit (returned as ``-10 - code``, its arguments set in ``st[S_ARG0 ...]``)."""
    sid = set_of[known]
    if sid < 0:
        st[S_ARG0] = known
        return -10 - NEED_SET
    return _lookup_in(st, par, sid, lk, codes, ht, a, x, y, h)


@njit(cache=True, inline="always")
def _lookup_in(
    st: I64, par: I64, sid: int, lk: I64, codes: I64, ht: I64, a: int, x: int, y: int, h: int,
) -> int:  # fmt: skip
    """:func:`_lookup` in the look-ups of id ``sid``."""
    slot = 4 * a + h
    read = lk[sid, slot]
    m = read[LK_MASK]
    if m == UNLOADED:
        st[S_ARG0], st[S_ARG1] = sid, slot
        return -10 - NEED_SLOT
    k1 = sid * par[P_NSLOTS] + slot
    k2 = -1 - (y * par[P_WIDTH] + x) if m == BY_CELL else codes[read[LK_R], y, x] & m
    v = _hash_get(ht, k1, k2)
    if v == EMPTY:
        st[S_ARG0], st[S_ARG1], st[S_ARG2], st[S_ARG3], st[S_ARG4] = sid, slot, x, y, k2
        return -10 - NEED_FILL
    return v


@no_refcount
def warm_hits(
    n: int, st: I64, par: I64, set_of: I64, lk: I64, codes: I64, ht: I64, known: int, a: int,
    xs: I64, ys: I64, hs: I64,
) -> int:  # fmt: skip
    """``n`` look-ups of action ``a`` at the poses ``(xs, ys, hs)`` in turn, as the mission
    kernel makes them (for the benchmark of a warm hit); the sum of the answer ids."""
    total = 0
    k = xs.shape[0]
    for i in range(n):
        j = i % k
        total += _lookup(st, par, set_of, lk, codes, ht, known, a, xs[j], ys[j], hs[j])
    return total


@no_refcount
def run_kernel(
    par: I64, st: I64, mv: I64, grid: U8, avail: U8, block: I64, waits: I64, ev: I64,
    set_of: I64, lk: I64, codes: I64, ht: I64, ans: I64, ans_act: I32, pen: I64, pb: I64,
    qa: I64, qs: I64, tr: I64, rp: I64, rp_act: I64, planner: Kernels, search: Kernels,
    deferring: Deferring,
) -> int:  # fmt: skip
    """Run (or resume) the mission; the exit code (see the module docstring). ``planner`` is
    the loaded kernel planner's arrays and ``search`` its records, generation and heap
    (:mod:`selfrepair.execution.compiled.planner`); ``deferring`` the deferring mode's arrays
    ``(pend, gh, ans_dpos)``."""
    stride, margin = par[P_STRIDE], par[P_MARGIN]
    gx, gy, gh = par[P_GX], par[P_GY], par[P_GH]
    while True:
        if st[S_PHASE] == 0:
            x, y, h = st[S_X], st[S_Y], st[S_H]
            if x == gx and y == gy and (gh < 0 or h == gh):
                st[S_END] = REACHED
                return DONE
            if st[S_STEP] >= par[P_LIMIT]:
                st[S_END] = STEP_LIMIT
                return DONE
            if par[P_SENSE_NOW]:
                st[S_KNOWN] = _true_mask(ev, st[S_STEP], st[S_UNITS], par[P_SEED])
            st[S_TRIES] = 0
            if st[S_NSTEPS] >= tr.shape[0] or st[S_QLEN] + 2 > qa.shape[0]:
                return GROW
        # the question: repair until the queue's front is available under the known faults
        while True:
            known = st[S_KNOWN]
            qlen = st[S_QLEN]
            if st[S_PHASE] == 0:
                ahead = -1
                if qlen > 0 and avail[known, qa[qlen - 1]]:
                    if par[P_BEFORE] > 0 and st[S_EARLY_AT] != st[S_STEP]:
                        # the stepper's horizon: a known fault among the next actions
                        for i in range(1, min(par[P_BEFORE] + 1, qlen)):
                            if not avail[known, qa[qlen - 1 - i]]:
                                ahead = qa[qlen - 1 - i]
                                break
                    if ahead < 0:
                        break
                if st[S_TRIES] >= par[P_MAX_TRIES]:
                    return TOO_MANY
                room = rp_act.shape[0] - st[S_NACT]
                if st[S_NREP] >= rp.shape[0] or room < qlen + 64:
                    return GROW  # before the clock starts: growing is no part of a repair
                if par[P_REWRITE] and _rewrite_short(par, qlen, qa.shape[0], room) > 0:
                    return GROW  # room for the longest rewrite the look-ups can splice
                st[S_PHASE] = 1
                st[S_T0] = _now()
                if ahead >= 0:
                    st[S_EARLY_AT] = st[S_STEP]  # at most one early repair per step
                    st[S_RACTION] = ahead
                else:
                    st[S_RACTION] = qa[qlen - 1] if qlen > 0 else -1
            if st[S_NREP] >= rp.shape[0]:
                return GROW
            code = _repair(par, st, mv, avail, ev, set_of, lk, codes, ht, ans, ans_act, pb, qa,
                           qs, rp, rp_act, planner, search, deferring)  # fmt: skip
            if code != DONE:
                return code
            st[S_PHASE] = 0
            st[S_TRIES] += 1
            r = st[S_NREP] - 1
            if rp[r, RP_STATUS] != R_REPAIRED:
                w = -1
                if rp[r, RP_STATUS] == R_STUCK and st[S_WAITS] < par[P_MAX_WAIT]:
                    for i in range(waits.shape[0]):
                        if avail[st[S_KNOWN], waits[i]]:
                            w = waits[i]
                            break
                if w < 0:
                    st[S_END] = FAILED
                    st[S_FAIL_REP] = r
                    return DONE
                st[S_WAITS] += 1
                qa[st[S_QLEN]] = w  # room for it was checked at the top of the loop
                qs[st[S_QLEN]] = SRC_WAIT
                st[S_QLEN] += 1
                break
        # the command
        qlen = st[S_QLEN]
        a, source = qa[qlen - 1], qs[qlen - 1]
        x, y, h = st[S_X], st[S_Y], st[S_H]
        known = st[S_KNOWN]
        true = _true_mask(ev, st[S_STEP], st[S_UNITS], par[P_SEED])
        n = st[S_NSTEPS]
        row = tr[n]
        row[T_STEP], row[T_ACTION], row[T_X], row[T_Y], row[T_H] = st[S_STEP], a, x, y, h
        if avail[true, a]:
            base = (y + margin) * stride + x + margin
            for j in range(mv[a, h, 4]):
                if grid[base + mv[a, h, 5 + j]] == 0:
                    st[S_END] = COLLISION
                    return DONE
            if par[P_WEIGHT]:
                for j in range(mv[a, h, 4]):
                    st[S_PENALTY] += pen[base + mv[a, h, 5 + j]]
            nx, ny, nh = x + mv[a, h, 0], y + mv[a, h, 1], mv[a, h, 2]
            st[S_X], st[S_Y], st[S_H] = nx, ny, nh
            st[S_UNITS] += mv[a, h, 3]
            st[S_EXEC_UNITS] += mv[a, h, 3]
            st[S_MOVED] += 1
            st[S_QLEN] = qlen - 1
            row[T_EX], row[T_EY], row[T_EH] = nx, ny, nh
            row[T_UNITS], row[T_SOURCE], row[T_KNOWN] = mv[a, h, 3], source, known
        else:
            if source == SRC_WAIT:
                st[S_QLEN] = qlen - 1  # a wait an unknown fault forbids: ask again
            st[S_UNITS] += par[P_FAILED_UNITS]
            row[T_EX], row[T_EY], row[T_EH] = x, y, h
            row[T_UNITS], row[T_SOURCE], row[T_KNOWN] = par[P_FAILED_UNITS], SRC_FAILED, known
            st[S_KNOWN] = known | block[true, a]
        st[S_STEP] += 1
        st[S_NSTEPS] = n + 1


@njit(cache=True, inline="always")
def _repair(
    par: I64, st: I64, mv: I64, avail: U8, ev: I64, set_of: I64, lk: I64, codes: I64,
    ht: I64, ans: I64, ans_act: I32,
    pb: I64, qa: I64, qs: I64, rp: I64, rp_act: I64, planner: Kernels, search: Kernels,
    deferring: Deferring,
) -> int:  # fmt: skip
    """One repair of the queue (``st[S_RACTION]``: the faulty front action, -1 for the
    defensive replan), recorded in ``rp``; an exit code when it needs Python first."""
    x, y, h = st[S_X], st[S_Y], st[S_H]
    known = st[S_KNOWN]
    a = st[S_RACTION]
    qlen = st[S_QLEN]
    r = st[S_NREP]
    rec = rp[r]
    kind = K_REPLAN
    aid = -1
    defer = par[P_DEFER] == 1 and a >= 0
    pend, gh, ans_dpos = deferring
    grown = 0  # deferring: the guard id of this repair's guard set with ``a`` added
    pfx = 0  # lookahead fallback: the healthy actions before the faulty one, kept in front
    window = -1  # lookahead: the plan id of the window's search
    wlen = 0
    px, py, ph = x, y, h  # where the look-up and the replan start (lookahead: past the prefix)
    if a < 0:
        kind = K_DEFENSIVE
    elif par[P_STRATEGY] == 2:
        # lookahead(): the window runs from the front to P_WINDOW actions after the first
        # faulty action among the first P_BEFORE + 1
        f = 0
        for i in range(min(par[P_BEFORE] + 1, qlen)):
            if not avail[known, qa[qlen - 1 - i]]:
                f = i
                break
        wlen = min(f + par[P_WINDOW] + 1, qlen)
        if st[S_LA_READY] == 0:
            ex, ey, eh = x, y, h
            for i in range(wlen):
                b = qa[qlen - 1 - i]
                ex, ey, eh = ex + mv[b, eh, 0], ey + mv[b, eh, 1], mv[b, eh, 2]
            st[S_ARG0], st[S_ARG1], st[S_ARG2], st[S_ARG3] = known, ex, ey, eh
            return NEED_WINDOW
        window = st[S_LA_ID]
        if st[S_LA_STATUS] == R_REPAIRED:
            kind = K_WINDOW
        else:  # replacement() for the faulty action where the robot will meet it
            pfx = f
            for i in range(f):
                b = qa[qlen - 1 - i]
                px, py, ph = px + mv[b, ph, 0], py + mv[b, ph, 1], mv[b, ph, 2]
            if not (0 <= px < par[P_WIDTH] and 0 <= py < par[P_HEIGHT]):
                return OFF_GRID
            b = qa[qlen - 1 - f]
            aid = _lookup(st, par, set_of, lk, codes, ht, known, b, px, py, ph)
            if aid <= -10:
                return -10 - aid
            kind = K_MISS if aid == NO_ANSWER else K_HIT
    elif defer:
        # DeferringRepairer.repair: the guard of the deferred action pending at this marker
        sid = set_of[known]
        if sid < 0:
            st[S_ARG0] = known
            return NEED_SET
        guard = pend[qlen, 1] if qlen <= st[S_PEND_HI] and pend[qlen, 0] == a + 1 else 0
        if guard != 0:
            sid = _hash_get(gh, 2 * guard + 1, sid)
            if sid == EMPTY:
                st[S_ARG0], st[S_ARG1] = 2 * guard + 1, set_of[known]
                return NEED_GUARD
        aid = _lookup_in(st, par, sid, lk, codes, ht, a, x, y, h)
        if aid <= -10:
            return -10 - aid
        kind = K_MISS if aid == NO_ANSWER else K_HIT
        if kind == K_HIT and ans[aid, A_DLEN] > 0:  # every guard id the commit needs, known first
            grown = _hash_get(gh, 2 * guard, a)
            if grown == EMPTY:
                st[S_ARG0], st[S_ARG1] = 2 * guard, a
                return NEED_GUARD
            for j in range(ans[aid, A_DLEN]):
                d = ans_act[ans[aid, A_OFF] + ans_dpos[ans[aid, A_DOFF] + j]]
                if _hash_get(gh, 2 * grown, d) == EMPTY:
                    st[S_ARG0], st[S_ARG1] = 2 * grown, d
                    return NEED_GUARD
    elif par[P_STRATEGY] == 1:
        aid = _lookup(st, par, set_of, lk, codes, ht, known, a, x, y, h)
        if aid <= -10:
            return -10 - aid
        kind = K_MISS if aid == NO_ANSWER else K_HIT
    if kind == K_WINDOW:  # the window's sub-plan replaces the window
        status = R_REPAIRED
        off = st[S_NACT]
        consumed = wlen
        n = st[S_LA_LEN]
        if qlen - wlen + n + 2 > qa.shape[0] or n > rp_act.shape[0] - off:
            st[S_PLAN_LEN] = n
            return GROW  # the sub-plan stays ready for the retry
        for i in range(n):
            rp_act[off + i] = pb[i]
        st[S_QLEN] -= consumed
        _push(qa, qs, st, rp_act, off, n, SRC_LOOKAHEAD)
        rec[RP_PLAN] = -1
        rec[RP_EXPANSIONS] = 0
        rec[RP_SUBST] = 0
    elif kind != K_HIT:  # a replan (lookahead: from past the prefix, which stays in front)
        off = st[S_NACT]
        consumed = qlen
        st[S_ARG0], st[S_ARG1], st[S_ARG2], st[S_ARG3] = known, px, py, ph
        if st[S_PLAN_READY] == 0 and st[S_PL_MASK] != known:
            return NEED_PLANNER
        for i in range(pfx):
            rp_act[off + i] = qa[qlen - 1 - i]
        if st[S_PLAN_READY] == 0 and st[S_PL_KERNEL] == 1:  # one call of the lattice kernel
            mt, hdist, ppen, nbr, ppar, moves = planner
            prec, gen, heap, pscal, ppar2, pextra = search
            found, n, expansions = plan_in_kernel(
                mt, hdist, ppen, nbr, ppar, moves, prec, gen, heap, pscal, ppar2, pextra,
                px, py, ph, par[P_BUDGET], rp_act, off + pfx,
            )  # fmt: skip
            if found == 4:
                return GROW_HEAP
            if found == 3 or pfx + n + 2 > qa.shape[0]:
                st[S_PLAN_LEN] = pfx + n
                return GROW
            status = R_REPAIRED if found == 0 else (R_STUCK if found == 1 else R_BUDGET)
            rec[RP_PLAN] = -1
        else:
            if st[S_PLAN_READY] == 0:
                return NEED_PLAN
            status = st[S_PLAN_STATUS]
            n = st[S_PLAN_LEN]
            expansions = st[S_PLAN_EXP]
            if status == R_REPAIRED and (
                pfx + n + 2 > qa.shape[0] or pfx + n > rp_act.shape[0] - off
            ):
                return GROW  # the plan stays ready for the retry
            st[S_PLAN_READY] = 0
            for i in range(n):
                rp_act[off + pfx + i] = pb[i]
            rec[RP_PLAN] = st[S_PLAN_ID]
        if status == R_REPAIRED:
            n += pfx
            st[S_QLEN] = 0
            _push(qa, qs, st, rp_act, off, n, SRC_REPLAN)
        else:
            n = pfx  # the record keeps the prefix (nothing is spliced)
        rec[RP_EXPANSIONS] = expansions
        rec[RP_SUBST] = 0
    else:
        status = R_REPAIRED
        off = st[S_NACT]
        consumed = 1 + pfx
        substituted = 0
        start, length = ans[aid, A_OFF], ans[aid, A_LEN]
        if rp_act.shape[0] - off < length + qlen:
            return GROW
        for i in range(pfx):  # lookahead: the healthy actions before the faulty one
            rp_act[off + i] = qa[qlen - 1 - i]
        for i in range(length):
            rp_act[off + pfx + i] = ans_act[start + i]
        n = pfx + length
        if par[P_REWRITE]:
            # the whole-plan rewrite: walk the rest of the queue along its predicted poses
            width, height = par[P_WIDTH], par[P_HEIGHT]
            sid = set_of[known]  # loaded: the first look-up found it (rewriting is replacement's)
            px, py, ph = x + mv[a, h, 0], y + mv[a, h, 1], mv[a, h, 2]
            done = 0  # queue actions after the faulty one consumed (up to the last hit)
            kept = n  # the spliced actions up to the last hit
            for k in range(qlen - 1):
                b = qa[qlen - 2 - k]
                if avail[known, b]:  # a plain action: kept only if a later one is substituted
                    rp_act[off + n] = b  # room: qlen past the last check
                    n += 1
                else:
                    if not (0 <= px < width and 0 <= py < height):
                        break
                    hit = _lookup_in(st, par, sid, lk, codes, ht, b, px, py, ph)
                    if hit <= -10:
                        return -10 - hit
                    if hit == NO_ANSWER:
                        break
                    hoff, hlen = ans[hit, A_OFF], ans[hit, A_LEN]
                    if rp_act.shape[0] - (off + n) < qlen + hlen:
                        return GROW
                    for j in range(hlen):
                        rp_act[off + n + j] = ans_act[hoff + j]
                    n += hlen
                    kept = n
                    done = k + 1
                    substituted += 1
                npx, npy = px + mv[b, ph, 0], py + mv[b, ph, 1]
                ph = mv[b, ph, 2]
                px, py = npx, npy
            n = kept
            if substituted:
                kind = K_REWRITE
                consumed = 1 + done
        if st[S_QLEN] - consumed + n + 2 > qa.shape[0]:
            return GROW
        st[S_QLEN] -= consumed
        _push(qa, qs, st, rp_act, off, n, SRC_REPLACEMENT)
        rec[RP_SUBST] = substituted
        rec[RP_PLAN] = -1
        rec[RP_EXPANSIONS] = 0
    rec[RP_LATENCY] = _now() - st[S_T0]
    rec[RP_STEP], rec[RP_X], rec[RP_Y], rec[RP_H] = st[S_STEP], x, y, h
    rec[RP_ACTION], rec[RP_KIND], rec[RP_AID], rec[RP_STATUS] = a, kind, aid, status
    rec[RP_CONSUMED], rec[RP_ACT_OFF], rec[RP_ACT_LEN] = consumed, off, n
    rec[RP_KNOWN], rec[RP_QLEN] = known, qlen
    rec[RP_WINDOW], rec[RP_PREFIX] = window, pfx
    st[S_LA_READY] = 0
    st[S_NACT] = off + n
    st[S_NREP] = r + 1
    if defer:  # the repairer's pending deferred actions, as DeferringRepairer.repair keeps them
        hi = st[S_PEND_HI]
        for m in range(qlen + 1, hi + 1):  # passed: no longer ahead
            pend[m, 0] = 0
        hi = min(hi, qlen)
        pend[qlen, 0] = 0  # popped
        if kind == K_MISS:  # a replan replaces the whole queue
            for m in range(hi + 1):
                pend[m, 0] = 0
            hi = 0
        else:
            after = qlen - 1 + ans[aid, A_LEN]
            for j in range(ans[aid, A_DLEN]):
                p = ans_dpos[ans[aid, A_DOFF] + j]
                d = ans_act[ans[aid, A_OFF] + p]
                pend[after - p, 0] = d + 1
                pend[after - p, 1] = _hash_get(gh, 2 * grown, d)
                hi = max(hi, after - p)
        st[S_PEND_HI] = hi
    return DONE


@njit(cache=True, inline="always")
def _rewrite_short(par: I64, qlen: int, queue_room: int, act_room: int) -> int:
    """How many more entries a whole-plan rewrite of a queue of ``qlen`` actions may need than
    ``queue_room`` (the queue's length) and ``act_room`` (the repair actions' free room) give,
    at most: each queued action replaced by the longest answer (``par[P_LONGEST]``). Positive:
    grow first (the driver's ``GROW`` makes the same room), so a warm rewrite never exits to
    grow inside its clock."""
    longest = max(int(par[P_LONGEST]), 1)
    return max(qlen * longest + 2 - queue_room, qlen * (longest + 1) + longest + 64 - act_room)


@njit(cache=True, inline="always")
def _push(qa: I64, qs: I64, st: I64, acts: I64, off: int, n: int, source: int) -> None:
    """Put ``acts[off : off + n]`` at the front of the queue (kept reversed: front last)."""
    q = st[S_QLEN]
    for i in range(n):
        qa[q + i] = acts[off + n - 1 - i]
        qs[q + i] = source
    st[S_QLEN] = q + n
