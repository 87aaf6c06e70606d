"""Summary statistics and the findings on hand-made rows: each outcome can be reached, and too few
pairs make every finding INCONCLUSIVE."""

from __future__ import annotations

import json

import pytest

from selfrepair.experiment.findings import (
    MIN_PAIRS,
    Outcome,
    check_findings,
    reference_note,
    summarize,
)
from selfrepair.experiment.summary import fault_set_bite
from selfrepair.stats import percentile


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
    faults: str = "FL:F",
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
        "faults": faults,
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
        "ticks_over_optimum": None if extra is None else extra + 1.0,
        "plan_distance": 4,
        "plan_distance_motion": 2,
        "completed_without_replan": int(reached == 1 and replans == 0),
        "repair_compute_ns": sum(lat for _, lat in latencies),
        "first_repair_ns": latencies[0][1] if latencies else None,
        "cold_first_repair_ns": 10 * latencies[0][1] if latencies else None,
    }


def test_percentile_nearest_rank() -> None:
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
    assert (replan.missions, replan.completed, replan.met_fault, replan.no_replan) == (2, 1, 2, 0)
    assert replan.latency_median_us == 700.0 and replan.replans_per_mission == 1.0
    assert replan.resolved_locally == 0.0
    assert replan.over_optimum is not None and replan.over_optimum.estimate == 2.0
    assert replan.repair_compute_us is not None and replan.repair_compute_us.estimate == 800.0
    assert replan.cold_first_repair_us is not None
    assert replan.cold_first_repair_us.estimate == 8000.0
    table = by_label["replacement[handwritten,flat]"]
    assert table.resolved_locally == 0.75 and table.latency_median_us == 10.0
    assert table.no_replan == 0 and table.plan_distance_motion_mean == 2.0
    assert summarize(rows)[0].label == "replan"
    cells = dict(zip(table.HEADERS, table.cells(), strict=True))
    assert cells["no replan"] == "0/1 (0.0%)"
    assert cells["repair compute/mission µs"] == "830 [830, 830]"


def _outcome(rows: list[dict[str, object]], number: str) -> Outcome:
    found = {f.number: f for f in check_findings(rows)}  # type: ignore[arg-type]
    return found[number].outcome


def _situations(n: int) -> list[str]:
    return [f"r{i}" for i in range(n)]


def _replan_rows(routes: list[str]) -> list[dict[str, object]]:
    return [
        row("replan", route=r, encounters=1, replans=1, latencies=(("replan", 1_000_000),))
        for r in routes
    ]


