"""Every limit flag: a value below the input's size refuses it with one stderr line naming the
limit and the flag (exit 2), and a value that fits lets the same command run."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from selfrepair.cli import main
from selfrepair.limits import (
    MAX_CELLS,
    MAX_LOOKUP_PATTERNS,
    MAX_MISSIONS,
    MAX_TABLE_BYTES,
    MAX_TABLE_CANDIDATES,
)
from selfrepair.tables.fileformat import bundled_table, dump_table
from selfrepair.world.bundled import load_bundled
from selfrepair.world.maze import save_maze

ROUTE = ["--start", "1,1,E", "--goal", "13,13"]


@pytest.fixture
def files(tmp_path: Path) -> dict[str, str]:
    maze = tmp_path / "m.maze"
    save_maze(load_bundled("narrow-short"), maze)  # 15 x 15 = 225 cells
    table = tmp_path / "t.json"
    table.write_text(dump_table(bundled_table("handwritten")), encoding="utf-8")
    experiment = tmp_path / "e.toml"
    experiment.write_text(
        'name = "e"\n[[mazes]]\nfile = "m.maze"\nroutes = 2\n[faults]\nsets = ["FL:F"]\n'
        '[[strategies]]\nname = "replan"\n',
        encoding="utf-8",
    )
    return {"maze": str(maze), "table": str(table), "toml": str(experiment), "db": str(tmp_path)}


def _table_size(files: dict[str, str]) -> int:
    return Path(files["table"]).stat().st_size


def _candidates() -> int:
    return sum(len(e.candidates) for e in bundled_table("handwritten").entries)


# (flag, value that refuses, value that fits, command)
CASES = [
    ("--max-cells", "224", "225", lambda f: ["maze", "show", f["maze"]]),
    ("--max-cells", "224", "225", lambda f: ["maze", "generate", "--width", "15", "--height",
                                              "15", "--seed", "1"]),
    ("--max-cells", "224", "225", lambda f: ["plan", f["maze"], *ROUTE]),
    ("--max-cells", "224", "225", lambda f: ["path", f["maze"], "--from", "1,1", "--to", "13,13"]),
    ("--max-cells", "224", "225", lambda f: ["run", f["maze"], *ROUTE, "--strategy", "replan"]),
    ("--max-cells", "224", "225", lambda f: ["table", "coverage", "handwritten", "--faults",
                                              "singles", "--maze", f["maze"]]),
    ("--max-cells", "224", "225", lambda f: ["experiment", f["toml"], "--jobs", "1", "--db",
                                              f["db"] + "/a.sqlite"]),
    ("--max-missions", "1", "2", lambda f: ["experiment", f["toml"], "--jobs", "1", "--db",
                                             f["db"] + "/b.sqlite"]),
    ("--max-table-bytes", "1000", "table", lambda f: ["table", "show", f["table"]]),
    ("--max-table-bytes", "1000", "table", lambda f: ["table", "check", f["table"]]),
    ("--max-table-bytes", "1000", "table", lambda f: ["table", "coverage", f["table"],
                                                       "--faults", "singles", "--no-walls"]),
    ("--max-table-bytes", "1000", "table", lambda f: ["run", "narrow-short", *ROUTE,
                                                       "--table", f["table"]]),
    ("--max-table-candidates", "10", "candidates", lambda f: ["table", "show", f["table"]]),
    ("--max-table-candidates", "10", "candidates", lambda f: ["table", "check", f["table"]]),
    ("--max-table-candidates", "10", "candidates", lambda f: ["table", "coverage", f["table"],
                                                               "--faults", "singles",
                                                               "--no-walls"]),
    ("--max-table-candidates", "10", "candidates", lambda f: ["run", "narrow-short", *ROUTE,
                                                               "--table", f["table"]]),
]


@pytest.mark.parametrize(("flag", "low", "fits", "command"), CASES)
def test_limit_flag_refuses_then_admits(
    files: dict[str, str],
    capsys: pytest.CaptureFixture[str],
    flag: str,
    low: str,
    fits: str,
    command,  # type: ignore[no-untyped-def]
) -> None:
    args = command(files)
    assert main([*args, flag, low]) == 2
    err = capsys.readouterr().err
    assert err.startswith("selfrepair: error: ") and err.count("\n") == 1, err
    assert f"limit {flag[2:].replace('-', '_')}; raise it with {flag})" in err
    fits = {"table": str(_table_size(files)), "candidates": str(_candidates())}.get(fits, fits)
    assert main([*args, flag, fits]) in (0, 1)  # 1: a table check may list gaps
    capsys.readouterr()


def test_defaults_are_the_documented_constants() -> None:
    assert (
        MAX_CELLS,
        MAX_MISSIONS,
        MAX_TABLE_BYTES,
        MAX_TABLE_CANDIDATES,
        MAX_LOOKUP_PATTERNS,
    ) == (4_194_304, 1_000_000, 67_108_864, 1_000_000, 4096)
    doc = (Path(__file__).parent.parent / "docs" / "reliability.md").read_text(encoding="utf-8")
    for name, default in (
        ("max_cells", "4,194,304"),
        ("max_missions", "1,000,000"),
        ("max_table_bytes", "67,108,864"),
        ("max_table_candidates", "1,000,000"),
        ("max_lookup_patterns", "4,096"),
    ):
        flag = "--" + name.replace("_", "-")
        assert f"| `{name}` | `{flag}` | {default} |" in doc


@pytest.mark.parametrize(
    ("flag", "low", "fits", "command"),
    [
        ("--max-cells", "224", "225", lambda f: ["maze", "routes", f["maze"], "-n", "1"]),
        ("--max-cells", "224", "225", lambda f: ["compare", f["maze"], *ROUTE, "--strategies",
                                                  "replan", "--no-warm-up"]),
        ("--max-table-bytes", "1000", "table", lambda f: ["compare", "narrow-short", *ROUTE,
                                                           "--table", f["table"],
                                                           "--strategies", "replacement"]),
        ("--max-table-candidates", "10", "candidates", lambda f: ["compare", "narrow-short",
                                                                   *ROUTE, "--table", f["table"],
                                                                   "--strategies",
                                                                   "replacement"]),
    ],
)
def test_limit_flags_of_the_newer_commands(
    files: dict[str, str],
    capsys: pytest.CaptureFixture[str],
    flag: str,
    low: str,
    fits: str,
    command,  # type: ignore[no-untyped-def]
) -> None:
    test_limit_flag_refuses_then_admits(files, capsys, flag, low, fits, command)


@pytest.fixture
def text_files(files: dict[str, str], tmp_path: Path) -> dict[str, str]:
    """Inputs guarded by byte limits: a route file, a MovingAI scenario with its map, a team
    scenario, a mission trace and a team trace."""
    data = Path(__file__).parent / "data" / "movingai"
    for name in ("maze512-1-0.map", "maze512-1-0.map.scen"):
        shutil.copy(data / name, tmp_path / name)
    package = Path(__file__).parents[1] / "src" / "selfrepair" / "data"
    shutil.copy(package / "team" / "three-robots.toml", tmp_path / "team.toml")
    routes = Path(files["maze"]).with_suffix(".routes")
    assert main(["maze", "routes", files["maze"], "-n", "2", "--seed", "0", "-o", str(routes)]) == 0
    trace = tmp_path / "t.jsonl"
    assert main(["run", "narrow-short", *ROUTE, "--faults", "FL:F", "--strategy", "replan",
                 "--no-warm-up", "--trace", str(trace)]) == 0
    team_trace = tmp_path / "team.jsonl"
    assert main(["team", "run", "three-robots", "--trace", str(team_trace)]) == 0
    return {
        **files,
        "routes": str(routes),
        "scen": str(tmp_path / "maze512-1-0.map.scen"),
        "team": str(tmp_path / "team.toml"),
        "trace": str(trace),
        "team_trace": str(team_trace),
        "out": str(tmp_path),
    }


# (flag, file whose size is the limit that fits, command)
BYTE_CASES = [
    ("--max-file-bytes", "routes", lambda f: ["maze", "show", f["maze"], "--routes"]),
    ("--max-file-bytes", "scen", lambda f: ["check-scen", f["scen"], "--sample", "1"]),
    ("--max-file-bytes", "toml", lambda f: ["experiment", f["toml"], "--jobs", "1", "--db",
                                             f["db"] + "/c.sqlite"]),
    ("--max-file-bytes", "team", lambda f: ["team", "run", f["team"]]),
    ("--max-file-bytes", "team", lambda f: ["team", "compare", f["team"]]),
    ("--max-trace-bytes", "trace", lambda f: ["replay", f["trace"]]),
    ("--max-trace-bytes", "trace", lambda f: ["view", f["trace"], "-o", f["out"] + "/v.html"]),
    ("--max-trace-bytes", "trace", lambda f: ["animate", f["trace"], "-o", f["out"] + "/a.gif",
                                              "--max-frames", "2"]),
    ("--max-trace-bytes", "team_trace", lambda f: ["team", "replay", f["team_trace"]]),
    ("--max-trace-bytes", "team_trace", lambda f: ["team", "frame", f["team_trace"], "-o",
                                                   f["out"] + "/f.png"]),
]


@pytest.mark.parametrize(("flag", "file", "command"), BYTE_CASES)
def test_byte_limit_flags_refuse_then_admit(
    text_files: dict[str, str],
    capsys: pytest.CaptureFixture[str],
    flag: str,
    file: str,
    command,  # type: ignore[no-untyped-def]
) -> None:
    size = Path(text_files[file]).stat().st_size
    args = command(text_files)
    capsys.readouterr()
    assert main([*args, flag, str(size - 1)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("selfrepair: error: ") and err.count("\n") == 1, err
    assert f"at most {size - 1:,} bytes" in err
    assert f"limit {flag[2:].replace('-', '_')}; raise it with {flag})" in err
    assert main([*args, flag, str(size)]) == 0, capsys.readouterr().err
    capsys.readouterr()
