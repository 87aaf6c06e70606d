"""A robot the library does not ship (examples/omni/robot.py) goes through everything that
docs/extending.md shows: registration, planning (both backends), table generation, coverage,
missions with every strategy, traces and replay, an experiment in worker processes, and the
report. Nothing in the library knows this robot."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.cli import main
from selfrepair.errors import InputError, ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import Domain, check_domain
from selfrepair.robots.registry import domain_names, get_domain, load_plugin
from selfrepair.search.lattice import plan, plan_cost
from selfrepair.search.problem import PlanningProblem
from selfrepair.tables.fileformat import dump_table
from selfrepair.tables.generate import generate_table
from selfrepair.tables.model import GenerateOptions
from selfrepair.world.maze import Maze

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "omni"
ROBOT = EXAMPLE / "robot.py"


@pytest.fixture(scope="module")
def omni() -> Domain:  # type: ignore[type-arg]
    load_plugin(ROBOT)
    return get_domain("omni")


def test_the_example_robot_is_a_valid_registered_domain(omni: Domain) -> None:  # type: ignore[type-arg]
    check_domain(omni)
    assert "omni" in domain_names()
    assert len(omni.actions) == 10 and len(omni.faults) == 8 and len(omni.fault_sets) == 8 + 28
    assert load_plugin(ROBOT) == load_plugin(ROBOT)  # loaded once per process


def test_a_broken_plugin_is_one_clear_error(tmp_path: Path) -> None:
    bad = tmp_path / "bad.py"
    bad.write_text("raise RuntimeError('no wheels')\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"bad\.py.*no wheels"):
        load_plugin(bad)
    assert main(["--plugin", str(bad), "domains"]) == 2
    assert main(["--plugin", str(tmp_path / "missing.py"), "domains"]) == 2


def test_a_domain_that_breaks_the_contract_is_refused(omni: Domain) -> None:  # type: ignore[type-arg]
    from dataclasses import replace

    drifting = replace(omni, name="drift", apply=lambda pose, a: Pose(abs(pose.x), 0, pose.heading))
    with pytest.raises(ProblemError, match="translation"):
        check_domain(drifting)


@st.composite
def problems(draw: st.DrawFn) -> PlanningProblem:
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    walls = rng.random((8, 9)) < draw(st.sampled_from([0.0, 0.15, 0.3]))
    free = [(int(x), int(y)) for y, x in zip(*np.nonzero(~walls), strict=True)]
    if len(free) < 2:
        walls[0, 0] = walls[7, 8] = False
        free = [(0, 0), (8, 7)]
    start = free[draw(st.integers(0, len(free) - 1))]
    goal = free[draw(st.integers(0, len(free) - 1))]
    heading = draw(st.sampled_from(list(Heading)))
    faults = draw(st.sampled_from(["", "FL:F", "FL:F,RR:B", "FR:B"]))
    omni = get_domain("omni")
    return PlanningProblem(
        Maze(walls), Pose(*start, heading), goal, faults=omni.parse_faults(faults), domain=omni
    )


@NUMBA
@settings(max_examples=40, deadline=None)
@given(problems())
def test_the_compiled_planner_runs_the_new_robot_exactly_like_the_reference(
    omni: Domain,  # type: ignore[type-arg]
    problem: PlanningProblem,
) -> None:
    reference = plan(problem, backend="python")
    compiled = plan(problem, backend="numba")
    assert (compiled.status, compiled.actions, compiled.cost) == (
        reference.status,
        reference.actions,
        reference.cost,
    )
    assert compiled.expansions == reference.expansions
    if reference.cost is not None:
        assert plan_cost(problem, reference.actions) == reference.cost


def test_the_shipped_tables_are_what_the_generator_makes(omni: Domain) -> None:  # type: ignore[type-arg]
    for shape, name in (("fault-indexed", "table-indexed"), ("fault-agnostic", "table-agnostic")):
        table = generate_table(omni, GenerateOptions(shape=shape))  # type: ignore[arg-type]
        assert dump_table(table) == (EXAMPLE / f"{name}.json").read_text(encoding="utf-8")


def test_the_walkthrough_of_docs_extending(
    omni: Domain,  # type: ignore[type-arg]
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    plugin = ["--plugin", str(ROBOT)]
    work = tmp_path / "omni"
    shutil.copytree(EXAMPLE, work)
    assert main([*plugin, "domains"]) == 0 and "omni" in capsys.readouterr().out
    assert main([*plugin, "table", "coverage", str(work / "table-agnostic.json"), "--json"]) == 0
    coverage = json.loads(capsys.readouterr().out)
    assert coverage["totals"]["fault_sets"] == 36 and coverage["totals"]["optimal_share"] == 1.0
    statuses = {}
    for strategy in ("replan", "replacement", "lookahead"):
        trace = work / f"{strategy}.jsonl"
        code = main(
            [*plugin, "run", "narrow-short", "--domain", "omni", "--start", "1,1,E",
             "--goal", "13,13", "--faults", "FL:F", "--strategy", strategy,
             "--table", str(work / "table-indexed.json"), "--recursion", "guarded",
             "--trace", str(trace), "--json"]
        )  # fmt: skip
        row = json.loads(capsys.readouterr().out)
        statuses[strategy] = (code, row["status"], row["domain"])
        assert main([*plugin, "replay", str(trace)]) == 0
        assert "ok" in capsys.readouterr().out
    assert set(statuses.values()) == {(0, "reached", "omni")}
    small = (work / "experiment.toml").read_text(encoding="utf-8")
    small = small.replace('bundled = "wide-short"', 'bundled = "narrow-short"')
    small = re.sub(r'sets = "singles"', 'sets = ["FL:F", "RR:B"]', small)
    (work / "small.toml").write_text(small, encoding="utf-8")
    db = tmp_path / "omni.sqlite"
    assert main(["experiment", str(work / "small.toml"), "--db", str(db), "--jobs", "2"]) == 0
    assert "omni:" in capsys.readouterr().out
    assert main(["report", str(db), "-o", str(tmp_path / "report")]) == 0
    assert (tmp_path / "report" / "report.md").is_file()


def test_the_python_example_of_docs_extending_runs(omni: Domain) -> None:  # type: ignore[type-arg]
    text = (ROOT / "docs" / "extending.md").read_text(encoding="utf-8")
    code = re.search(r"## In Python\n\n```python\n(.*?)```", text, re.S)
    assert code is not None
    exec(compile(code.group(1).replace("examples/omni", str(EXAMPLE)), "extending.md", "exec"), {})
