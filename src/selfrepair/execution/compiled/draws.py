"""The intermittent-fault draw of the Python simulator, compiled: bit for bit
``float(numpy.random.default_rng([seed, event, step]).random())`` (see
:meth:`selfrepair.execution.faults.FaultEvent.active`), without making a generator.

What NumPy does, and this module repeats over unsigned 64-bit integers:

1. ``SeedSequence([seed, event, step])`` turns each integer into its 32-bit words (least
   significant first; ``0`` is one word ``0``), concatenates them, and mixes them into a pool of
   four 32-bit words (``mix_entropy``: ``hashmix`` and ``mix`` with NumPy's constants).
2. ``PCG64`` asks the pool for four 64-bit words (``generate_state(4, uint64)``: eight 32-bit
   words, in pairs, low word first): the 128-bit seed (words 0 and 1, high first) and stream
   (words 2 and 3), and seeds the generator as ``pcg_setseq_128_srandom_r`` does (the increment
   ``stream << 1 | 1``, one step, add the seed, one step).
3. ``random()`` is one more step, the XSL-RR output of the new state, and ``(u64 >> 11) *
   2**-53``.

An event is active when that draw is below its probability ``p``; :func:`threshold` turns ``p``
into the integer ``t`` with ``draw < p`` exactly when ``u64 >> 11 < t``, so the kernel compares
integers. ``tests/test_compiled_loop.py`` checks :func:`draw53` against NumPy for random
seeds, events and steps.
"""

from __future__ import annotations

import math

import numpy as np

from selfrepair.jit import njit

__all__ = ["MAX_SEED", "MAX_WORD", "draw53", "threshold", "uniform"]

MAX_SEED = (1 << 63) - 1
"""The largest seed the compiled draw takes (an ``int64``; a larger one runs in Python)."""
MAX_WORD = (1 << 32) - 1
"""The largest event index and step the compiled draw takes (one 32-bit word each)."""

_M32 = np.uint64(0xFFFFFFFF)
_INIT_A = np.uint64(0x43B0D7E5)
_MULT_A = np.uint64(0x931E8875)
_INIT_B = np.uint64(0x8B51F9DD)
_MULT_B = np.uint64(0x58F38DED)
_MIX_L = np.uint64(0xCA01F9DD)
_MIX_R = np.uint64(0x4973F715)
_S16 = np.uint64(16)
_S32 = np.uint64(32)
_PCG_HI = np.uint64(0x2360ED051FC65DA4)
_PCG_LO = np.uint64(0x4385DF649FCCF645)
_ONE = np.uint64(1)
_ZERO = np.uint64(0)


@njit(cache=True, inline="always")
def _hashmix(value: np.uint64, hc: np.uint64) -> tuple[np.uint64, np.uint64]:
    """NumPy's ``hashmix`` on 32-bit words: the mixed value and the next hash constant."""
    value = (value ^ hc) & _M32
    hc = (hc * _MULT_A) & _M32
    value = (value * hc) & _M32
    value ^= value >> _S16
    return value, hc


@njit(cache=True, inline="always")
def _mix(x: np.uint64, y: np.uint64) -> np.uint64:
    """NumPy's ``mix`` of two 32-bit words."""
    result = ((_MIX_L * x) - (_MIX_R * y)) & _M32
    return result ^ (result >> _S16)


@njit(cache=True, inline="always")
def _mulhi(a: np.uint64, b: np.uint64) -> np.uint64:
    """The high 64 bits of the 128-bit product ``a * b``."""
    a_lo, a_hi = a & _M32, a >> _S32
    b_lo, b_hi = b & _M32, b >> _S32
    lo_lo = a_lo * b_lo
    hi_lo = a_hi * b_lo
    lo_hi = a_lo * b_hi
    cross = (lo_lo >> _S32) + (hi_lo & _M32) + lo_hi
    return a_hi * b_hi + (hi_lo >> _S32) + (cross >> _S32)


@njit(cache=True, inline="always")
def _step(
    hi: np.uint64, lo: np.uint64, ihi: np.uint64, ilo: np.uint64
) -> tuple[np.uint64, np.uint64]:
    """One PCG64 step: ``state * MULT + inc`` modulo 2**128."""
    nlo = lo * _PCG_LO
    nhi = _mulhi(lo, _PCG_LO) + hi * _PCG_LO + lo * _PCG_HI
    slo = nlo + ilo
    carry = _ONE if slo < nlo else _ZERO
    return nhi + ihi + carry, slo


