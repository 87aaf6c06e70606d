"""The baselines experiment: strategy entries for D* Lite and LPG-adapt (and replan's backend),
strategies limited to some mazes, the comparison with intervals, its CLI table, report section and
figure. Tests that run LPG need the ``pddl`` extra and are skipped with that reason without it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from extras import LPG
from selfrepair.baselines import adapt
from selfrepair.baselines.lpg import lpg_available
from selfrepair.cli import main
from selfrepair.cli.experiments import resolve_experiment
from selfrepair.errors import ConfigError
from selfrepair.experiment.comparison import (
    FIRST_REPAIR,
    REPAIR_COMPUTE,
    BaselineLine,
    baseline_tables,
    common_rows,
    compare_baselines,
    has_baselines,
    maze_table,
    per_maze,
)
from selfrepair.experiment.config import load_config, parse_config
from selfrepair.experiment.missions import count_missions, expand, to_spec
from selfrepair.experiment.store import Value
from selfrepair.experiment.summary import is_reference_replan

DOCS = Path(__file__).parent.parent / "docs"

needs_lpg = LPG

BASE = """\
name = "mini"
seed = 3

[[mazes]]
bundled = "narrow-short"
routes = [{start = "7,13,W", goal = "1,8", name = "r1"}]

[[mazes]]
bundled = "wide-short"
routes = [{start = "2,23,E", goal = "22,22", name = "r1"}]

[faults]
sets = ["FR:B", "FL:F"]

[[strategies]]
name = "replan"

[[strategies]]
name = "replan"
backend = "python"

[[strategies]]
name = "dstar-lite"

