"""Whole-plan rewriting as an option: experiment files, mission keys, ``selfrepair run
--rewrite``, the summary columns and finding 1 checked apart for the rewriting robot."""

from __future__ import annotations

import json

import pytest

from selfrepair.cli import main
from selfrepair.errors import ConfigError, ProblemError
from selfrepair.experiment.config import parse_config
from selfrepair.experiment.findings import (
    Finding,
    Outcome,
    Row,
    StrategySummary,
    check_findings,
    is_rewrite,
    summarize,
)
from selfrepair.experiment.missions import expand, to_spec
from selfrepair.repair.strategies import StrategyOptions

CONFIG = """\
name = "rw"

[[mazes]]
bundled = "narrow-short"

[faults]
sets = ["FL:F"]

[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
"""


def _variants(text: str) -> list[str]:
    return sorted({dict(m.labels)["variant"] for m in expand(parse_config(text))})  # type: ignore[misc]


@pytest.mark.parametrize(
    ("line", "variants"),
    [
        ("", ["replacement[handwritten,flat]"]),
        ("rewrite = false", ["replacement[handwritten,flat]"]),
        ("rewrite = true", ["replacement[handwritten,flat,rewrite]"]),
        (
            "rewrite = [false, true]",
            ["replacement[handwritten,flat,rewrite]", "replacement[handwritten,flat]"],
        ),
    ],
)
def test_rewrite_variants(line: str, variants: list[str]) -> None:
    assert _variants(CONFIG + line + "\n") == variants


def test_variants_without_rewrite_keep_their_keys() -> None:
    plain = {m.key for m in expand(parse_config(CONFIG))}
    both = expand(parse_config(CONFIG + "rewrite = [false, true]\n"))
    assert plain < {m.key for m in both}
    rewriting = [m for m in both if m.key not in plain]
    assert len(rewriting) == len(plain) == 4  # the four bundled routes
    assert all(to_spec(m).options.rewrite is True for m in rewriting)
    assert all(to_spec(m).options.rewrite is False for m in both if m.key in plain)


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ('rewrite = "yes"', "rewrite"),
        ("rewrite = []", "non-empty list"),
        ('rewrite = [true, "no"]', "list of them"),
    ],
)
def test_bad_rewrite_values_name_the_key(line: str, expected: str) -> None:
    with pytest.raises(ConfigError, match=expected) as info:
        parse_config(CONFIG + line + "\n")
    assert "strategies[0].rewrite" in str(info.value)


def test_rewrite_is_for_replacement_only() -> None:
    text = CONFIG.replace('name = "replacement"', 'name = "lookahead"') + "rewrite = true\n"
    with pytest.raises(ConfigError, match="replacement strategy only"):
        parse_config(text)


def test_strategy_options_check_rewrite() -> None:
    with pytest.raises(ProblemError, match="rewrite"):
        StrategyOptions(rewrite="yes")  # type: ignore[arg-type]


def test_rewrite_is_refused_in_deferring_modes() -> None:
    """``primitive`` replacements may keep faulty actions for later: nothing to rewrite with."""
    with pytest.raises(ProblemError, match="primitive"):
        StrategyOptions(recursion="primitive", rewrite=True)
    text = CONFIG.replace('["flat"]', '["flat", "primitive"]') + "rewrite = [false, true]\n"
    with pytest.raises(ConfigError, match="primitive"):
        parse_config(text)
    assert StrategyOptions(recursion="primitive").rewrite is False


def test_run_with_rewrite_repairs_once(capsys: pytest.CaptureFixture[str]) -> None:
    route = ["narrow-short", "--start", "1,1,E", "--goal", "13,13", "--faults", "FL:F"]
    rows = {}
    for flag in ((), ("--rewrite",)):
        code = main(["run", *route, "--recursion", "guarded", *flag, "--json"])
        assert code == 0
        rows[flag] = json.loads(capsys.readouterr().out)
    plain, rewriting = rows[()], rows[("--rewrite",)]
    assert rewriting["faulty_encounters"] == 1 < plain["faulty_encounters"]
    assert rewriting["final_pose"] == plain["final_pose"]
    assert rewriting["ticks"] == plain["ticks"]


# --- summary and finding 1r ----------------------------------------------------------------------


