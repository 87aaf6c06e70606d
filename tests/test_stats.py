"""The one statistics module (selfrepair.stats): nearest-rank percentile and lower median on
hand-made samples with known answers, properties, and the team rows that use them."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.errors import ProblemError
from selfrepair.execution.metrics import latency_stats
from selfrepair.stats import Interval, bootstrap_interval, lower_median, percentile
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
