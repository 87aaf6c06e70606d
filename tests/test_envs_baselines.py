"""Baseline policies on the Gymnasium environment against the reference experiment, the
evaluation's intervals, and ``selfrepair gym-eval`` driven in-process."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest

from selfrepair.cli import main
from selfrepair.envs import FaultyMazeEnv
from selfrepair.envs.evaluate import EpisodeEnd, Evaluation, episode_seeds, evaluate, run_episode
from selfrepair.envs.policies import PlannerPolicy, make_policy, policy_names
from selfrepair.errors import ProblemError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.config import load_config
from selfrepair.experiment.missions import expand, to_spec
from selfrepair.stats import bootstrap_interval, wilson_interval


def _paper_specs(variant: str) -> list[MissionSpec]:
    """The reference experiment's missions of ``variant`` at clearance weight 0."""
    path = resources.files("selfrepair").joinpath("data", "experiments", "paper.toml")
    missions = expand(load_config(str(path)))
    chosen = [
        m
        for m in missions
        if dict(m.labels)["variant"] == variant and str(dict(m.labels)["clearance_weight"]) == "0"
    ]
    return [to_spec(m) for m in chosen]


def _options(spec: MissionSpec) -> dict[str, object]:
    return {"maze": spec.maze, "start": spec.start, "goal": spec.goal, "faults": spec.schedule}


@pytest.mark.parametrize(
    "recursion",
    ["flat", pytest.param("guarded", marks=pytest.mark.slow)],
)
def test_replacement_policy_matches_the_paper_replacement_robot(recursion: str) -> None:
    """Every mission of the paper experiment's replacement robot (hand-written table): the
    policy in the environment reaches the goal whenever the executor does, in the same steps."""
    specs = _paper_specs(f"replacement[handwritten,{recursion}]")
    assert len(specs) == 192
    env = FaultyMazeEnv(recursion=recursion)
    policy = make_policy("replacement")
    executor_reached = env_reached = 0
    for spec in specs:
        result = run_mission(spec)
        episode = run_episode(env, policy, spec.seed, _options(spec))
        assert episode.reached >= result.reached
        assert episode.steps == len(result.steps), spec
        executor_reached += result.reached
        env_reached += episode.reached
    assert env_reached >= executor_reached


def test_random_policy_reaches_far_fewer_goals() -> None:
    specs = _paper_specs("replacement[handwritten,flat]")
    specs = [s for s in specs if s.maze.name == "narrow-short"]
    env = FaultyMazeEnv()
    replacement, random = make_policy("replacement"), make_policy("random")
    planned = sum(run_episode(env, replacement, 0, _options(s)).reached for s in specs)
    lucky = sum(run_episode(env, random, i, _options(s)).reached for i, s in enumerate(specs[:24]))
    assert planned == len(specs) == 48
    assert lucky <= 24 // 4


def test_replan_policy_reaches_like_the_executor() -> None:
    specs = [s for s in _paper_specs("replan") if s.maze.name == "wide-short"]
    env = FaultyMazeEnv(mazes="wide-short")
    policy = make_policy("replan")
    for spec in specs[:12]:
        result = run_mission(spec)
        episode = run_episode(env, policy, 0, _options(spec))
        assert (episode.reached, episode.steps) == (result.reached, len(result.steps))


def test_policy_gives_up_when_no_plan_exists() -> None:
    env = FaultyMazeEnv(domain="three-action", mazes="narrow-short")
    episode = run_episode(
        env, make_policy("replacement"), 0, {"maze": "narrow-short", "start": "1,1,E",
                                              "goal": "13,13", "faults": "F"}
    )  # fmt: skip
    assert episode.end is EpisodeEnd.GAVE_UP and not episode.reached


def test_evaluation_is_paired_and_seeded() -> None:
    env = FaultyMazeEnv(mazes="narrow-short", max_steps=60)
    first = evaluate(env, make_policy("replacement"), 6, seed=4)
    other = evaluate(env, make_policy("random"), 6, seed=4)
    situation = [(e.seed, e.maze, e.start, e.goal, e.faults) for e in first.episodes]
    assert situation == [(e.seed, e.maze, e.start, e.goal, e.faults) for e in other.episodes]
    assert [e.seed for e in first.episodes] == list(episode_seeds(4, 6))
    assert first.successes == 6 and other.successes < 6
    again = evaluate(env, make_policy("random"), 6, seed=4)
    assert again == other
    with pytest.raises(ProblemError, match="--max-episodes"):
        evaluate(env, make_policy("random"), 11, max_episodes=10)


