"""Hidden faults on the command line and in experiment files: the options, their checks, the
rows they give."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from capture import captured_spec
from selfrepair.cli import main
from selfrepair.diagnosis.cooperative import Observer, SensingRange
from selfrepair.errors import ConfigError
from selfrepair.experiment.config import parse_config
from selfrepair.experiment.missions import expand, to_spec

ROUTE = ["narrow-short", "--start", "7,13,W", "--goal", "1,8", "--faults", "FL:F"]


def test_run_with_hidden_faults_reports_the_diagnosis(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["run", *ROUTE, "--detect", "hidden", "--strategy", "active-diagnosis", "--noise", "0.01",
         "--fault-behaviour", "stall", "--json", "--no-warm-up"]
    )  # fmt: skip
    row = json.loads(capsys.readouterr().out)
    assert code == 0 and row["status"] == "reached"
    assert row["detection"] == "hidden" and row["behaviour"] == "stall"
    # FL:F stalls the front-left wheel: the first command already ends off the plan (a surprise
    # at step 0), the robot bumps into walls while it diagnoses, and it names the right class
    assert row["observation_noise"] == 0.01 and row["isolated_right"] == 1
    assert row["surprise_step"] == 0 and row["bumps"] > 0


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        (["--detect", "hidden", "--fault-behaviour", "melt"], "--fault-behaviour: expected one of"),
        (["--noise", "0.1"], "--noise: expected --detect hidden"),
        (["--fault-behaviour", "stall"], "--fault-behaviour: expected --detect hidden"),
        (["--detect", "hidden", "--noise", "0.5"], "--noise: expected a number in [0, 0.5)"),
        (["--detect", "hidden", "--fault-prior", "1"], "--fault-prior: expected a number in (0,"),
        (["--detect", "hidden", "--confidence", "-0.1"], "--confidence: expected a number"),
        (["--detect", "seen"], "--detect: expected one of now, on-use, hidden"),
        (["--observers", "2"], "--observers: expected --detect hidden"),
        (["--observer-noise", "0.1"], "--observer-noise: expected --detect hidden"),
        (["--detect", "hidden", "--observers", "9"], "--observers: expected a number from 0 to 8"),
        (["--detect", "hidden", "--observers", "-1"], "--observers: expected a number from 0"),
        (["--detect", "hidden", "--observers", "2", "--observer-range", "65"],
         "--observer-range: expected a number from 0 to 64"),
        (["--detect", "hidden", "--observers", "2", "--observer-noise", "0.5"],
         "--observer-noise: expected a number in [0, 0.5)"),
        (["--detect", "hidden", "--observer-range", "2"],
         "--observer-range: expected --observers N of at least 1"),
        (["--detect", "hidden", "--observers", "two"], "--observers"),
        (["--observer-view", "wheels"], "--observer-view: expected --detect hidden"),
        (["--detect", "hidden", "--observer-view", "wheels"],
         "--observer-view: expected --observers N of at least 1"),
        (["--detect", "hidden", "--observers", "2", "--observer-view", "legs"],
         "--observer-view: expected one of pose, wheels"),
    ],
)
def test_bad_hidden_fault_options_are_one_line_exit_2(
    extra: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    for command in ("run", "compare"):
        assert main([command, *ROUTE, *extra]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and expected in err, err


def test_run_with_observers_hears_them(capsys: pytest.CaptureFixture[str]) -> None:
    def isolated(*extra: str) -> dict[str, object]:
        code = main(
            ["run", *ROUTE, "--detect", "hidden", "--strategy", "active-diagnosis", "--noise",
             "0.01", "--json", "--no-warm-up", *extra]
        )  # fmt: skip
        row: dict[str, object] = json.loads(capsys.readouterr().out)
        assert code == 0 and row["status"] == "reached" and row["isolated_right"] == 1
        return row

    alone = isolated()
    team = isolated("--observers", "2", "--observer-range", "3", "--observer-noise", "0.01")
    blind = isolated("--observers", "2", "--observer-range", "0")  # sees only its own cell
    assert (alone["observers"], team["observers"], blind["observers"]) == (0, 2, 2)
    assert isinstance(alone["isolation_actions"], int)
    assert isinstance(team["isolation_actions"], int)
    assert team["isolation_actions"] < alone["isolation_actions"]


def test_run_and_compare_give_the_mission_its_observers(monkeypatch: pytest.MonkeyPatch) -> None:
    args = [*ROUTE, "--detect", "hidden", "--noise", "0.02", "--observers", "3",
            "--observer-range", "2", "--no-warm-up"]  # fmt: skip
    for command, extra in (("run", []), ("compare", []), ("run", ["--observer-noise", "0"])):
        observers = captured_spec(monkeypatch, [command, *args, *extra]).observers
        noise = 0.0 if extra else 0.02  # default: the robot's own rate
        assert observers == tuple(Observer(f"t{i}", noise, SensingRange(2)) for i in (1, 2, 3))


def test_a_robot_without_a_model_refuses_a_fault_behaviour(
    capsys: pytest.CaptureFixture[str],
) -> None:
    args = ["run", "narrow-short", "--start", "1,1,E", "--goal", "13,13", "--faults", "L",
            "--domain", "three-action", "--detect", "hidden",
            "--fault-behaviour", "stall"]  # fmt: skip
    assert main(args) == 2
    assert "no fault-behaviour model" in capsys.readouterr().err


def test_compare_runs_the_strategies_for_hidden_faults(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["compare", *ROUTE, "--detect", "hidden", "--json", "--no-warm-up"]) == 0
    runs = json.loads(capsys.readouterr().out)["runs"]
    names = [r["strategy"].split("[")[0] for r in runs]
    assert names == ["oracle", "diagnose", "conformant", "active-diagnosis", "trial-and-error"]


EXPERIMENT = """
name = "hidden"
seed = 1

