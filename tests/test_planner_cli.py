"""``selfrepair plan`` and ``selfrepair path``, driven in-process."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from extras import need
from selfrepair.cli import main

U_TURN = ".....\n.###.\n.....\n"


@pytest.fixture
def maze_file(tmp_path: Path) -> Path:
    path = tmp_path / "u.txt"
    path.write_text(U_TURN, encoding="utf-8")
    return path


def run_json(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, dict]:
    code = main(args)
    return code, json.loads(capsys.readouterr().out)


def test_plan_json_shape(maze_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, data = run_json(
        ["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2", "--json"], capsys
    )
    assert code == 0
    assert data["status"] == "solved"
    assert data["cost"] == 7 and data["duration"] == 7
    assert data["actions"] == ["FFFF"] * 4 + ["FBFB"] + ["FFFF"] * 2
    assert data["poses"][0] == [0, 0, "E"] and data["poses"][-1] == [4, 2, "S"]
    assert len(data["poses"]) == len(data["actions"]) + 1
    assert data["expansions"] > 0


def test_plan_fractional_cost_is_a_number_with_an_exact_twin(
    maze_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, data = run_json(
        ["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2,W",
         "--clearance-weight", "1/3", "--json"],
        capsys,
    )  # fmt: skip
    assert code == 0
    assert data["cost_exact"] == "38/3"  # duration 8 + 1/3 * 14 cells of shortfall 1 (radius 2)
    assert data["cost"] == 12.666667  # a JSON number, rounded
    assert data["duration"] == 8 and data["duration_exact"] == "8"
    assert data["poses"][-1] == [4, 2, "W"]


def test_plan_reports_the_search_apart_from_the_kernel_load(
    maze_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, data = run_json(
        ["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2", "--json"], capsys
    )
    assert code == 0 and set(data) >= {"search_ms", "kernel_load_ms"}
    assert "wall_time_ms" not in data
    assert main(["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2"]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    assert re.fullmatch(r"expansions: \d+  search: [\d.]+ ms(  \(kernels loaded .*\))?", last)


def test_kernels_are_loaded_before_the_search_is_timed(
    maze_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The command loads the kernels first, then calls the planner: the order is the point."""
    from selfrepair.search import lattice, warmup

    need("numba", "fast")  # the kernels are what is loaded
    calls: list[str] = []
    monkeypatch.setattr(warmup, "_WARM", set())

    def load(*kinds: str) -> int:
        calls.append("load " + ",".join(kinds))
        return 5_000_000

    monkeypatch.setattr(warmup, "warm_up", load)
    real_plan = lattice.plan
    monkeypatch.setattr(lattice, "plan", lambda *a, **k: calls.append("plan") or real_plan(*a, **k))
    code, data = run_json(
        ["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2", "--backend", "numba",
         "--json"],
        capsys,
    )  # fmt: skip
    # only the lattice kernels, which plan uses, are loaded, and before the search
    assert code == 0 and calls == ["load lattice", "plan"] and data["kernel_load_ms"] == 5.0


