"""The statistics every report uses: one percentile, one median, one interval, one bootstrap
(and its paired cut).

Definitions (one each, used by single-robot rows, team rows, summaries, findings and plots):

* :func:`percentile` - the **nearest-rank** percentile: the smallest value of the data with at
  least the fraction ``q`` of the data at or below it (rank ``ceil(q * n)``, 1-based). It is
  always a value of the data. The 99th percentile of fewer than 100 values is their maximum,
  of exactly 100 the second largest. (numpy's ``method="lower"`` instead takes index
  ``floor(q * (n - 1))``, the second largest of any ``2 <= n <= 100`` values: not this.)
* :func:`lower_median` - the lower median, ``percentile(values, 1/2)``: the middle value of an odd
  count, the lower of the two middle ones of an even count; a value of the data, so a median of
  integer nanoseconds stays an integer.
* :class:`Interval` and :func:`bootstrap_interval` - an estimate with its 95% percentile-bootstrap
  interval over a sample whose unit is the **mission** (repairs inside one mission are not
  independent, missions are) or the episode. The bootstrap is seeded (:data:`BOOTSTRAP_SEED` by
  default), so a report recomputed from the same rows prints the same intervals.
* :func:`wilson_interval` - the Wilson score interval of a success rate (good at rates near 0
  and 1, where the normal approximation fails; scipy, imported inside).

Misuse (an empty sample, a fraction outside [0, 1]) raises
:class:`~selfrepair.errors.ProblemError`; no data is an outcome the caller handles first.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TypeVar

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_SEED",
    "LEVEL",
    "STATISTICS",
    "Interval",
    "bootstrap_interval",
    "lower_median",
    "paired_cut_interval",
    "percentile",
    "wilson_interval",
]

N = TypeVar("N", int, float)

LEVEL = 0.95
"""Confidence level of every interval."""

BOOTSTRAP_RESAMPLES = 2000
"""Bootstrap resamples per interval (the percentile method's error at 2000 is about 1% of the
interval's width)."""

BOOTSTRAP_SEED = 20_061_201
"""Seed of every bootstrap: intervals are reproducible from the stored rows."""


def percentile(values: Sequence[N], q: float) -> N:
    """The nearest-rank ``q`` quantile of ``values`` (``q`` in [0, 1], e.g. 0.99): the smallest
    value with at least ``q`` of the values at or below it. ``q`` is read as the decimal it was
    written as (0.07 is 7/100, not the binary float just above it), so ranks are exact."""
    if not values:
        raise ProblemError("percentile of no values: expected at least one value")
    if not 0 <= q <= 1:
        raise ProblemError(f"percentile: expected a fraction q in [0, 1], got {q}")
    ordered = sorted(values)
    rank = math.ceil(Fraction(q).limit_denominator(1_000_000) * len(ordered))
    return ordered[max(rank, 1) - 1]


def lower_median(values: Sequence[N]) -> N:
    """The lower median of ``values``: the middle value of an odd count, the lower middle one
    of an even count (the nearest-rank 50th percentile)."""
    return percentile(values, 0.5)


@dataclass(frozen=True, slots=True)
class Interval:
    """An estimate with its interval at confidence ``level`` (``low`` and ``high``; equal to the
    estimate for a sample of one) and the sample size it came from."""

    estimate: float
    low: float
    high: float
    n: int
    level: float = LEVEL

    def scaled(self, factor: float) -> Interval:
        """The same interval in other units (e.g. ns to µs)."""
        return Interval(
            self.estimate * factor, self.low * factor, self.high * factor, self.n, self.level
        )

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


def _median(sample: npt.NDArray[np.float64], axis: int = -1) -> npt.NDArray[np.float64]:
    return np.asarray(np.median(sample, axis=axis), dtype=np.float64)


def _mean(sample: npt.NDArray[np.float64], axis: int = -1) -> npt.NDArray[np.float64]:
    return np.asarray(np.mean(sample, axis=axis), dtype=np.float64)


STATISTICS: dict[str, Callable[..., npt.NDArray[np.float64]]] = {
    "median": _median,
    "mean": _mean,
}
"""The statistics :func:`bootstrap_interval` knows (vectorised along the last axis). Its
``median`` is the usual one (the mean of the two middle values of an even count), because the
bootstrap distribution of a lower median is needlessly lumpy."""


def bootstrap_interval(
    values: Sequence[float],
    statistic: str = "median",
    *,
    level: float = LEVEL,
    seed: int = BOOTSTRAP_SEED,
    resamples: int = BOOTSTRAP_RESAMPLES,
) -> Interval | None:
    """The ``statistic`` of ``values`` with its percentile-bootstrap interval at ``level``;
    ``None`` for no values. With one value, or all values equal, the interval is the value itself.

    The percentile bootstrap: ``resamples`` samples of the same size drawn with replacement
    (``numpy.random.default_rng(seed)``), the statistic of each, and their ``(1 - level) / 2``
    and ``(1 + level) / 2`` quantiles (as ``scipy.stats.bootstrap(method="percentile")``
    computes it, vectorised here in numpy, which is an order of magnitude faster for the many
    small samples of a summary)."""
    if not values:
        return None
    sample = np.asarray(values, dtype=np.float64)
    fn = STATISTICS[statistic]
    estimate = float(fn(sample))
    if len(sample) == 1 or np.all(sample == sample[0]):
        return Interval(estimate, estimate, estimate, len(sample), level)
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(sample), size=(resamples, len(sample)))
    stats = fn(sample[draws], axis=-1)
    tail = (1 - level) / 2
    low, high = np.quantile(stats, [tail, 1 - tail])
    return Interval(
        estimate, min(float(low), estimate), max(float(high), estimate), len(sample), level
    )


