"""`experiment diagnosis` (issue 24 item 7): the bundled design, observing teammates in the
mission factors, and findings G1 to G4 with paired tests."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from selfrepair.cli import main
from selfrepair.cli.experiments import resolve_experiment
from selfrepair.diagnosis import FaultBelief, Observation, ObservationModel, fault_model
from selfrepair.diagnosis.cooperative import Observer, ObserverView, SensingRange
from selfrepair.errors import ConfigError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.config import load_config, parse_config
from selfrepair.experiment.diagnosis_findings import diagnosis_findings
from selfrepair.experiment.findings import Outcome
from selfrepair.experiment.missions import count_missions, expand, to_spec
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action
from selfrepair.world.bundled import bundled_routes, load_bundled

SMALL = """\
name = "diag-small"
seed = 5

[[mazes]]
bundled = "narrow-short"
routes = [{start = "1,1,E", goal = "9,9"}]

[faults]
sets = ["FL:F", "RL:F", "FL:F,RR:B"]
detection = ["hidden"]
noise = [0, 0.05]
observers = [0, 2]

[[strategies]]
name = "oracle"

[[strategies]]
name = "diagnose"

[[strategies]]
name = "active-diagnosis"

[[strategies]]
name = "trial-and-error"
"""


def test_the_bundled_design_is_the_issue_s() -> None:
    config = load_config(resolve_experiment("diagnosis"))
    faults = config.faults
    assert faults.sets == "all" and faults.detection == (Detection.HIDDEN,)
    assert faults.noise == (0.0, 0.01, 0.05) and faults.observers == (0, 2)
    names = [s.name for s in config.strategies]
    assert names == ["oracle", "diagnose", "conformant", "active-diagnosis", "trial-and-error"]
    # 16 routes x 78 fault sets x 3 noise rates x 2 team sizes x 5 strategies
    assert count_missions(config) == 16 * 78 * 3 * 2 * 5 == 37_440
    quick = load_config(resolve_experiment("diagnosis-quick"))
    assert count_missions(quick) == 16 * 12 * 3 * 2 * 5


def test_the_bundled_wheel_variant_judges_g3() -> None:
    """`experiment diagnosis-wheels`: diagnosis-quick's noisy situations, active diagnosis alone
    or watched with the wheel view; its alone missions are diagnosis-quick's (same keys), and its
    rows pair up for G3 (and only the findings its design can judge apply)."""
    config = load_config(resolve_experiment("diagnosis-wheels"))
    faults = config.faults
    assert faults.observer_view is ObserverView.WHEELS and faults.observers == (0, 2)
    assert faults.noise == (0.01, 0.05) and faults.sets == "paper"
    assert [s.name for s in config.strategies] == ["active-diagnosis"]
    missions = expand(config)
    assert len(missions) == count_missions(config) == 16 * 12 * 2 * 2 == 768
    quick = {m.key for m in expand(load_config(resolve_experiment("diagnosis-quick")))}
    alone = {m.key for m in missions if "observers" not in m.settings}
    assert len(alone) == 384 and alone <= quick  # the view enters only a watched robot's key
    rows = []
    for mission in missions:
        s = mission.settings
        watched = "observers" in s
        rows.append({**dict(mission.labels), "observation_noise": s["noise"],
                     "observers": 2 if watched else 0, "surprise_step": 1,
                     "isolation_actions": 1 if watched else 3, "isolated_right": 1,
                     "reached": 1, "ticks_float": 10.0, "bumps": 0})  # fmt: skip
    found = _by_number(rows)
    assert found["G3"].outcome is Outcome.HELD and len(found["G3"].lines) == 1 + 2
    assert found["G4"].applies and not found["G1"].applies and not found["G2"].applies


def test_observers_enter_the_missions_only_when_present() -> None:
    missions = expand(parse_config(SMALL))
    assert len(missions) == 3 * 2 * 2 * 4
    specs = [to_spec(m) for m in missions]
    watched = [s for s in specs if s.observers]
    assert len(watched) == len(specs) // 2
    for spec in watched:
        assert [o.name for o in spec.observers] == ["t1", "t2"]
        assert {o.noise for o in spec.observers} == {spec.observation.noise}
        assert {o.sensing for o in spec.observers} == {SensingRange(3)}
    alone = [m for m in missions if not to_spec(m).observers]
    assert all("observers" not in m.settings for m in alone)  # older keys stay valid
    seeds = {m.seed for m in missions if m.settings["strategy"] == "oracle"}
    assert len(seeds) == 3 * 2 * 2  # one seed per situation, observers part of it


@pytest.mark.parametrize(
    ("old", "new", "expected"),
    [
        ('detection = ["hidden"]\nnoise = [0, 0.05]', 'detection = ["now"]', "observers need"),
        ("observers = [0, 2]", "observers = [0, 0]", "distinct numbers of observers"),
        ("observers = [0, 2]", "observers = [9]", "less than or equal to 8"),
        ("observers = [0, 2]", "observers = [0, 2]\nobserver_range = -1", "greater than"),
        ("observers = [0, 2]", 'observers = [0, 2]\nobserver_view = "eyes"',
         "expected 'pose' or 'wheels'"),
        ("observers = [0, 2]", 'observers = [0]\nobserver_view = "wheels"',
         "observer_view needs observers"),
        ('sets = ["FL:F", "RL:F", "FL:F,RR:B"]', 'sets = ["F"]\nobserver_view = "wheels"',
         "needs a robot that declares actuators"),
    ],
)
def test_bad_observer_keys_name_file_line_and_expectation(
    tmp_path: Path, old: str, new: str, expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    text = SMALL.replace(old, new)
    assert text != SMALL
    if 'sets = ["F"]' in text:  # the three-action robot: no actuators, the oracle only
        text = 'domain = "three-action"\n' + text.split("[[strategies]]")[0]
        text += '[[strategies]]\nname = "oracle"\n'
    with pytest.raises(ConfigError, match=expected) as info:
        parse_config(text, source="x.toml")
    assert str(info.value).startswith("x.toml:")  # the file and the line
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["experiment", str(path), "--db", str(tmp_path / "r.sqlite")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and str(path) in err


def test_the_observer_view_reaches_the_observers_and_the_key_only_when_wheels() -> None:
    wheels = SMALL.replace("observers = [0, 2]", 'observers = [0, 2]\nobserver_view = "wheels"')
    pose = SMALL.replace("observers = [0, 2]", 'observers = [0, 2]\nobserver_view = "pose"')
    assert parse_config(wheels).faults.observer_view is ObserverView.WHEELS
    missions = {view: expand(parse_config(text)) for view, text in (
        ("default", SMALL), ("pose", pose), ("wheels", wheels))}  # fmt: skip
    assert [m.seed for m in missions["pose"]] == [m.seed for m in missions["default"]]
    for mission in missions["wheels"]:
        spec = to_spec(mission)
        assert {o.view for o in spec.observers} <= {ObserverView.WHEELS}
        if spec.observers:
            assert mission.settings["observers"]["view"] == "wheels"
    for mission in missions["pose"]:
        assert {o.view for o in to_spec(mission).observers} <= {ObserverView.POSE}
        assert "view" not in mission.settings.get("observers", {})  # older keys stay valid
    alone = {m.seed for m in missions["wheels"] if not to_spec(m).observers}
    assert alone <= {m.seed for m in missions["pose"]}  # the robot alone: the same missions
    watched = {m.seed for m in missions["wheels"] if to_spec(m).observers}
    assert not watched & {m.seed for m in missions["pose"]}  # a wheel team: other situations


def _spec(observers: tuple[Observer, ...], strategy: str = "active-diagnosis") -> MissionSpec:
    maze = load_bundled("narrow-long")
    route = bundled_routes("narrow-long")[0]
    schedule = FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FL:F"), detection=Detection.HIDDEN)
    return MissionSpec(
        maze, route.start, route.goal, schedule=schedule, strategy=strategy, seed=3,
        observation=ObservationModel(0.05), observers=observers,
    )  # fmt: skip


def test_teammates_readings_reach_the_belief_and_the_result() -> None:
    team = tuple(Observer(f"t{i}", 0.05, SensingRange(3)) for i in (1, 2))
    alone, together = run_mission(_spec(())), run_mission(_spec(team))
    assert {o.source for o in alone.observations} == {"self"}
    assert len(alone.observations) == len(alone.steps) == len(alone.beliefs)
    sources = {o.source for o in together.observations}
    assert sources == {"self", "t1", "t2"}
    assert len(together.observations) > len(together.steps)  # in range most of the time
    assert all(o.bumped is None for o in together.observations if o.source != "self")
    assert mission_row(together)["observers"] == 2 and mission_row(alone)["observers"] == 0
    again = run_mission(_spec(team))
    assert again.observations == together.observations  # seeded streams
    # trial and error has no belief to feed: it records the readings, no belief
    trial = run_mission(_spec(team, "trial-and-error"))
    assert trial.observations and not trial.beliefs


def test_an_observer_sees_only_motions_in_its_range() -> None:
    near = (Observer("t1", 0.0, SensingRange(0)),)  # range 0: its own cell only
    result = run_mission(_spec(near))
    trail = [result.spec.start] + [s.end for s in result.steps]
    seen = [o for o in result.observations if o.source == "t1"]
    assert seen and len(seen) < len(result.steps)
    for o in seen:  # it stands where the robot was one command before, start and end there
        where = trail[max(0, o.step - 1)]
        assert o.start.cell == where.cell == o.end.cell


def test_a_teammate_reading_takes_out_what_it_contradicts() -> None:
    model = fault_model(FOUR_WHEEL)
    start, action = Pose(4, 4, Heading.N), parse_action("FFFF")
    moved = FOUR_WHEEL.apply(start, action)
    belief = FaultBelief(model)
    belief.update(Observation(0, action, start, moved, False, False, 0.0, "t1"))
    healthy = model.sets.index(frozenset())
    assert belief.alive >> healthy & 1  # the healthy robot explains the reading
    assert bin(belief.alive).count("1") < model.size  # hypotheses that stall FFFF are gone


def _row(strategy: str, **values: Any) -> dict[str, Any]:
    base: dict[str, Any] = {
        "maze": "m", "route": "r", "faults": "FL:F", "fault_count": 1, "fault_at": 0,
        "detection": "hidden", "replicate": 0, "observation_noise": 0.0, "observers": 0,
        "strategy": strategy, "variant": strategy, "reached": 1, "ticks_float": 10.0,
        "bumps": 0, "surprise_step": None, "isolation_actions": None, "isolated_right": None,
    }  # fmt: skip
    base.update(values)
    return base


def _by_number(rows: list[dict[str, Any]]) -> dict[str, Any]:
    return {f.number: f for f in diagnosis_findings(rows)}


def test_g1_is_not_held_when_one_oracle_mission_is_missed() -> None:
    rows = []
    for i in range(20):
        rows.append(_row("oracle", route=str(i)))
        rows.append(_row("diagnose", route=str(i), ticks_float=11.0, reached=int(i != 7)))
    found = _by_number(rows)["G1"]
    assert found.outcome is Outcome.NOT_HELD and "reaches 19 of 20" in found.evidence
    for row in rows:
        row["reached"] = 1
    assert _by_number(rows)["G1"].outcome is Outcome.HELD  # ratio 1.1 <= 1.25
    for row in rows:
        if row["strategy"] == "diagnose":
            row["ticks_float"] = 14.0
    assert _by_number(rows)["G1"].outcome is Outcome.NOT_HELD  # ratio 1.4


def test_g2_and_g3_judge_paired_commands_to_isolate() -> None:
    rows = []
    for i in range(30):
        place = {"route": str(i), "observation_noise": 0.01, "surprise_step": 2}
        rows.append(_row("diagnose", isolation_actions=6, isolated_right=1, **place))
        rows.append(_row("active-diagnosis", isolation_actions=3, isolated_right=1, **place))
        rows.append(_row("active-diagnosis", observers=2, isolation_actions=2, isolated_right=1,
                         **place))  # fmt: skip
        rows.append(_row("diagnose", observers=2, isolation_actions=6, isolated_right=1, **place))
    found = _by_number(rows)
    assert found["G2"].outcome is Outcome.HELD
    # active: 2 against 3 is a cut of a third (held); diagnose: none (not held): not held overall
    g3 = found["G3"]
    assert g3.outcome is Outcome.NOT_HELD
    assert any("active-diagnosis, noise 0.01, 2 observers" in line and line.endswith("held.")
               and "not held" not in line for line in g3.lines)  # fmt: skip
    assert found["G1"].applies is False and found["G4"].outcome is Outcome.INCONCLUSIVE


def test_no_hidden_rows_no_diagnosis_findings() -> None:
    assert diagnosis_findings([{"strategy": "replan", "observation_noise": None}]) == []


def test_experiment_runs_the_small_design_and_prints_the_findings(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    assert main(["experiment", str(path), "--db", str(tmp_path / "r.sqlite"), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    for number in ("G1", "G1t", "G2", "G3", "G4"):
        assert f"Finding {number}" in out
    assert "48 missions" in out