def test_plan_with_faults_uses_available_actions(
    maze_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, data = run_json(
        ["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,0", "--faults", "FL:F",
         "--json"],
        capsys,
    )  # fmt: skip
    assert code == 0
    assert all(a[0] != "F" for a in data["actions"])
    assert data["cost"] == 6


def test_plan_picture(maze_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2"]) == 0
    out = capsys.readouterr().out
    assert out.startswith(">oooo\n.###o\n....G\n")
    assert "status: solved" in out and "cost: 7" in out


def test_plan_unsolvable_exit_one(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    maze = tmp_path / "split.txt"
    maze.write_text("..#..\n..#..\n", encoding="utf-8")
    code, data = run_json(
        ["plan", str(maze), "--start", "0,0,E", "--goal", "4,0", "--json"], capsys
    )
    assert code == 1
    assert data["status"] == "unsolvable" and data["cost"] is None and data["actions"] == []


def test_plan_budget_exit_one(maze_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, data = run_json(
        ["plan", str(maze_file), "--start", "0,0,E", "--goal", "4,2", "--max-expansions", "2",
         "--json"],
        capsys,
    )  # fmt: skip
    assert code == 1 and data["status"] == "budget_exhausted"


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--start", "1,1,E", "--goal", "4,2"], "wall"),
        (["--start", "0,0,Q", "--goal", "4,2"], "--start"),
        (["--start", "0,0,E", "--goal", "4"], "--goal"),
        (["--start", "0,0,E", "--goal", "4,2", "--faults", "XX:F"], "--faults"),
        (["--start", "0,0,E", "--goal", "4,2", "--clearance-weight", "abc"], "--clearance-weight"),
        (["--start", "0,0,E", "--goal", "4,2", "--clearance-weight", "-1"], "--clearance-weight"),
        # 1e308 was accepted and printed a 310-digit cost
        (["--start", "0,0,E", "--goal", "4,2", "--clearance-weight", "1e308"], "1,000,000"),
        (["--start", "0,0,E", "--goal", "4,2", "--heuristic", "nope"], "heuristic"),
    ],
)
def test_plan_bad_input_exit_two(
    maze_file: Path, extra: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["plan", str(maze_file), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_path_json_shape(maze_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, data = run_json(
        ["path", str(maze_file), "--from", "0,0", "--to", "4,2", "--json"], capsys
    )
    assert code == 0
    assert data["status"] == "solved"
    assert data["cost"] == 6.0
    assert data["cost_exact"] == {"straight": 6, "diagonal": 0, "text": "6"}
    assert data["path"][0] == [0, 0] and data["path"][-1] == [4, 2] and len(data["path"]) == 7


def test_path_diagonal_cost(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    maze = tmp_path / "open.txt"
    maze.write_text("...\n...\n...\n", encoding="utf-8")
    code, data = run_json(["path", str(maze), "--from", "0,0", "--to", "2,1", "--json"], capsys)
    assert code == 0 and data["cost_exact"]["text"] == "1+1*sqrt2"
    code, data = run_json(
        ["path", str(maze), "--from", "0,0", "--to", "2,1", "--connectivity", "4", "--json"],
        capsys,
    )
    assert data["cost"] == 3.0


def test_path_on_a_big_map_prints_no_picture_by_default(
    capsys: pytest.CaptureFixture[str],
) -> None:
    data = Path(__file__).parent / "data" / "movingai" / "maze512-32-9.map"
    assert main(["path", str(data), "--from", "295,95", "--to", "292,96"]) == 0
    out = capsys.readouterr().out
    assert len(out) < 500 and "cost: 3.41421356" in out and "--picture" in out


def test_path_picture_on_a_movingai_map(capsys: pytest.CaptureFixture[str]) -> None:
    data = Path(__file__).parent / "data" / "movingai" / "maze512-32-9.map"
    assert main(["path", str(data), "--from", "295,95", "--to", "292,96", "--picture"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out[0]) == 512
    assert out[95][295] == "S" and out[96][292] == "G"
    assert "o" in out[95][292:296] + out[96][292:296]
    assert any(line.startswith("cost: 3.41421356") for line in out)


def test_path_bad_connectivity_exit_two(
    maze_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert (
        main(["path", str(maze_file), "--from", "0,0", "--to", "4,2", "--connectivity", "6"]) == 2
    )
    assert "--connectivity" in capsys.readouterr().err


DOC = Path(__file__).parent.parent / "docs" / "planner.md"


@pytest.mark.parametrize(("block", "weight"), [("plan_room_w0", "0"), ("plan_room_w1", "1")])
def test_docs_plan_examples_match_the_cli(
    block: str, weight: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = DOC.read_text(encoding="utf-8")
    room = re.search(r"`room.txt`:\n\n```text\n(.*?)```", text, re.S)
    shown = re.search(
        rf"<!-- BEGIN generated: {block} -->\n```text\n\$ (.*?)\n(.*?)```\n<!-- END", text, re.S
    )
    assert room is not None and shown is not None
    maze = tmp_path / "room.txt"
    maze.write_text(room.group(1), encoding="utf-8")
    command = shown.group(1).split()
    assert command[:3] == ["selfrepair", "plan", "room.txt"]
    assert ("--clearance-weight" in command) == (weight != "0")
    assert main(["plan", str(maze), *command[3:]]) == 0
    out = capsys.readouterr().out
    assert out.rsplit("expansions:", 1)[0] == shown.group(2)


def test_plan_and_path_accept_bundled_maze_names(capsys: pytest.CaptureFixture[str]) -> None:
    code, data = run_json(
        ["plan", "narrow-short", "--start", "1,1,E", "--goal", "3,1", "--json"], capsys
    )
    assert code == 0 and data["status"] == "solved" and data["poses"][-1][:2] == [3, 1]
    code, data = run_json(
        ["path", "narrow-short", "--from", "1,1", "--to", "3,1", "--json"], capsys
    )
    assert code == 0 and data["cost"] == 2


def test_warm_up_loads_the_families_asked_for_once(monkeypatch: pytest.MonkeyPatch) -> None:
    from selfrepair.errors import ProblemError
    from selfrepair.search import warmup

    with pytest.raises(ProblemError, match="unknown kernel family 'gpu'"):
        warmup.warm_up("gpu")
    loaded: list[tuple[str, ...]] = []
    monkeypatch.setattr(warmup, "_WARM", set())
    monkeypatch.setattr(warmup, "warm_up", lambda *kinds: loaded.append(kinds) or 7)
    assert warmup.ensure_warm("grid") == 7 and warmup.ensure_warm("grid") == 0
    assert warmup.ensure_warm() == 7 and warmup.ensure_warm("lattice", "grid") == 0
    assert loaded == [("grid",), ("lattice",)]