@njit(cache=True, inline="always")
def _word(pool: np.uint64, hb: np.uint64) -> tuple[np.uint64, np.uint64]:
    """One 32-bit word of ``generate_state`` from a pool word: the word and the next constant."""
    value = (pool ^ hb) & _M32
    hb = (hb * _MULT_B) & _M32
    value = (value * hb) & _M32
    return value ^ (value >> _S16), hb


@njit(cache=True)
def draw53(seed: int, event: int, step: int) -> int:
    """``u64 >> 11`` of the first 64-bit output of ``default_rng([seed, event, step])``, for
    ``0 <= seed <= MAX_SEED`` and ``0 <= event, step < 2**32`` (at most four 32-bit words of
    entropy, so the pool takes them all and NumPy's loop over further words never runs);
    ``random()`` is this times ``2**-53``. Scalars only: it allocates nothing."""
    s = np.uint64(seed)
    if s >> _S32:  # the seed is two words
        w0, w1, w2, w3 = s & _M32, s >> _S32, np.uint64(event), np.uint64(step)
    else:  # three words, and the pool's fourth is hashed from 0
        w0, w1, w2, w3 = s, np.uint64(event), np.uint64(step), _ZERO
    hc = _INIT_A
    p0, hc = _hashmix(w0, hc)
    p1, hc = _hashmix(w1, hc)
    p2, hc = _hashmix(w2, hc)
    p3, hc = _hashmix(w3, hc)
    # for i_src: for i_dst != i_src: pool[i_dst] = mix(pool[i_dst], hashmix(pool[i_src]))
    m, hc = _hashmix(p0, hc)
    p1 = _mix(p1, m)
    m, hc = _hashmix(p0, hc)
    p2 = _mix(p2, m)
    m, hc = _hashmix(p0, hc)
    p3 = _mix(p3, m)
    m, hc = _hashmix(p1, hc)
    p0 = _mix(p0, m)
    m, hc = _hashmix(p1, hc)
    p2 = _mix(p2, m)
    m, hc = _hashmix(p1, hc)
    p3 = _mix(p3, m)
    m, hc = _hashmix(p2, hc)
    p0 = _mix(p0, m)
    m, hc = _hashmix(p2, hc)
    p1 = _mix(p1, m)
    m, hc = _hashmix(p2, hc)
    p3 = _mix(p3, m)
    m, hc = _hashmix(p3, hc)
    p0 = _mix(p0, m)
    m, hc = _hashmix(p3, hc)
    p1 = _mix(p1, m)
    m, hc = _hashmix(p3, hc)
    p2 = _mix(p2, m)
    # generate_state(4, uint64): eight words from the pool in turn, paired low word first
    hb = _INIT_B
    a0, hb = _word(p0, hb)
    a1, hb = _word(p1, hb)
    a2, hb = _word(p2, hb)
    a3, hb = _word(p3, hb)
    a4, hb = _word(p0, hb)
    a5, hb = _word(p1, hb)
    a6, hb = _word(p2, hb)
    a7, hb = _word(p3, hb)
    s_hi, s_lo = a0 | (a1 << _S32), a2 | (a3 << _S32)
    i_hi, i_lo = a4 | (a5 << _S32), a6 | (a7 << _S32)
    inc_hi = (i_hi << _ONE) | (i_lo >> np.uint64(63))
    inc_lo = (i_lo << _ONE) | _ONE
    hi, lo = _step(_ZERO, _ZERO, inc_hi, inc_lo)
    lo2 = lo + s_lo
    hi = hi + s_hi + (_ONE if lo2 < lo else _ZERO)
    hi, lo = _step(hi, lo2, inc_hi, inc_lo)
    hi, lo = _step(hi, lo, inc_hi, inc_lo)  # random(): one more step, then the output
    x = hi ^ lo
    rot = hi >> np.uint64(58)
    out = (x >> rot) | (x << ((np.uint64(64) - rot) & np.uint64(63)))
    return int(out >> np.uint64(11))


def uniform(seed: int, event: int, step: int) -> float:
    """:func:`draw53` as NumPy's ``random()`` returns it (for checks)."""
    return int(draw53(seed, event, step)) * 2.0**-53


def threshold(probability: float) -> int:
    """The integer ``t`` with ``k * 2**-53 < probability`` exactly when ``k < t`` (``k`` an
    integer in ``[0, 2**53)``): ``ceil(probability * 2**53)``, exact since scaling by a power of
    two is."""
    return math.ceil(probability * 2.0**53)
