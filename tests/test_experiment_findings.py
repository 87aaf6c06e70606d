"""Summary statistics and the three findings on hand-made rows: each verdict can go either way."""

from __future__ import annotations

import json

import pytest

from selfrepair.experiment.findings import check_findings, percentile, summarize


def row(
    strategy: str,
    *,
    table: str | None = None,
    recursion: str | None = None,
    weight: str = "0",
    route: str = "r1",
    encounters: int = 0,
    replacements: int = 0,
    replans: int = 0,
    latencies: tuple[tuple[str, int], ...] = (),
    actions: int = 10,
    reached: int = 1,
    extra: float = 1.0,
) -> dict[str, object]:
    variant = strategy if table is None else f"{strategy}[{table},{recursion}]"
    return {
        "key": f"{variant}-{weight}-{route}",
        "strategy": strategy,
        "variant": variant,
        "table": table,
        "recursion": recursion,
        "clearance_weight": weight,
        "maze": "m",
        "route": route,
        "faults": "FL:F",
        "fault_at": 0,
        "detection": "now",
        "replicate": 0,
        "reached": reached,
        "faulty_encounters": encounters,
        "replacements": replacements,
        "lookaheads": 0,
        "replans": replans,
        "repair_count": len(latencies),
        "actions_executed": actions,
        "repair_latencies_ns": json.dumps([lat for _, lat in latencies]),
        "repair_sources": json.dumps([src for src, _ in latencies]),
        "repair_latency_total_ns": sum(lat for _, lat in latencies),
        "compute_per_action_ns": 1000.0 * (1 + len(latencies)),
        "extra_ticks": extra,
        "plan_distance": 4,
    }


def test_percentile_nearest_rank() -> None:
    assert percentile([], 0.5) is None
    assert percentile([3.0, 1.0, 2.0], 0.5) == 2.0
    assert percentile(list(range(1, 101)), 0.99) == 99.0


def test_summary_numbers() -> None:
    rows = [
        row("replan", encounters=1, replans=1, latencies=(("replan", 900_000),)),
        row(
            "replan",
            route="r2",
            encounters=1,
            replans=1,
            latencies=(("replan", 700_000),),
            reached=0,
            extra=None,
        ),  # type: ignore[arg-type]
        row(
            "replacement",
            table="handwritten",
            recursion="flat",
            encounters=4,
            replacements=3,
            replans=1,
            latencies=(("replacement", 10_000),) * 3 + (("replan", 800_000),),
        ),
    ]
    by_label = {s.label: s for s in summarize(rows)}
    replan = by_label["replan"]
    assert (replan.missions, replan.completed) == (2, 1)
    assert replan.latency_median_us == 700.0 and replan.replans_per_mission == 1.0
    assert replan.resolved_locally == 0.0 and replan.extra_ticks_mean == 1.0
    table = by_label["replacement[handwritten,flat]"]
    assert table.resolved_locally == 0.75 and table.latency_median_us == 10.0
    assert summarize(rows)[0].label == "replan"


def _finding(rows: list[dict[str, object]], number: int) -> tuple[str, str]:
    finding = check_findings(rows)[number - 1]  # type: ignore[arg-type]
    return finding.verdict, finding.evidence


@pytest.mark.parametrize(("table_ns", "verdict"), [(5_000, "held"), (600_000, "not held")])
def test_finding_1_compares_repair_time_per_action(table_ns: int, verdict: str) -> None:
    rows = [
        row("replan", encounters=1, replans=1, latencies=(("replan", 1_000_000),)),
        row(
            "replacement",
            table="handwritten",
            recursion="flat",
            encounters=2,
            replacements=2,
            latencies=(("replacement", table_ns),) * 2,
        ),
    ]
    assert _finding(rows, 1)[0] == verdict


def test_finding_1_part_2_can_fail_and_untested_without_pairs() -> None:
    base = [
        row("replan", encounters=1, replans=1, latencies=(("replan", 1_000_000),)),
        row(
            "replacement",
            table="handwritten",
            recursion="flat",
            route="r1",
            encounters=2,
            replacements=2,
            latencies=(("replacement", 1_000),) * 2,
        ),
        row("replan", route="r2", encounters=1, replans=1, latencies=(("replan", 1_000_000),)),
    ]
    slower = row(
        "replacement",
        table="handwritten",
        recursion="flat",
        route="r2",
        encounters=3,
        replacements=2,
        replans=1,
        latencies=(("replacement", 1_000),) * 2 + (("replan", 3_000_000),),
    )
    verdict, evidence = _finding([*base, slower], 1)
    assert verdict == "not held" and "3.00x" in evidence
    assert _finding([row("replan")], 1)[0] == "not tested"


def test_finding_2_clearance() -> None:
    def table(weight: str, replaced: int) -> dict[str, object]:
        return row(
            "replacement",
            table="handwritten",
            recursion="flat",
            weight=weight,
            encounters=10,
            replacements=replaced,
        )

    assert _finding([table("0", 8), table("1", 9)], 2)[0] == "held"
    assert _finding([table("0", 8), table("1", 8)], 2)[0] == "not held"
    assert _finding([table("0", 10), table("1", 10)], 2)[0] == "not tested"  # no room to rise
    assert _finding([table("0", 8)], 2)[0] == "not tested"
    none = row("replacement", table="handwritten", recursion="flat", weight="1")  # 0 encounters
    assert _finding([table("0", 5), none], 2)[0] == "not tested"  # nothing to compare at w=1
    assert _finding([none, {**table("1", 9), "key": "x"}], 2)[0] == "not tested"


def test_finding_3_tables() -> None:
    def table(name: str, replaced: int) -> dict[str, object]:
        return row(
            "replacement", table=name, recursion="flat", encounters=10, replacements=replaced
        )

    assert _finding([table("handwritten", 7), table("generated-indexed", 9)], 3)[0] == "held"
    assert _finding([table("handwritten", 7), table("generated-indexed", 6)], 3)[0] == "not held"
    assert _finding([table("handwritten", 10), table("generated-indexed", 10)], 3)[0] == "held"
    assert _finding([table("handwritten", 7)], 3)[0] == "not tested"
    quiet = row("replacement", table="generated-indexed", recursion="flat")  # 0 encounters
    assert _finding([table("handwritten", 7), quiet], 3)[0] == "not tested"
