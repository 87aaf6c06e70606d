"""Whole-plan rewriting as an option: experiment files, mission keys, ``selfrepair run
--rewrite``, the summary columns and finding 1 checked apart for the rewriting robot."""

from __future__ import annotations

import json

import pytest

from selfrepair.cli import main
from selfrepair.errors import ConfigError, ProblemError
from selfrepair.experiment.config import parse_config
from selfrepair.experiment.findings import check_findings, is_rewrite, summarize
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


# --- summary and finding 1 -----------------------------------------------------------------------


def _row(
    variant: str, latencies: list[tuple[str, int]], *, replans: int = 0, route: str = "r1"
) -> dict[str, object]:
    strategy = variant.split("[")[0]
    return {
        "key": f"{variant}-{route}",
        "strategy": strategy,
        "variant": variant,
        "table": "handwritten" if "[" in variant else None,
        "recursion": "guarded" if "[" in variant else None,
        "clearance_weight": "0",
        "maze": "m",
        "route": route,
        "faults": "FL:F",
        "fault_at": 0,
        "detection": "now",
        "replicate": 0,
        "reached": 1,
        "faulty_encounters": len(latencies),
        "replacements": sum(1 for s, _ in latencies if s == "replacement"),
        "lookaheads": 0,
        "replans": replans,
        "repair_count": len(latencies),
        "actions_executed": 20,
        "repair_latencies_ns": json.dumps([lat for _, lat in latencies]),
        "repair_sources": json.dumps([s for s, _ in latencies]),
        "repair_latency_total_ns": sum(lat for _, lat in latencies),
        "compute_per_action_ns": 1000.0,
        "extra_ticks": 1.0,
        "plan_distance": 2,
    }


ROWS = [
    _row("replan", [("replan", 500_000)], replans=1),
    _row("replacement[handwritten,guarded]", [("replacement", 3_000)] * 40),
    _row("replacement[handwritten,guarded,rewrite]", [("replacement", 20_000)]),
]


def test_summary_columns_for_hits_repairs_and_compute() -> None:
    by_label = {s.label: s for s in summarize(ROWS)}
    per_encounter = by_label["replacement[handwritten,guarded]"]
    rewriting = by_label["replacement[handwritten,guarded,rewrite]"]
    assert per_encounter.hit_latency_median_us == 3.0 and per_encounter.repairs_per_mission == 40
    assert per_encounter.repair_compute_per_mission_us == 120.0
    assert rewriting.hit_latency_median_us == 20.0 and rewriting.repairs_per_mission == 1
    assert by_label["replan"].hit_latency_median_us is None
    assert by_label["replan"].repair_compute_per_mission_us == 500.0
    cells = rewriting.cells()
    assert cells[-3:] == ("20", "1.00", "20")


def test_finding_1_is_checked_apart_for_the_rewriting_robot() -> None:
    assert is_rewrite(ROWS[2]) and not is_rewrite(ROWS[1]) and not is_rewrite(ROWS[0])
    finding = check_findings(ROWS)[0]
    assert finding.verdict == "held"
    first, _, second = finding.evidence.partition("with whole-plan rewriting: ")
    assert "ratio 0.2400" in first and "ratio 0.0400" in second
    without = check_findings(ROWS[:2])[0]
    assert without.verdict == "not held" and "rewriting" not in without.evidence
    slow = [*ROWS[:2], _row("replacement[handwritten,guarded,rewrite]", [("replacement", 90_000)])]
    assert check_findings(slow)[0].verdict == "not held"


def test_findings_2_and_3_leave_rewriting_variants_out() -> None:
    """A rewrite counts as one encounter for many occurrences: its share is not comparable."""
    hand = _row("replacement[handwritten,guarded]", [("replacement", 3_000)] * 10)
    other = _row("replacement[generated-indexed,guarded]", [("replacement", 3_000)] * 10)
    other["table"] = "generated-indexed"
    bad_rewrite = _row(
        "replacement[generated-indexed,guarded,rewrite]",
        [("replacement", 20_000), ("replan", 400_000)],
        replans=1,
    )
    bad_rewrite["table"] = "generated-indexed"
    finding = check_findings([ROWS[0], hand, other, bad_rewrite])[2]
    assert finding.verdict == "held" and "50.00%" not in finding.evidence
