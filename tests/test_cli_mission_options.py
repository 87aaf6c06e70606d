"""``run`` and ``compare`` share one set of mission options (``cli._mission.MissionOptions``):
the same flags, forwarded the same way, and the strategy options do in ``compare`` what they do
in ``run``."""

from __future__ import annotations

import json
from dataclasses import fields
from typing import Any

import pytest
import typer

from capture import captured_spec
from selfrepair.caching import clear_caches
from selfrepair.cli import app, main
from selfrepair.cli._mission import MissionOptions
from selfrepair.execution.result import MissionSpec
from selfrepair.repair.lookups import lookup_memory

ROUTE = ["narrow-short", "--start", "1,1,E", "--goal", "13,13"]

RUN_ONLY = {"strategy", "trace"}
"""The intended differences, which both commands' help names: ``run`` runs one strategy
(``--strategy``) and writes its trace (``--trace``); ``compare`` runs several
(``--strategies``), and a trace holds one mission."""
COMPARE_ONLY = {"strategies"}

NON_DEFAULT = {
    "faults": ["--faults", "L"],
    "at": ["--at", "1"],
    "clock": ["--clock", "tick"],
    "detect": ["--detect", "on-use"],
    "transient": ["--transient", "5"],
    "intermittent": [],  # at most one of --transient and --intermittent
    "events": ["--events", "3,13@2..9"],
    "sensing": ["--sensing", "bump"],
    "sensing_range": ["--sensing-range", "4"],
    "table": ["--table", "three-action"],
    "recursion": ["--recursion", "guarded"],
    "max_depth": ["--max-depth", "3"],
    "window": ["--window", "4"],
    "lpg_time_limit": ["--lpg-time-limit", "0.5"],
    "rewrite": ["--rewrite"],
    "clearance_weight": ["--clearance-weight", "1/2"],
    "heuristic": ["--heuristic", "manhattan"],
    "backend": ["--backend", "python"],
    "plan_with_faults": ["--plan-with-faults"],
    "seed": ["--seed", "3"],
    "warm_up": ["--no-warm-up"],
    "domain_name": ["--domain", "three-action"],
    "max_cells": ["--max-cells", "1000"],
    "max_table_bytes": ["--max-table-bytes", "100000"],
    "max_table_candidates": ["--max-table-candidates", "1000"],
    "max_lookup_patterns": ["--max-lookup-patterns", "7"],
    "max_wait": ["--max-wait", "3"],
    "fault_behaviour": [],  # needs --detect hidden and a robot with a model: test_diagnosis_cli
    "noise": [],  # needs --detect hidden: test_diagnosis_cli
    "observers": [],  # likewise
    "observer_range": [],  # likewise
    "observer_noise": [],  # likewise
    "observer_view": [],  # likewise
    "bump_switch": ["--no-bumps"],
    "max_faults": ["--max-faults", "1"],
    "fault_prior": ["--fault-prior", "0.1"],
    "confidence": ["--confidence", "0.05"],
}
"""A value other than the default for every option of :class:`MissionOptions` (a new option
must be added here, so that the forwarding test covers it)."""


def _params(name: str) -> dict[str, Any]:
    command = typer.main.get_command(app).commands[name]  # type: ignore[attr-defined]
    return {p.name: p for p in command.params}


def test_run_and_compare_share_their_options() -> None:
    run, compare = _params("run"), _params("compare")
    assert set(run) - set(compare) == RUN_ONLY
    assert set(compare) - set(run) == COMPARE_ONLY
    shared = {f.name for f in fields(MissionOptions)}
    assert shared <= set(run) & set(compare)
    for name in shared:
        a, b = run[name], compare[name]
        assert (a.opts, a.secondary_opts, a.default, a.help, a.required) == (
            b.opts,
            b.secondary_opts,
            b.default,
            b.help,
            b.required,
        ), name


