"""``selfrepair pddl``, driven in-process."""

from __future__ import annotations

from pathlib import Path

import pytest

from selfrepair.baselines.pddltext import parse_pddl_plan
from selfrepair.cli import main
from selfrepair.geometry import Heading, Pose
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.bundled import load_bundled

ROUTE = ["narrow-short", "--start", "7,13,W", "--goal", "1,8"]


def test_writes_domain_and_problem(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert main(["pddl", *ROUTE, "--faults", "FL:F", "-o", str(out)]) == 0
    domain = (out / "domain.pddl").read_text(encoding="utf-8")
    problem = (out / "problem.pddl").read_text(encoding="utf-8")
    assert domain.count("(:action ") == 81
    assert "(define (problem narrow-short)" in problem
    assert "(healthy fl f)" not in problem and "(healthy fl s)" in problem
    assert "(robot-at c7_13) (facing west)" in problem
    assert "(:goal (and (robot-at c1_8)))" in problem
    lines = capsys.readouterr().out.splitlines()
    assert lines[1] == "97 cells, 408 static facts, 2145 ground actions"
    assert not (out / "plan.pddl").exists()


def test_goal_heading_name_and_plan(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = ["pddl", "narrow-short", "--start", "7,13,W", "--goal", "1,8,N", "--name", "r1"]
    assert main([*args, "--plan", "-o", str(tmp_path)]) == 0
    problem = (tmp_path / "problem.pddl").read_text(encoding="utf-8")
    assert "(define (problem r1)" in problem and "(facing north)" in problem
    start = Pose(7, 13, Heading.W)
    expected = plan(PlanningProblem(load_bundled("narrow-short"), start, (1, 8), Heading.N))
    text = (tmp_path / "plan.pddl").read_text(encoding="utf-8")
    assert parse_pddl_plan(text, start) == expected.actions
    assert f"{len(expected.actions)} steps" in capsys.readouterr().out


def test_no_plan_is_exit_1(tmp_path: Path) -> None:
    maze = tmp_path / "split.txt"
    maze.write_text("..#..\n..#..\n", encoding="utf-8")
    args = ["pddl", str(maze), "--start", "0,0,E", "--goal", "4,0", "--plan", "-o", str(tmp_path)]
    assert main(args) == 1
    assert (tmp_path / "problem.pddl").exists() and not (tmp_path / "plan.pddl").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--start", "7,13"], "--start: expected a pose X,Y,H"),
        (["--start", "0,0,E"], "the start (0,0) is a wall"),
        (["--goal", "99,1"], "the goal (99,1) is outside the 15x15 maze"),
        (["--faults", "FL:X"], "--faults: expected a fault WHEEL:MODE"),
        (["--max-cells", "100"], "more than the PDDL export limit of 100; raise it with"),
        (["--max-cells", "0"], "--max-cells"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    base = {"--start": "7,13,W", "--goal": "1,8"}
    base.update(dict(zip(args[::2], args[1::2], strict=True)))
    argv = ["pddl", "narrow-short", *(x for kv in base.items() for x in kv), "-o", str(tmp_path)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "domain.pddl").exists()


def test_unknown_maze_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["pddl", "nowhere", "--start", "1,1,E", "--goal", "2,2", "-o", str(tmp_path)]) == 2
    assert "unknown maze 'nowhere'" in capsys.readouterr().err
