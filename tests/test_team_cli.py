"""Team commands, driven in-process: ``team run|compare|replay|table|frame``, team experiments
(``experiment``, ``report``, ``animate``), bad input (one line, exit 2, before anything runs),
and the re-simulation of the bundled team experiment's traces."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from selfrepair.cli import main
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.teams import expand_team, load_experiment

SCENARIO = """
name = "mine"
maze = "wide-short"

[[robots]]
name = "r1"
start = "1,1,E"

[[robots]]
name = "r2"
start = "22,13,W"

[[tasks]]
item = "i1"
pickup = "5,4"
dropoff = "16,1"
"""


def _write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("selfrepair: error: ") and "Traceback" not in err
    return err


# --- bad input ------------------------------------------------------------------------------------


def test_a_task_on_a_wall_is_refused_before_anything_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write(tmp_path, SCENARIO.replace('pickup = "5,4"', 'pickup = "3,4"'))
    trace = tmp_path / "t.jsonl"
    assert main(["team", "run", str(path), "--trace", str(trace)]) == 2
    err = _one_error_line(capsys)
    assert "task i1: pickup 3,4 is a wall" in err and f"{path}:" in err
    assert ":15:" in err  # the pickup line of the task
    assert not trace.exists()


def test_more_robots_than_free_cells_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tiny = _write(tmp_path, "#####\n#...#\n#####\n", "tiny.maze")
    path = _write(tmp_path, f'maze = "{tiny}"\nrobots = 4\ntasks = 0\n')
    assert main(["team", "run", str(path)]) == 2
    err = _one_error_line(capsys)
    assert "4 robots" in err and "3" in err and ":2:" in err


def test_more_explicit_robots_than_free_cells_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tiny = _write(tmp_path, "####\n#..#\n####\n", "tiny.maze")
    robots = "".join(f'[[robots]]\nname = "r{i}"\nstart = "1,1,E"\n' for i in range(3))
    path = _write(tmp_path, f'maze = "{tiny}"\n{robots}')
    assert main(["team", "run", str(path)]) == 2
    assert "3 robots do not fit" in _one_error_line(capsys)


def test_an_item_no_robot_can_reach_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    split = _write(tmp_path, "#######\n#..#..#\n#..#..#\n#######\n", "split.maze")
    text = (
        f'maze = "{split}"\n[[robots]]\nname = "r1"\nstart = "1,1,E"\n'
        '[[tasks]]\nitem = "far"\npickup = "4,1"\ndropoff = "5,2"\n'
    )
    path = _write(tmp_path, text)
    assert main(["team", "run", str(path)]) == 2
    err = _one_error_line(capsys)
    assert "item far at 4,1: no robot with a gripper can reach it" in err and ":7:" in err


def test_an_item_only_a_gripperless_robot_reaches_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = SCENARIO.replace('start = "1,1,E"', 'start = "1,1,E"\ngripper = false').replace(
        'start = "22,13,W"', 'start = "22,13,W"\ngripper = false'
    )
    assert main(["team", "run", str(_write(tmp_path, text))]) == 2
    assert "no robot with a gripper" in _one_error_line(capsys)


def test_bad_scenario_keys_and_faults_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for text, expected in (
        (SCENARIO + "colour = 3\n", "key 'tasks[0].colour': unknown key"),
        ("colour = 3\n" + SCENARIO, "key 'colour': unknown key"),
        (SCENARIO + '[[faults]]\nkind = "melted"\nrobot = "r1"\n', "key 'faults[0].kind'"),
        (SCENARIO + '[[faults]]\nkind = "gripper"\nrobot = "r9"\n', "unknown robot 'r9'"),
        (SCENARIO + '[[faults]]\nkind = "wheels"\nrobot = "r1"\nwheel_faults = "XX:F"\n', "XX:F"),
        (SCENARIO.replace('"1,1,E"', '"1,1"'), ":7: key 'robots[0].start'"),
        ("maze = [\n", "invalid TOML"),
    ):
        assert main(["team", "run", str(_write(tmp_path, text))]) == 2, expected
        assert expected in _one_error_line(capsys)


def test_a_team_experiment_too_big_for_its_maze_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (
        'kind = "team"\nname = "big"\n[[mazes]]\nbundled = "narrow-short"\n[team]\n'
        'sizes = [2, 40]\n[faults]\ncases = ["none"]\n[[strategies]]\nname = "alone"\n'
    )
    db = tmp_path / "big.sqlite"
    assert main(["experiment", str(_write(tmp_path, text, "big.toml")), "--db", str(db)]) == 2
    err = _one_error_line(capsys)
    assert "key 'team.sizes'" in err and "40 robots" in err and ":6:" in err
    assert not db.exists()


def test_a_team_experiment_with_a_bad_key_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = 'kind = "team"\nname = "x"\n[[mazes]]\nbundled = "wide-short"\n[team]\nsizes = [2]\n'
    text += '[faults]\ncases = ["lava"]\n[[strategies]]\nname = "alone"\n'
    assert main(["experiment", str(_write(tmp_path, text, "x.toml"))]) == 2
    assert "faults.cases" in _one_error_line(capsys)


# --- commands -------------------------------------------------------------------------------------


def test_team_run_trace_replay_frame_and_animate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = tmp_path / "t.jsonl"
    assert main(["team", "run", "three-robots", "--trace", str(trace), "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert row["all_delivered"] == 1 and row["team_replacements"] >= 1
    assert row["baseline_makespan"] and row["makespan_ratio"] >= 1
    assert main(["team", "replay", str(trace)]) == 0
    assert "no conflict, no teleport" in capsys.readouterr().out
    png = tmp_path / "f.png"
    assert main(["team", "frame", str(trace), "-o", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"
    gif = tmp_path / "m.gif"
    assert main(["animate", str(trace), "-o", str(gif), "--max-frames", "8"]) == 0
    assert gif.read_bytes()[:3] == b"GIF"


def test_team_frame_and_animation_refuse_the_wrong_suffix_before_reading(tmp_path: Path) -> None:
    from selfrepair.errors import TraceError
    from selfrepair.team.draw import animate_team_trace, draw_team_frame

    missing = tmp_path / "absent.jsonl"  # never read: the output's suffix is checked first
    with pytest.raises(TraceError, match=r"m\.gif: expected an output file ending in \.png"):
        draw_team_frame(missing, tmp_path / "m.gif")
    with pytest.raises(TraceError, match=r"f\.png: expected an output file ending in \.gif"):
        animate_team_trace(missing, tmp_path / "f.png")


def test_team_replay_exits_1_on_a_conflict(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    trace = tmp_path / "t.jsonl"
    assert main(["team", "run", "three-robots", "--strategy", "alone", "--trace", str(trace)]) == 1
    lines = trace.read_text().splitlines()
    moves = [i for i, line in enumerate(lines) if '"type": "move"' in line]
    data = json.loads(lines[moves[0]])
    data["from"], data["to"] = [5, 5, "N"], [5, 4, "N"]
    lines[moves[0]] = json.dumps(data)
    trace.write_text("\n".join(lines) + "\n")
    capsys.readouterr()
    assert main(["team", "replay", str(trace)]) == 1
    assert "teleport" in capsys.readouterr().out


def test_team_table_and_compare(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["team", "table", "generated", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {"handover-deliver", "detour", "fetch-hand"} <= {r["candidate"] for r in rows}
    assert main(["team", "table"]) == 0 and "handover-deliver" in capsys.readouterr().out
    assert main(["team", "compare", "three-robots", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert "team-replacement[handwritten]" in out and "reallocation" in out and "6/6" in out


def test_team_experiment_report_and_resume(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (
        'kind = "team"\nname = "mini"\nseed = 5\n[[mazes]]\nbundled = "wide-short"\n[team]\n'
        'sizes = [3]\n[faults]\ncases = ["immobilised-carrying"]\n'
        '[[strategies]]\nname = "team-replacement"\n[[strategies]]\nname = "reallocation"\n'
    )
    config, db = _write(tmp_path, text, "mini.toml"), tmp_path / "mini.sqlite"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    out = capsys.readouterr().out
    assert "2 missions, 0 already stored, 2 run" in out and "reallocation" in out
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    assert "2 already stored, 0 run" in capsys.readouterr().out
    report = tmp_path / "report"
    assert main(["report", str(db), "-o", str(report)]) == 0
    text = (report / "report.md").read_text()
    assert "# Team missions" in text and "team-replacement[handwritten]" in text
    assert main(["team", "replay", str(report / "mission.jsonl")]) == 0


# --- every trace of the team experiment re-simulates ----------------------------------------------


def _replays(mission: Mission, tmp_path: Path) -> str:
    from selfrepair.experiment.keys import canonical_json
    from selfrepair.experiment.mazes import maze_of
    from selfrepair.experiment.teams import _case_of, _options_of
    from selfrepair.team.experiment import run_case
    from selfrepair.team.trace import read_team_trace, replay_team, write_team_trace

    s = mission.settings
    result, baseline = run_case(
        maze_of(canonical_json(s["maze"])), _case_of(s, mission.seed), _options_of(s, mission.seed)
    )
    path = tmp_path / f"{mission.key}.jsonl"
    write_team_trace(result, path, baseline)
    report = replay_team(read_team_trace(path))
    return "" if report.ok else f"{mission.config}: {report}"


def _bundled_missions() -> tuple[Mission, ...]:
    from importlib import resources

    path = resources.files("selfrepair").joinpath("data", "experiments", "team.toml")
    config = load_experiment(Path(str(path)))
    assert not isinstance(config, type(None))
    return expand_team(config)  # type: ignore[arg-type]


def test_a_sample_of_the_team_experiment_re_simulates(tmp_path: Path) -> None:
    missions = _bundled_missions()
    sizes = {dict(m.labels)["team_size"] for m in missions}
    assert min(sizes) == 2 and max(sizes) == 8
    cases = {dict(m.labels)["fault_case"] for m in missions}
    assert {"immobilised-carrying", "gripper", "blocked", "wheels"} <= cases
    sample = missions[::41]
    problems = [p for m in sample if (p := _replays(m, tmp_path))]
    assert not problems, problems[:3]


@pytest.mark.slow
def test_every_trace_of_the_team_experiment_re_simulates(tmp_path: Path) -> None:
    problems = [p for m in _bundled_missions() if (p := _replays(m, tmp_path))]
    assert not problems, problems[:3]


def test_robot_and_task_limits_name_their_flags(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["team", "run", "three-robots", "--max-robots", "2"]) == 2
    assert "at most 2 robots" in (err := _one_error_line(capsys)) and "--max-robots" in err
    assert main(["team", "run", "three-robots", "--max-tasks", "5"]) == 2
    assert "--max-tasks" in _one_error_line(capsys)
    path = _write(tmp_path, 'maze = "wide-short"\nrobots = 3\ntasks = 9\n')
    assert main(["team", "run", str(path), "--max-tasks", "8"]) == 2
    assert "at most 8 tasks" in _one_error_line(capsys)