def paired_cut_interval(
    before: Sequence[float],
    after: Sequence[float],
    statistic: str = "median",
    *,
    level: float = LEVEL,
    seed: int = BOOTSTRAP_SEED,
    resamples: int = BOOTSTRAP_RESAMPLES,
) -> Interval | None:
    """The cut ``1 - stat(after) / stat(before)`` of the paired samples ``before`` and
    ``after`` (pair ``i`` is ``before[i]`` and ``after[i]``: the same unit measured twice), with
    its percentile-bootstrap interval at ``level``; ``stat`` is a statistic of
    :data:`STATISTICS`. A cut of 0.3 is 30% less after than before.

    The bootstrap resamples the **pairs** together: ``resamples`` draws of ``len(before)``
    pair indices with replacement (``numpy.random.default_rng(seed)``), the cut of each drawn
    pair sample, and their ``(1 - level) / 2`` and ``(1 + level) / 2`` quantiles; the interval
    always holds the estimate (as :func:`bootstrap_interval`'s). Values may be ``math.inf``
    (e.g. a mission that never isolated a fault: more than any finite count), which the median
    orders last; a cut is defined only when both statistics are finite and ``stat(before) >
    0``, and resamples whose cut is undefined are left out of the quantiles.

    ``None`` for no pairs or an undefined cut of the samples themselves. Samples of different
    lengths or an unknown statistic raise :class:`~selfrepair.errors.ProblemError`."""
    if len(before) != len(after):
        raise ProblemError(
            f"paired cut: expected as many values after as before, got {len(after)} after "
            f"and {len(before)} before"
        )
    if statistic not in STATISTICS:
        raise ProblemError(
            f"paired cut: expected a statistic in {', '.join(STATISTICS)}, got {statistic!r}"
        )
    if not before:
        return None
    fn = STATISTICS[statistic]
    b = np.asarray(before, dtype=np.float64)
    a = np.asarray(after, dtype=np.float64)
    estimate = _cut(fn(b), fn(a))
    if not np.isfinite(estimate):
        return None
    cut = float(estimate)
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(b), size=(resamples, len(b)))
    cuts = _cut(fn(b[draws], axis=-1), fn(a[draws], axis=-1))
    cuts = cuts[np.isfinite(cuts)]
    tail = (1 - level) / 2
    low, high = np.quantile(cuts, [tail, 1 - tail]) if len(cuts) else (cut, cut)
    return Interval(cut, min(float(low), cut), max(float(high), cut), len(b), level)


def _cut(
    before: npt.NDArray[np.float64] | np.float64, after: npt.NDArray[np.float64] | np.float64
) -> npt.NDArray[np.float64]:
    """``1 - after / before`` where both are finite and ``before > 0``, else ``nan``."""
    b = np.asarray(before, dtype=np.float64)
    a = np.asarray(after, dtype=np.float64)
    defined = np.isfinite(a) & np.isfinite(b) & (b > 0)
    safe = np.where(defined, b, 1.0)
    return np.where(defined, 1.0 - np.where(defined, a, 0.0) / safe, np.nan)


def wilson_interval(successes: int, trials: int, level: float = LEVEL) -> Interval | None:
    """The success rate ``successes / trials`` with its Wilson score interval at ``level``
    (``scipy.stats.binomtest(...).proportion_ci(method="wilson")``); ``None`` for no trials."""
    if trials < 1:
        return None
    from scipy.stats import binomtest

    ci = binomtest(successes, trials).proportion_ci(confidence_level=level, method="wilson")
    return Interval(successes / trials, float(ci.low), float(ci.high), trials, level)