[[mazes]]
bundled = "narrow-short"
routes = "bundled"

[faults]
sets = ["FL:F", "RL:F,RR:B"]
detection = ["now", "hidden"]
noise = [0, 0.05]
behaviour = "stall"
bump_switch = true

[[strategies]]
name = "oracle"

[[strategies]]
name = "active-diagnosis"
confidence = 0.02
"""


def test_experiment_files_take_the_hidden_fault_keys() -> None:
    missions = expand(parse_config(EXPERIMENT))
    routes, sets, strategies = 4, 2, 2
    # detection now once, hidden at each noise rate: missions of equal settings are one
    assert len(missions) == routes * sets * strategies * (1 + 2)
    specs = [to_spec(m) for m in missions]
    hidden = [s for s in specs if s.schedule.detection == "hidden"]
    assert {s.observation.noise for s in hidden} == {0.0, 0.05}
    assert {s.behaviour for s in hidden} == {"stall"}
    active = [s for s in specs if s.strategy == "active-diagnosis"]
    assert {s.options.confidence for s in active} == {0.02}
    now = [s for s in specs if s.schedule.detection == "now"]
    assert all("noise" not in m.settings for m in missions if m.settings["detection"] == "now")
    assert {s.observation.noise for s in now} == {0.0}


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ('behaviour = "stall"', 'behaviour = "melt"', "expected a fault behaviour of four-wheel"),
        ("noise = [0, 0.05]", "noise = [0.7]", "less than 0.5"),
        ('detection = ["now", "hidden"]', 'detection = ["now"]', 'need detection = ["hidden"]'),
        ("confidence = 0.02", "confidence = 1.5", "less than 1"),
    ],
)
def test_bad_hidden_fault_keys_name_the_key(
    tmp_path: Path, old: str, new: str, expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert old in EXPERIMENT
    with pytest.raises(ConfigError, match="key '") as info:
        parse_config(EXPERIMENT.replace(old, new), source="x.toml")
    assert expected in str(info.value)
    path = tmp_path / "bad.toml"
    path.write_text(EXPERIMENT.replace(old, new))
    assert main(["experiment", str(path), "--db", str(tmp_path / "r.sqlite")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