def test_intervals() -> None:
    interval = wilson_interval(8, 10)
    assert interval is not None and interval.estimate == 0.8 and interval.n == 10
    z = 1.959963984540054
    centre = (0.8 + z * z / 20) / (1 + z * z / 10)
    half = z / (1 + z * z / 10) * math.sqrt(0.8 * 0.2 / 10 + z * z / 400)
    assert interval.low == pytest.approx(centre - half) and interval.high == pytest.approx(
        centre + half
    )
    top = wilson_interval(10, 10)
    assert top is not None and top.high == pytest.approx(1.0)
    assert wilson_interval(0, 0) is None
    values = [-10.0, -12.0, -8.0, -30.0, -9.0, -11.0]
    boot = bootstrap_interval(values, "mean", seed=1)
    assert boot is not None and boot.low < sum(values) / len(values) < boot.high
    assert boot.low >= -30.0


def test_evaluation_intervals_are_undefined_for_too_few_episodes() -> None:
    empty = Evaluation("replan", 3, ())
    assert math.isnan(empty.success_interval().low) and math.isnan(empty.return_interval().low)
    assert empty.success_interval().level == 0.95


def test_policy_names_and_misuse() -> None:
    assert policy_names() == ("replacement", "replan", "random")
    with pytest.raises(ProblemError, match="unknown policy"):
        make_policy("greedy")
    with pytest.raises(ProblemError, match="reset"):
        PlannerPolicy("replan")({}, {})


def test_gym_eval_prints_rates_with_intervals(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["--policy", "replacement", "--episodes", "4", "--maze", "narrow-short"]
    code = main(["gym-eval", *args])
    out = capsys.readouterr().out
    assert code == 0
    assert "success rate 1.000 (4/4), 95% Wilson interval [0.510, 1.000]" in out
    assert "mean return" in out and "95% bootstrap interval [" in out


def test_gym_eval_json(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["gym-eval", "--policy", "random", "--episodes", "3", "--seed", "2", "--json"]
    code = main([*args, "--domain", "three-action", "--maze", "narrow-short", "--max-steps", "40"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0
    assert data["policy"] == "random" and data["domain"] == "three-action"
    assert len(data["runs"]) == 3 and all(r["steps"] <= 40 for r in data["runs"])
    low, high = data["success_interval"]
    assert 0.0 <= low <= data["success_rate"] <= high <= 1.0


def test_gym_eval_paper_faults_and_generated_mazes(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["gym-eval", "--episodes", "3", "--faults", "paper", "--generate", "15x15", "--json"]
    )
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and all(r["maze"].startswith("gen15x15") for r in data["runs"])


def test_gym_eval_with_a_plugin_robot(capsys: pytest.CaptureFixture[str]) -> None:
    omni = Path(__file__).resolve().parent.parent / "examples" / "omni"
    args = ["--domain", "omni", "--table", str(omni / "table-indexed.json"), "--faults", "FL:F"]
    plugin = ["--plugin", str(omni / "robot.py")]
    code = main([*plugin, "gym-eval", *args, "--episodes", "3", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 0 and data["domain"] == "omni" and data["successes"] == 3


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--policy", "greedy"], "unknown policy"),
        (["--faults", "paper", "--domain", "three-action"], "--faults"),
        (["--generate", "15by15"], "--generate"),
        (["--episodes", "20", "--max-episodes", "10"], "--max-episodes"),
        (["--detection", "sometimes"], "detection"),
    ],
)
def test_gym_eval_bad_input_is_one_line(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["gym-eval", *args])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_cli_import_loads_no_gymnasium() -> None:
    probe = "import sys, selfrepair.cli; print('gymnasium' in sys.modules, 'scipy' in sys.modules)"
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    ).stdout
    assert out.split() == ["False", "False"]