[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["guarded"]
"""

LPG = """
[[strategies]]
name = "lpg-adapt"
time_limit = 3
seed = 1
mazes = ["narrow-short"]
"""


# --- configuration -----------------------------------------------------------------------------


def test_strategy_entries_become_options_specs_and_labels() -> None:
    missions = expand(parse_config(BASE))
    by_variant = {dict(m.labels)["variant"] for m in missions}
    assert by_variant == {
        "replan",
        "replan[python]",
        "dstar-lite",
        "replacement[handwritten,guarded]",
    }
    python = next(m for m in missions if dict(m.labels)["variant"] == "replan[python]")
    assert to_spec(python).backend == "python"
    default = next(m for m in missions if dict(m.labels)["variant"] == "replan")
    assert default.settings["options"] == {}  # so the keys of older experiments stay valid
    assert to_spec(default).backend == "auto"
    assert count_missions(parse_config(BASE)) == len(missions) == 2 * 2 * 4


def test_lpg_entry_and_maze_filter(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(adapt, "lpg_available", lambda: True)
    config = parse_config(BASE + LPG)
    missions = expand(config)
    lpg = [m for m in missions if dict(m.labels)["strategy"] == "lpg-adapt"]
    assert {dict(m.labels)["maze"] for m in lpg} == {"narrow-short"}
    assert len(lpg) == 2 and dict(lpg[0].labels)["variant"] == "lpg-adapt[3s,seed=1]"
    spec = to_spec(lpg[0])
    assert spec.options.lpg_time_limit_s == 3 and spec.options.lpg_seed == 1
    assert count_missions(config) == len(missions) == 2 * 2 * 4 + 2


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ("time_limit = 3", "time_limit = 0", "time_limit", "greater than 0"),
        ("time_limit = 3", "time_limit = 4000", "time_limit", "less than or equal to 3600"),
        ("time_limit = 3", 'time_limit = "5"', "time_limit", "number"),
        ("seed = 1", "seed = -1", "seed", "greater than or equal to 0"),
        ('mazes = ["narrow-short"]', "mazes = []", "mazes", "at least 1"),
        ("time_limit = 3", "windows = [3]", "windows", "unknown key"),
    ],
)
def test_bad_lpg_entries_name_the_key(
    monkeypatch: pytest.MonkeyPatch, old: str, new: str, key: str, expected: str
) -> None:
    monkeypatch.setattr(adapt, "lpg_available", lambda: True)
    text = BASE + LPG.replace(old, new)
    key = f"strategies[4].{key}"
    with pytest.raises(ConfigError, match=expected) as info:
        parse_config(text)
    assert f"key {key!r}" in str(info.value)


def test_replan_backend_must_be_known() -> None:
    with pytest.raises(ConfigError, match=r"strategies\[1\]\.backend.*'auto', 'numba' or"):
        parse_config(BASE.replace('backend = "python"', 'backend = "cuda"'))


def test_lpg_without_the_extra_is_refused_before_any_mission(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setattr(adapt, "lpg_available", lambda: False)
    path = tmp_path / "x.toml"
    path.write_text(BASE + LPG)
    with pytest.raises(ConfigError, match=r"pip install 'selfrepair\[pddl\]'") as info:
        load_config(path)
    assert str(info.value).startswith(f"{path.resolve()}:31: key 'strategies[4].name'")
    code = main(["experiment", str(path), "--db", str(tmp_path / "x.sqlite")])
    assert code == 2


def test_lpg_for_another_robot_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(adapt, "lpg_available", lambda: True)
    text = 'domain = "three-action"\n' + BASE.replace('sets = ["FR:B", "FL:F"]', 'sets = ["F"]')
    with pytest.raises(ConfigError, match="four-wheel robot only"):
        parse_config(text + LPG)


def test_a_maze_filter_must_name_a_maze_of_the_experiment() -> None:
    text = BASE.replace('name = "dstar-lite"', 'name = "dstar-lite"\nmazes = ["wide-lng"]')
    with pytest.raises(ConfigError, match=r"strategies\[2\]\.mazes.*wide-short.*'wide-lng'"):
        expand(parse_config(text))


@needs_lpg
def test_bundled_baselines_experiment_expands_as_documented() -> None:
    config = load_config(resolve_experiment("baselines"))
    missions = expand(config)
    labels = [dict(m.labels) for m in missions]
    assert len(missions) == count_missions(config) == 8 * 96 + 72
    for text in (
        resolve_experiment("baselines").read_text(encoding="utf-8"),
        (DOCS / "baselines.md").read_text(encoding="utf-8"),
    ):
        assert f"{len(missions)} missions" in text
    lpg = {lab["maze"] for lab in labels if lab["strategy"] == "lpg-adapt"}
    assert lpg == {"narrow-short", "wide-short", "narrow-long"}
    assert {lab["maze"] for lab in labels if lab["strategy"] == "dstar-lite"} == lpg | {"wide-long"}


# --- the comparison ----------------------------------------------------------------------------


def row(variant: str, maze: str = "m", route: str = "r1", **metrics: Value) -> dict[str, Value]:
    strategy = variant.split("[")[0]
    values: dict[str, Value] = {
        "variant": variant,
        "strategy": strategy,
        "maze": maze,
        "route": route,
        "faults": "FL:F",
        "fault_at": 0,
        "detection": "now",
        "replicate": 0,
        "clearance_weight": "0",
        "reached": 1,
        "faulty_encounters": 1,
        "repair_count": 1,
        "repair_compute_ns": 1_000_000,
        "first_repair_ns": 500_000,
        "repair_expansions": 10,
        "ticks_float": 20.0,
        "plan_distance": 4,
        "fallbacks": 0,
        "repair_attempts": json.dumps({strategy: 1}),
        "maze_free_cells": 97,
    }
    values.update(metrics)
    return values


def test_the_table_uses_only_situations_every_variant_ran() -> None:
    rows = [
        row("replan"),
        row("replan", maze="big", maze_free_cells=2721),
        row("dstar-lite", repair_compute_ns=30_000_000),
        row("dstar-lite", maze="big", maze_free_cells=2721),
        row(
            "lpg-adapt[5s]",
            ticks_float=26.0,
            fallbacks=1,
            repair_attempts=json.dumps({"lpg-adapt:timeout": 1, "replan": 1}),
        ),
    ]
    assert has_baselines(rows) and not has_baselines([row("replan")])
    assert {r["maze"] for r in common_rows(rows)} == {"m"}
    lines = {line.label: line for line in compare_baselines(rows)}
    assert list(lines) == ["replan", "dstar-lite", "lpg-adapt[5s]"]
    lpg = lines["lpg-adapt[5s]"]
    assert lpg.missions == 1 and lpg.fallbacks == 1 and lpg.timeouts == 1
    assert lpg.over_reference is not None and lpg.over_reference.estimate == 6.0
    assert lpg.cells()[4] == "n/a" and lpg.cells()[9] == "1"
    assert lines["dstar-lite"].repair_ms is not None
    assert lines["dstar-lite"].repair_ms.estimate == 30.0
    assert lines["replan"].cells()[9] == "-"
    assert lines["replan"].first_ms is not None and lines["replan"].first_ms.estimate == 0.5
    everywhere = {
        line.label: line.missions for line in compare_baselines(rows, same_missions=False)
    }
    assert everywhere == {"replan": 2, "dstar-lite": 2, "lpg-adapt[5s]": 1}


def test_intervals_come_from_missions() -> None:
    rows = [row("replan", route=f"r{i}", repair_compute_ns=1_000_000 * (i + 1)) for i in range(9)]
    rows += [row("dstar-lite", route=f"r{i}") for i in range(9)]
    line = compare_baselines(rows)[0]
    assert line.repair_ms is not None
    assert line.repair_ms.estimate == 5.0 and line.repair_ms.n == 9
    assert line.repair_ms.low < 5.0 < line.repair_ms.high


def test_per_maze_and_maze_table_order_by_size() -> None:
    rows = [
        row("replan", maze="big", maze_free_cells=2721),
        row("replan"),
        row("dstar-lite", maze="big", maze_free_cells=2721, repair_compute_ns=5_000_000),
        row("replan", route="r2", faulty_encounters=0),  # met no fault: left out
    ]
    cells = per_maze(rows, REPAIR_COMPUTE)
    assert [(c.label, c.maze) for c in cells] == [
        ("replan", "m"),
        ("replan", "big"),
        ("dstar-lite", "big"),
    ]
    headers, body = maze_table(rows, REPAIR_COMPUTE)
    assert headers == ("strategy", "m (97 free cells)", "big (2721 free cells)")
    assert body[1] == ("dstar-lite", "-", "5.00 [5.00, 5.00]")


def test_baseline_tables_are_the_same_missions_and_both_maze_tables() -> None:
    rows = [
        row("replan"),
        row("replan", maze="big", maze_free_cells=2721),
        row("replan", maze="a", route="r2"),
        row("dstar-lite", repair_compute_ns=30_000_000),
        row("dstar-lite", maze="a", route="r2", first_repair_ns=2_000_000),
    ]
    tables = baseline_tables(rows)
    assert tables.missions == 2 and tables.mazes == ("a", "m")  # "big": replan only
    headers, body = tables.comparison
    assert headers == BaselineLine.HEADERS
    assert [cells[0] for cells in body] == ["replan", "dstar-lite"]
    assert body[1][1] == "2/2"
    assert tables.first_repair == maze_table(rows, FIRST_REPAIR)
    assert tables.repair_compute == maze_table(rows, REPAIR_COMPUTE)
    assert tables.first_repair != tables.repair_compute
    assert baseline_tables([]).missions == 0


def test_only_default_replan_is_the_findings_reference() -> None:
    assert is_reference_replan(row("replan"))
    assert not is_reference_replan(row("replan[python]"))
    assert not is_reference_replan(row("dstar-lite"))
    assert is_reference_replan({"strategy": "replan"})  # rows built without a variant


# --- end to end ------------------------------------------------------------------------------


def test_experiment_prints_the_comparison_and_the_report_has_its_section(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "mini.toml"
    path.write_text(BASE + (LPG if lpg_available() else ""))
    db = tmp_path / "mini.sqlite"
    assert main(["experiment", str(path), "--db", str(db), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "Baselines on the same missions (narrow-short" in out
    assert "First repair ms by maze" in out and "dstar-lite" in out
    assert "The replanner in these findings is variant replan only" in out
    summary = out[: out.index("Fault sets:")]
    order = [summary.index(f"│ {start}") for start in ("replan ", "dstar-lite ", "replacement[")]
    assert order == sorted(order)
    report = tmp_path / "report"
    assert main(["report", str(db), "-o", str(report)]) == 0
    text = (report / "report.md").read_text(encoding="utf-8")
    assert "## Baselines: D* Lite, LPG-adapt and A* replanning" in text
    assert "| replan[python] |" in text and "(baselines.png)" in text
    findings = text[text.index("## The original study's findings") : text.index("## Figures")]
    assert "*The replanner in these findings is variant replan only" in findings
    assert "dstar-lite" in findings and "replan[python]" in findings
    assert (report / "baselines.png").stat().st_size > 0
