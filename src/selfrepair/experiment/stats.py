"""Paired tests for the findings: the pairs of missions in the same situation under two strategies.

The unit of every test here is the pair of missions (repairs inside one mission are not
independent, missions are). Intervals, the bootstrap, percentiles and medians are the ground
module's (:mod:`selfrepair.stats`).

* :func:`sign_test` - the exact one-sided sign test on paired outcomes (the binomial tail over the
  pairs that differ), used for yes/no outcomes such as "completed without replan";
* :func:`wilcoxon_greater` - the one-sided Wilcoxon signed-rank test on paired differences
  (``scipy.stats.wilcoxon``; scipy is imported inside, so importing this module stays cheap).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction

__all__ = ["sign_test", "wilcoxon_greater"]


def sign_test(better: int, worse: int) -> float:
    """One-sided exact sign test: the probability of at least ``better`` successes among the
    ``better + worse`` pairs that differ, if each direction were equally likely (1.0 when no pair
    differs). Small means "better" is more frequent than chance allows. (The binomial tail,
    computed exactly with integers: ``scipy.stats.binomtest(..., alternative="greater")``.)"""
    n = better + worse
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, k) for k in range(better, n + 1))
    return float(Fraction(tail, 2**n))


def wilcoxon_greater(differences: Sequence[float]) -> float:
    """One-sided Wilcoxon signed-rank test that the paired ``differences`` are centred above 0
    (zero differences dropped; 1.0 when none is left)."""
    nonzero = [d for d in differences if d != 0]
    if not nonzero:
        return 1.0
    from scipy.stats import wilcoxon

    return float(wilcoxon(nonzero, alternative="greater").pvalue)
