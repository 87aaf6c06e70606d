"""The one statistics module (selfrepair.stats): nearest-rank percentile and lower median on
hand-made samples with known answers, properties, and the team rows that use them."""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.errors import ProblemError
from selfrepair.execution.metrics import latency_stats
from selfrepair.stats import (
    Interval,
    bootstrap_interval,
    lower_median,
    paired_cut_interval,
    percentile,
)
from selfrepair.team import engine
from selfrepair.team.metrics import team_row
from selfrepair.team.result import RepairOutcome, TeamOptions
from selfrepair.team.scenario import resolve_scenario


def test_percentile_known_answers() -> None:
    assert percentile([3, 1, 2], 0.5) == 2
    assert percentile([3.0, 1.0, 2.0], 0.5) == 2.0
    assert percentile(list(range(1, 101)), 0.99) == 99  # 99 of 100 values at or below 99
    assert percentile(list(range(1, 11)), 0.99) == 10  # fewer than 100 values: the largest
    assert percentile(list(range(1, 101)), 0.07) == 7  # 0.07 read as 7/100, not 0.0700...01
    assert percentile([5, 9], 0.0) == 5 and percentile([5, 9], 1.0) == 9


def test_lower_median_is_a_value_of_the_data() -> None:
    assert lower_median([4, 1, 3, 2]) == 2
    assert lower_median([7]) == 7
    assert isinstance(lower_median([10, 20]), int)


def test_misuse_raises() -> None:
    with pytest.raises(ProblemError, match="no values"):
        percentile([], 0.5)
    with pytest.raises(ProblemError, match=r"\[0, 1\]"):
        percentile([1], 99)


@given(st.lists(st.integers(-1000, 1000), min_size=1, max_size=300), st.floats(0, 1))
def test_nearest_rank_definition(values: list[int], q: float) -> None:
    """The smallest value with at least q of the values at or below it."""
    p = percentile(values, q)
    assert p in values
    share = sum(v <= p for v in values) / len(values)
    assert share >= q - 1e-6
    below = [v for v in values if v < p]
    assert not below or sum(v <= max(below) for v in values) / len(values) < q + 1e-6


def test_single_robot_latency_stats_use_the_same_definition() -> None:
    stats = latency_stats([50, 10, 40, 20, 30])
    assert (stats.median_ns, stats.p99_ns, stats.max_ns) == (30, 50, 50)


def test_bootstrap_interval_of_a_constant_sample_is_a_point() -> None:
    assert bootstrap_interval([2.0, 2.0, 2.0]) == Interval(2.0, 2.0, 2.0, 3)
    assert bootstrap_interval([]) is None
    interval = bootstrap_interval([1.0, 2.0, 3.0, 4.0, 100.0])
    assert interval is not None and interval.low <= interval.estimate <= interval.high


def test_paired_cut_of_two_pairs_has_a_known_interval() -> None:
    """Pairs (1, 0) and (1, 1): a resample holds both copies of one pair (probability 1/4
    each, cut 1 or 0) or one of each (1/2, cut 0.5); its 2.5% and 97.5% quantiles are 0 and 1."""
    for statistic in ("median", "mean"):
        cut = paired_cut_interval([1.0, 1.0], [0.0, 1.0], statistic)
        assert cut is not None
        assert (cut.estimate, cut.low, cut.high, cut.n) == (0.5, 0.0, 1.0, 2)


def test_paired_cut_resamples_the_pairs_together() -> None:
    """Every ``after`` is half its ``before``: every resample of pairs cuts by exactly a half
    (resampled apart, the two samples' statistics would scatter)."""
    before = [1.0, 2.0, 3.0, 4.0, 10.0, 40.0]
    after = [b / 2 for b in before]
    for statistic in ("median", "mean"):
        cut = paired_cut_interval(before, after, statistic)
        assert cut is not None
        assert cut.estimate == pytest.approx(0.5)
        assert cut.low == pytest.approx(0.5) and cut.high == pytest.approx(0.5)


def test_paired_cut_undefined_and_misuse() -> None:
    assert paired_cut_interval([], []) is None
    assert paired_cut_interval([0.0, 0.0], [1.0, 2.0]) is None  # nothing before to cut
    assert paired_cut_interval([math.inf] * 3, [1.0, 2.0, 3.0]) is None  # median before infinite
    # an infinite value counts as more than any finite one: the median stays finite
    cut = paired_cut_interval([3.0, 3.0, math.inf], [2.0, 2.0, 2.0])
    assert cut is not None and cut.estimate == pytest.approx(1 / 3)
    with pytest.raises(ProblemError, match="as many values"):
        paired_cut_interval([1.0, 2.0], [1.0])
    with pytest.raises(ProblemError, match="median, mean"):
        paired_cut_interval([1.0], [1.0], "mode")


_counts = st.lists(
    st.tuples(st.integers(1, 60), st.integers(0, 60)), min_size=1, max_size=40
)


@given(_counts, st.sampled_from(["median", "mean"]), st.integers(0, 2**32 - 1))
def test_paired_cut_interval_holds_its_estimate_and_is_seeded(
    pairs: list[tuple[int, int]], statistic: str, seed: int
) -> None:
    before = [float(b) for b, _ in pairs]
    after = [float(a) for _, a in pairs]
    cut = paired_cut_interval(before, after, statistic, seed=seed, resamples=200)
    assert cut is not None
    assert cut.low <= cut.estimate <= cut.high and cut.n == len(pairs)
    assert paired_cut_interval(before, after, statistic, seed=seed, resamples=200) == cut


def test_team_p99_of_fewer_than_100_repairs_is_the_slowest() -> None:
    """Issue 29 item 16: numpy's method="lower" made p99 the second-largest value."""
    result = engine.run_team(
        resolve_scenario("three-robots"), TeamOptions(strategy="team-replacement")
    )
    repaired = [r for r in result.repairs if r.outcome is RepairOutcome.REPAIRED]
    assert repaired
    template = repaired[0]
    latencies = [406_372, 184_015, 120_000, 90_000, 15_000]
    repairs = tuple(
        dataclasses.replace(template, latency_ns=ns, cpu_ns=ns // 2) for ns in latencies
    )
    row = team_row(dataclasses.replace(result, repairs=repairs))
    assert row["repair_latency_p99_ns"] == 406_372 == row["repair_latency_max_ns"]
    assert row["repair_latency_median_ns"] == 120_000
    assert row["repair_cpu_p99_ns"] == 406_372 // 2