@pytest.mark.parametrize(
    ("table_ns", "outcome"),
    [(5_000, Outcome.HELD), (600_000, Outcome.NOT_HELD), (50_000, Outcome.INCONCLUSIVE)],
)
def test_finding_1_compares_repair_compute_per_mission(table_ns: int, outcome: Outcome) -> None:
    routes = _situations(20)
    noisy = [table_ns, table_ns * 3] if outcome is Outcome.INCONCLUSIVE else [table_ns]
    rows = _replan_rows(routes) + [
        row(
            "replacement",
            table="handwritten",
            recursion="flat",
            route=r,
            encounters=2,
            replacements=2,
            latencies=(("replacement", noisy[i % len(noisy)] // 2),) * 2,
        )
        for i, r in enumerate(routes)
    ]
    assert _outcome(rows, "1") is outcome


def test_findings_compare_with_variant_replan_only() -> None:
    """Faster replanners of other variants in the same situations (stored after the reference,
    so a looser choice of reference would pick them) change no finding; the note names them."""
    routes = _situations(20)
    table = [
        row(
            "replacement",
            table="handwritten",
            recursion="flat",
            route=r,
            encounters=1,
            replacements=1,
            latencies=(("replacement", 5_000),),
        )
        for r in routes
    ]
    others = []
    for strategy, variant in (("replan", "replan[python]"), ("dstar-lite", "dstar-lite")):
        for r in routes:
            other = row(strategy, route=r, encounters=1, replans=1, latencies=(("replan", 9_000),))
            other["variant"] = variant
            others.append(other)
    rows = _replan_rows(routes) + table
    assert _outcome(rows, "1") is Outcome.HELD and reference_note(rows) is None  # type: ignore[arg-type]
    assert _outcome(rows + others, "1") is Outcome.HELD
    assert _outcome(rows + others, "1b") is _outcome(rows, "1b")
    note = reference_note(rows + others)  # type: ignore[arg-type]
    assert note is not None and "variant replan only" in note
    assert "dstar-lite, replan[python] do not enter them" in note


def test_finding_1b_replanning_time() -> None:
    routes = _situations(15)

    def slower(r: str, ns: int) -> dict[str, object]:
        return row(
            "replacement",
            table="handwritten",
            recursion="flat",
            route=r,
            encounters=3,
            replacements=2,
            replans=1,
            latencies=(("replacement", 1_000),) * 2 + (("replan", ns),),
        )

    assert _outcome(_replan_rows(routes) + [slower(r, 3_000_000) for r in routes], "1b") == (
        Outcome.NOT_HELD
    )
    assert _outcome(_replan_rows(routes) + [slower(r, 300_000) for r in routes], "1b") == (
        Outcome.HELD
    )


def _flat(
    route: str,
    weight: str = "0",
    ok: bool = True,
    table: str = "handwritten",
    recursion: str = "flat",
) -> dict[str, object]:
    return row(
        "replacement",
        table=table,
        recursion=recursion,
        weight=weight,
        route=route,
        encounters=10,
        replacements=10 if ok else 9,
        replans=0 if ok else 1,
    )


def test_finding_2_clearance_by_paired_missions() -> None:
    routes = _situations(30)
    base = [_flat(r, ok=i % 2 == 0) for i, r in enumerate(routes)]  # 15 of 30 without a replan
    rises = [_flat(r, "1", ok=True) for r in routes]
    same = [_flat(r, "1", ok=i % 2 == 0) for i, r in enumerate(routes)]
    falls = [_flat(r, "1", ok=False) for r in routes]
    assert _outcome(base + rises, "2") is Outcome.HELD
    assert _outcome(base + same, "2") is Outcome.NOT_HELD  # no rise, interval [0, 0]
    assert _outcome(base + falls, "2") is Outcome.NOT_HELD
    full = [_flat(r) for r in routes]
    # a baseline at 100% leaves no room: neither held nor refuted
    assert _outcome(full + [_flat(r, "1") for r in routes], "2") is Outcome.INCONCLUSIVE
    assert _outcome(base, "2") is Outcome.NOT_APPLICABLE  # no weight above 0: left out


def test_finding_3_tables_by_paired_missions() -> None:
    routes = _situations(30)
    hand = [_flat(r, ok=i % 3 == 0) for i, r in enumerate(routes)]
    better = [_flat(r, table="generated-indexed") for r in routes]
    worse = [_flat(r, ok=False, table="generated-indexed") for r in routes]
    assert _outcome(hand + better, "3") is Outcome.HELD
    assert _outcome(hand + worse, "3") is Outcome.NOT_HELD
    assert _outcome(hand, "3") is Outcome.NOT_APPLICABLE  # no other table: left out


def test_finding_4_primitive_against_guarded() -> None:
    routes = _situations(30)
    guarded = [_flat(r, recursion="guarded") for r in routes]
    bad = [_flat(r, ok=i % 2 == 0, recursion="primitive") for i, r in enumerate(routes)]
    good = [_flat(r, recursion="primitive") for r in routes]
    assert _outcome(guarded + bad, "4") is Outcome.HELD
    assert _outcome(guarded + good, "4") is Outcome.NOT_HELD  # as good as guarded: not "bad"


def test_too_few_pairs_make_every_finding_inconclusive() -> None:
    """The same strong effects as above, on fewer pairs than MIN_PAIRS: nothing is decided."""
    routes = _situations(MIN_PAIRS - 1)
    rows = _replan_rows(routes)
    for i, r in enumerate(routes):
        rows += [
            _flat(r, ok=i % 3 == 0),
            _flat(r, "2"),
            _flat(r, table="generated-indexed"),
            _flat(r, recursion="guarded"),
            _flat(r, ok=False, recursion="primitive"),
        ]
        rows[-5]["repair_compute_ns"] = 5  # negligible against 1 ms...
    findings = check_findings(rows)  # type: ignore[arg-type]
    assert [f.number for f in findings] == ["1", "1b", "2", "3", "4"]
    assert all(f.outcome is Outcome.INCONCLUSIVE for f in findings), [
        (f.number, f.outcome) for f in findings
    ]
    # ... and one pair more decides them
    more = _situations(MIN_PAIRS + 20)
    rows = _replan_rows(more) + [_flat(r, ok=i % 3 == 0) for i, r in enumerate(more)]
    rows += [_flat(r, "2") for r in more]
    assert _outcome(rows, "2") is Outcome.HELD


def test_findings_print_as_short_paragraphs() -> None:
    routes = _situations(30)
    rows = [_flat(r, ok=i % 2 == 0) for i, r in enumerate(routes)]
    rows += [_flat(r, "1") for r in routes]
    finding = {f.number: f for f in check_findings(rows)}["2"]  # type: ignore[arg-type]
    text = finding.paragraph()
    assert text.startswith("Finding 2: HELD.")
    assert all(len(line) <= 96 for line in text.splitlines())
    assert "\n  - replacement[handwritten,flat] w=1 vs w=0: 30 against 15 of 30" in text
    assert finding.markdown().startswith("**Finding 2: HELD.**")


def test_fault_set_bite_counts_missions_that_met_a_fault() -> None:
    rows = [
        row("replan", faults="FL:F", encounters=1),
        row("replan", route="r2", faults="FL:F"),
        row("replacement", table="handwritten", recursion="flat", faults="RL:F", encounters=3),
    ]
    bites = {b.faults: b for b in fault_set_bite(rows)}  # type: ignore[arg-type]
    assert (bites["FL:F"].missions, bites["FL:F"].met, bites["FL:F"].replan_met) == (2, 1, 1)
    assert (bites["RL:F"].missions, bites["RL:F"].met, bites["RL:F"].replan_missions) == (1, 1, 0)
