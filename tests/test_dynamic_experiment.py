"""The changing world in experiments: the ``[world]`` section, its missions (paired obstacles,
keys of a static experiment unchanged), findings D1 to D3 and ``experiment dynamic``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from selfrepair.cli import main
from selfrepair.errors import ConfigError, InputError
from selfrepair.experiment.config import parse_config
from selfrepair.experiment.dynamic_findings import dynamic_findings
from selfrepair.experiment.missions import expand, to_spec
from selfrepair.experiment.verdicts import Outcome

SMALL = """\
name = "small-dynamic"
seed = 5
[[mazes]]
bundled = "wide-short"
routes = [{ start = "2,23,E", goal = "22,22" }]
[faults]
sets = ["", "FL:F"]
[world]
rates = [5, 40]
duration = 20
sensing = ["range", "bump"]
[[strategies]]
name = "replan"
[[strategies]]
name = "dstar-lite"
[[strategies]]
name = "replacement"
tables = ["generated-indexed"]
recursion = ["guarded"]
"""


def test_world_section_multiplies_the_missions_and_pairs_the_obstacles() -> None:
    missions = expand(parse_config(SMALL))
    assert len(missions) == 1 * 2 * 2 * 2 * 3  # route x faults x rates x sensing x strategies
    by_situation: dict[tuple[Any, ...], set[str]] = {}
    for mission in missions:
        labels = dict(mission.labels)
        spec = to_spec(mission)
        assert spec.world.sensing == labels["sensing"]
        assert spec.options.max_wait == 200
        key = (labels["faults"], labels["world_rate"], labels["sensing"])
        by_situation.setdefault(key, set()).add(repr(spec.world.events))
    assert all(len(worlds) == 1 for worlds in by_situation.values())  # one world per situation
    frequent = [k for k in by_situation if k[1] == "40.0"]
    assert frequent and all(by_situation[k] != {"()"} for k in frequent)


def test_a_static_experiment_keeps_its_keys() -> None:
    static = SMALL.split("[world]")[0] + SMALL.split('sensing = ["range", "bump"]\n')[1]
    missions = expand(parse_config(static))
    assert len(missions) == 6
    assert all("world" not in m.settings for m in missions)
    assert all(not to_spec(m).world for m in missions)
    assert all("world_rate" not in dict(m.labels) for m in missions)


def test_bad_world_sections_name_the_key() -> None:
    with pytest.raises((ConfigError, InputError), match="rates"):
        parse_config(SMALL.replace("rates = [5, 40]", "rates = []"))
    with pytest.raises((ConfigError, InputError), match="sensing"):
        parse_config(SMALL.replace('sensing = ["range", "bump"]', 'sensing = ["sonar"]'))


def _row(strategy: str, replicate: int, latency: int, ticks: float) -> dict[str, Any]:
    return {
        "maze": "m", "route": "r1", "faults": "", "fault_at": 0, "detection": "now",
        "replicate": replicate, "world_rate": "10.0", "sensing": "range", "strategy": strategy,
        "repair_latency_median_ns": latency, "ticks_float": ticks, "reached": 1,
        "completed_without_replan": int(strategy == "replacement"),
    }  # fmt: skip


def test_findings_judge_the_paired_response_time() -> None:
    rows = [
        row
        for k in range(12)
        for row in (
            _row("replan", k, 100_000 + k, 20.0),
            _row("dstar-lite", k, 50_000 + k, 20.0),
            _row("replacement", k, 20_000 + k, 24.0),
        )
    ]
    found = {f.number: f for f in dynamic_findings(rows)}
    assert found["D1"].outcome is Outcome.HELD and found["D3"].outcome is Outcome.HELD
    assert found["D2"].outcome is Outcome.HELD
    assert "ticks to the goal 4.0 [4.0, 4.0] more" in found["D1"].evidence
    slow = [{**r, "repair_latency_median_ns": 500_000} if r["strategy"] == "replacement" else r
            for r in rows]  # fmt: skip
    assert {f.number: f.outcome for f in dynamic_findings(slow)}["D1"] is Outcome.NOT_HELD
    few = [r for r in rows if r["replicate"] < 3]
    assert {f.number: f.outcome for f in dynamic_findings(few)}["D1"] is Outcome.INCONCLUSIVE
    assert dynamic_findings([{**r, "world_rate": None} for r in rows]) == []


def test_the_rewriting_robot_is_judged_apart() -> None:
    rows = [
        row
        for k in range(12)
        for row in (
            {**_row("replan", k, 100_000 + k, 20.0), "rewrite": None},
            {**_row("dstar-lite", k, 50_000 + k, 20.0), "rewrite": None},
            {**_row("replacement", k, 20_000 + k, 24.0), "rewrite": 0},
            {**_row("replacement", k, 400_000 + k, 24.0), "rewrite": 1},
        )
    ]
    found = {f.number: f.outcome for f in dynamic_findings(rows)}
    assert found["D1"] is Outcome.HELD and found["D2"] is Outcome.HELD  # not mixed
    assert found["D1r"] is Outcome.NOT_HELD and found["D2r"] is Outcome.NOT_HELD
    without = [r for r in rows if r["rewrite"] != 1]
    assert "D1r" not in {f.number for f in dynamic_findings(without)}
    assert "D4" not in found
    lpg = [{**_row("lpg-adapt", k, 1_500_000 + k, 22.0), "rewrite": None} for k in range(12)]
    assert {f.number: f.outcome for f in dynamic_findings(rows + lpg)}["D4"] is Outcome.HELD


def test_a_small_dynamic_experiment_runs_and_prints_its_findings(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tmp_path / "small.toml"
    config.write_text(SMALL.replace('sensing = ["range", "bump"]', 'sensing = ["range"]'))
    assert main(["experiment", str(config), "--db", str(tmp_path / "s.sqlite"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "Finding D1" in out and "Finding D2" in out and "Finding D3" in out


def test_an_optional_lpg_adapt_is_left_out_with_its_reason_where_it_cannot_run(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import selfrepair.baselines.adapt as adapt
    from selfrepair.experiment.variants import left_out

    lpg = '[[strategies]]\nname = "lpg-adapt"\ntime_limit = 1\nmazes = ["wide-short"]\n'
    monkeypatch.setattr(adapt, "lpg_available", lambda: False)
    with pytest.raises((ConfigError, InputError), match="pddl extra"):
        parse_config(SMALL + lpg)
    config = parse_config(SMALL + lpg + "optional = true\n")
    assert [name for name, _ in left_out(config)] == ["lpg-adapt"]
    assert "pddl extra" in left_out(config)[0][1]
    missions = expand(config)
    assert len(missions) == len(expand(parse_config(SMALL)))  # none of LPG's
    assert "lpg-adapt" not in {dict(m.labels)["strategy"] for m in missions}