def test_the_help_names_the_intended_differences(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compare", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "Takes every option of run but two: --strategies in place of --strategy" in text
    assert "no --trace" in text
    assert main(["run", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "Takes every option of compare but --strategies" in text


def test_every_mission_option_reaches_the_spec_of_both_commands(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Both commands build the same mission from the same flags, every option set to a value
    other than its default (the mission is captured before it runs)."""
    assert set(NON_DEFAULT) == {f.name for f in fields(MissionOptions)} - {"maze", "start", "goal"}
    argv = [*ROUTE, *(arg for args in NON_DEFAULT.values() for arg in args)]
    specs = {}
    for command, strategy in (("run", "--strategy"), ("compare", "--strategies")):
        specs[command] = captured_spec(monkeypatch, [command, *argv, strategy, "replacement"])
    run, compare = specs["run"], specs["compare"]
    assert compare.options == run.options
    for field in fields(MissionSpec):
        if field.name != "maze":
            assert getattr(compare, field.name) == getattr(run, field.name), field.name
    assert compare.maze.name == run.maze.name == "narrow-short"
    got = compare.options
    assert (got.lpg_time_limit_s, got.max_lookup_patterns, got.rewrite) == (0.5, 7, True)
    assert (got.recursion, got.max_depth, got.window) == ("guarded", 3, 4)
    assert compare.domain.name == "three-action" and compare.initial_faults_known
    assert compare.world.to_json()["events"][0] == {"cell": [3, 13], "blocked": True, "at": 2}
    assert (compare.world.sensing, compare.world.sensing_range) == ("bump", 4)
    assert (got.max_faults, got.fault_prior, got.confidence) == (1, 0.1, 0.05)
    assert not compare.observation.bumps


def _compare_json(capsys: pytest.CaptureFixture[str], *args: str) -> dict[str, Any]:
    code = main(["compare", *ROUTE, "--faults", "FL:F", "--no-warm-up", *args, "--json"])
    data: dict[str, Any] = json.loads(capsys.readouterr().out)
    assert code == 0, data
    return data


def test_compare_with_rewrite_repairs_once(capsys: pytest.CaptureFixture[str]) -> None:
    """``--rewrite``: the replacement robot rewrites the rest of its plan at the first faulty
    action, so it meets one faulty action where it met several without."""
    args = ["--strategies", "replacement,replan", "--recursion", "guarded"]
    plain, rewriting = _compare_json(capsys, *args), _compare_json(capsys, *args, "--rewrite")
    (plain_table, plain_replan), (rewrite_table, rewrite_replan) = plain["runs"], rewriting["runs"]
    assert rewrite_table["repairs"] == 1 < plain_table["repairs"]
    assert rewrite_table["ticks"] == plain_table["ticks"]
    assert rewrite_replan == {**plain_replan, **_timings(rewrite_replan)}  # replan ignores it


def _timings(run: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in run.items() if k.startswith("repair_latency")}


def test_compare_max_lookup_patterns_caps_what_the_mission_stores(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["--strategies", "replacement", "--recursion", "guarded"]
    patterns = {}
    for cap in ("0", "4096"):
        clear_caches()
        runs = _compare_json(capsys, *args, "--max-lookup-patterns", cap)["runs"]
        assert runs[0]["status"] == "reached"
        patterns[cap] = sum(m.patterns for m in lookup_memory() if m.faults == "FL:F")
    assert patterns["0"] == 0 < patterns["4096"]


@pytest.mark.parametrize(
    ("args", "flag"),
    [(["--lpg-time-limit", "0"], "--lpg-time-limit"),
     (["--max-lookup-patterns", "-1"], "--max-lookup-patterns")],
)  # fmt: skip
def test_compare_checks_the_new_options(
    args: list[str], flag: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["compare", *ROUTE, *args]) == 2
    err = capsys.readouterr().err
    assert err.startswith("selfrepair: error:") and flag in err and err.count("\n") == 1