def _row(
    variant: str, latencies: list[tuple[str, int]], *, replans: int = 0, route: str = "r1"
) -> Row:
    strategy = variant.split("[")[0]
    return {
        "key": f"{variant}-{route}",
        "strategy": strategy,
        "variant": variant,
        "table": variant.split("[")[1].split(",")[0] if "[" in variant else None,
        "recursion": "guarded" if "[" in variant else None,
        "rewrite": (1 if variant.endswith(",rewrite]") else 0) if "[" in variant else None,
        "clearance_weight": "0",
        "maze": "m",
        "route": route,
        "faults": "FL:F",
        "fault_at": 0,
        "detection": "now",
        "replicate": 0,
        "reached": 1,
        "completed_without_replan": int(replans == 0),
        "faulty_encounters": len(latencies),
        "replacements": sum(1 for s, _ in latencies if s == "replacement"),
        "lookaheads": 0,
        "replans": replans,
        "repair_count": len(latencies),
        "actions_executed": 20,
        "repair_latencies_ns": json.dumps([lat for _, lat in latencies]),
        "repair_sources": json.dumps([s for s, _ in latencies]),
        "repair_compute_ns": sum(lat for _, lat in latencies),
        "plan_distance": 2,
    }


def _rows(variant: str, latencies: list[tuple[str, int]], replans: int = 0) -> list[Row]:
    """The same mission on 12 routes (finding 1 needs at least 10 pairs)."""
    return [_row(variant, latencies, replans=replans, route=f"r{i}") for i in range(12)]


REPLAN = _rows("replan", [("replan", 500_000)], replans=1)
PER_ENCOUNTER = _rows("replacement[handwritten,guarded]", [("replacement", 3_000)] * 40)
REWRITING = _rows("replacement[handwritten,guarded,rewrite]", [("replacement", 20_000)])


def test_summary_columns_for_repairs_and_hits() -> None:
    by_label = {s.label: s for s in summarize([*REPLAN, *PER_ENCOUNTER, *REWRITING])}
    per_encounter = by_label["replacement[handwritten,guarded]"]
    rewriting = by_label["replacement[handwritten,guarded,rewrite]"]
    assert per_encounter.hit_latency_median_us == 3.0 and per_encounter.repairs_per_mission == 40
    assert rewriting.hit_latency_median_us == 20.0 and rewriting.repairs_per_mission == 1
    assert by_label["replan"].hit_latency_median_us is None
    assert rewriting.cells()[-2:] == ("1.00", "20")
    assert StrategySummary.HEADERS[-2:] == ("repairs/mission", "hit latency median µs")


def _finding(findings: list[Finding], number: str) -> Finding | None:
    return next((f for f in findings if f.number == number), None)


def test_finding_1r_judges_the_rewriting_robot_apart() -> None:
    assert is_rewrite(REWRITING[0]) and not is_rewrite(PER_ENCOUNTER[0])
    assert not is_rewrite(REPLAN[0])
    # the column decides, not the label's text; a row stored before the column reads its config
    assert not is_rewrite({**REWRITING[0], "rewrite": 0})
    old = {k: v for k, v in PER_ENCOUNTER[0].items() if k != "rewrite"}
    assert is_rewrite({**old, "config": '{"options": {"rewrite": true}}'})
    assert not is_rewrite({**old, "config": '{"options": {"table": "handwritten"}}'})
    findings = check_findings([*REPLAN, *PER_ENCOUNTER, *REWRITING])
    one, rewritten = _finding(findings, "1"), _finding(findings, "1r")
    assert one is not None and rewritten is not None
    assert one.outcome is Outcome.NOT_HELD and "rewrite" not in one.evidence  # 0.24 of replan
    assert rewritten.outcome is Outcome.HELD and "0.040" in rewritten.evidence  # 0.04
    assert [f.number for f in findings][:2] == ["1", "1r"]
    without = check_findings([*REPLAN, *PER_ENCOUNTER])
    assert _finding(without, "1r") is None and _finding(without, "1") == one
    slow = _rows("replacement[handwritten,guarded,rewrite]", [("replacement", 90_000)])
    late = _finding(check_findings([*REPLAN, *PER_ENCOUNTER, *slow]), "1r")
    assert late is not None and late.outcome is Outcome.NOT_HELD


def test_other_findings_leave_rewriting_variants_out() -> None:
    """A rewrite is one repair for many occurrences: rewriting robots are never mixed with the
    ones that replace per encounter (same table and mode, same situations)."""
    other = _rows("replacement[generated-indexed,guarded]", [("replacement", 3_000)] * 10)
    bad = _rows(
        "replacement[generated-indexed,guarded,rewrite]",
        [("replacement", 20_000), ("replan", 400_000)],
        replans=1,
    )
    base = [*REPLAN, *PER_ENCOUNTER, *other]
    clean = check_findings(base)
    mixed = check_findings([*base, *bad, *REWRITING])
    for number in ("1", "1b", "2", "3", "4"):
        assert _finding(mixed, number) == _finding(clean, number), number
