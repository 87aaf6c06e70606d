"""Statistics for the findings and the summary: intervals and paired tests over missions.

The unit of every statistic here is the **mission** (or the pair of missions in the same situation
under two strategies): repairs inside one mission are not independent, missions are. Everything
is deterministic: bootstrap resampling uses a fixed seed (:data:`BOOTSTRAP_SEED`), so a report
recomputed from the same database prints the same intervals.

* :func:`bootstrap_interval` - a percentile bootstrap 95% interval of a statistic (median or mean)
  of one sample;
* :func:`sign_test` - the exact one-sided sign test on paired outcomes (the binomial tail over the
  pairs that differ), used for yes/no outcomes such as "completed without replan";
* :func:`wilcoxon_greater` - the one-sided Wilcoxon signed-rank test on paired differences
  (``scipy.stats.wilcoxon``; scipy is imported inside, so importing this module stays cheap).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import numpy.typing as npt

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_SEED",
    "LEVEL",
    "Interval",
    "bootstrap_interval",
    "lower_median",
    "sign_test",
    "wilcoxon_greater",
]

LEVEL = 0.95
"""Confidence level of every interval."""

BOOTSTRAP_RESAMPLES = 2000
"""Bootstrap resamples per interval (the percentile method's error at 2000 is about 1% of the
interval's width)."""

BOOTSTRAP_SEED = 20_061_201
"""Seed of every bootstrap: intervals are reproducible from the stored rows."""


@dataclass(frozen=True, slots=True)
class Interval:
    """An estimate with its 95% interval (``low`` and ``high``; equal to the estimate for a
    sample of one) and the sample size it came from."""

    estimate: float
    low: float
    high: float
    n: int

    def scaled(self, factor: float) -> Interval:
        """The same interval in other units (e.g. ns to µs)."""
        return Interval(self.estimate * factor, self.low * factor, self.high * factor, self.n)

    def text(self, digits: int = 0, unit: str = "") -> str:
        """``12 [10, 15]``: estimate and interval, rounded to ``digits`` decimals."""
        return (
            f"{_num(self.estimate, digits)}{unit} "
            f"[{_num(self.low, digits)}, {_num(self.high, digits)}]"
        )


def _num(value: float, digits: int) -> str:
    if digits == 0 and abs(value) >= 10:
        return f"{value:,.0f}"
    if digits == 0:
        return f"{value:.1f}"
    return f"{value:.{digits}f}"


def lower_median(values: Sequence[float]) -> float:
    """The lower median (a value of the data; the middle one for an odd count)."""
    ordered = sorted(values)
    return float(ordered[(len(ordered) - 1) // 2])


def _median(sample: npt.NDArray[np.float64], axis: int = -1) -> npt.NDArray[np.float64]:
    return np.asarray(np.median(sample, axis=axis), dtype=np.float64)


def _mean(sample: npt.NDArray[np.float64], axis: int = -1) -> npt.NDArray[np.float64]:
    return np.asarray(np.mean(sample, axis=axis), dtype=np.float64)


STATISTICS: dict[str, Callable[..., npt.NDArray[np.float64]]] = {
    "median": _median,
    "mean": _mean,
}
"""The statistics :func:`bootstrap_interval` knows (vectorised along the last axis)."""


def bootstrap_interval(values: Sequence[float], statistic: str = "median") -> Interval | None:
    """The ``statistic`` of ``values`` with its percentile-bootstrap 95% interval; ``None`` for
    no values. With one value, or all values equal, the interval is the value itself.

    The percentile bootstrap: :data:`BOOTSTRAP_RESAMPLES` samples of the same size drawn with
    replacement, the statistic of each, and their 2.5% and 97.5% quantiles (as
    ``scipy.stats.bootstrap(method="percentile")`` computes it, vectorised here in numpy,
    which is an order of magnitude faster for the many small samples of a summary)."""
    if not values:
        return None
    sample = np.asarray(values, dtype=np.float64)
    fn = STATISTICS[statistic]
    estimate = float(fn(sample))
    if len(sample) == 1 or np.all(sample == sample[0]):
        return Interval(estimate, estimate, estimate, len(sample))
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    draws = rng.integers(0, len(sample), size=(BOOTSTRAP_RESAMPLES, len(sample)))
    stats = fn(sample[draws], axis=-1)
    tail = (1 - LEVEL) / 2
    low, high = np.quantile(stats, [tail, 1 - tail])
    return Interval(estimate, min(float(low), estimate), max(float(high), estimate), len(sample))


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
