"""``check-scen``: grid A* against MovingAI optimal lengths, sampling, mismatches, exit codes."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from selfrepair.cli import main
from selfrepair.search.backend import numba_available
from selfrepair.search.scenarios import check_scenarios, sample_indices

DATA = Path(__file__).parent / "data" / "movingai"
MAPS = ["maze512-1-0", "maze512-4-0", "maze512-32-9"]
SAMPLE = 25 if numba_available() else 3


@pytest.mark.parametrize("name", MAPS)
def test_sampled_lines_match_the_listed_optimum(name: str) -> None:
    report = check_scenarios(DATA / f"{name}.map.scen", sample=SAMPLE, seed=1)
    assert report.lines > 8000 and len(report.checks) == SAMPLE
    assert report.mismatches == ()
    assert max(c.expected for c in report.checks) > 500  # the sample reaches the long queries


def test_cli_check_scen_exit_zero_and_summary(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["check-scen", str(DATA / "maze512-32-9.map.scen"), "--sample", "5"])
    out = capsys.readouterr().out
    assert code == 0
    assert "checked 5 of 8010 lines" in out and "0 mismatches" in out


def write_scen(tmp_path: Path, lines: list[str]) -> Path:
    shutil.copy(DATA / "maze512-32-9.map", tmp_path / "maze512-32-9.map")
    scen = tmp_path / "small.map.scen"
    scen.write_text("version 1\n" + "".join(line + "\n" for line in lines), encoding="utf-8")
    return scen


GOOD = "0\tmaze512-32-9.map\t512\t512\t295\t95\t292\t96\t3.41421356"
BAD = "0\tmaps/mazes/maze512-32-9.map\t512\t512\t295\t95\t292\t96\t3.50000000"


def test_mismatch_gives_exit_one_and_names_the_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scen = write_scen(tmp_path, [GOOD, BAD])
    code = main(["check-scen", str(scen)])
    out = capsys.readouterr().out
    assert code == 1
    assert f"{scen}:3:" in out and "expected 3.5" in out
    assert "1 mismatches" in out


def test_json_output_lists_mismatches(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scen = write_scen(tmp_path, [GOOD, BAD, GOOD])
    assert main(["check-scen", str(scen), "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["lines"] == 3 and data["checked"] == 3 and data["tolerance"] == 0.01
    assert [m["line"] for m in data["mismatches"]] == [3]
    assert data["mismatches"][0]["got"] == pytest.approx(2 + 2**0.5)


def test_tolerance_is_absolute_001(tmp_path: Path) -> None:
    near = GOOD.replace("3.41421356", "3.42")  # off by 0.0058: within 0.01
    far = GOOD.replace("3.41421356", "3.43")  # off by 0.0158
    report = check_scenarios(write_scen(tmp_path, [near, far]))
    assert [c.ok for c in report.checks] == [True, False]


def test_missing_map_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scen = tmp_path / "lonely.map.scen"
    scen.write_text("version 1\n" + GOOD + "\n", encoding="utf-8")
    assert main(["check-scen", str(scen)]) == 2
    err = capsys.readouterr().err
    assert "maze512-32-9.map" in err and "lonely.map.scen:2" in err


def test_sample_indices_are_spread_evenly_and_seeded() -> None:
    picks = sample_indices(1000, 10, seed=3)
    assert len(picks) == 10
    assert all(100 * i <= p < 100 * (i + 1) for i, p in enumerate(picks))
    assert picks == sample_indices(1000, 10, seed=3)
    assert picks != sample_indices(1000, 10, seed=4)
    assert sample_indices(5, 10, seed=0) == [0, 1, 2, 3, 4]
    assert sample_indices(5, None, seed=0) == [0, 1, 2, 3, 4]


@pytest.mark.slow
@pytest.mark.parametrize("name", MAPS)
def test_full_scenario_file_matches(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check-scen", str(DATA / f"{name}.map.scen")]) == 0
    assert " 0 mismatches" in capsys.readouterr().out


def _strict_json(text: str) -> dict:
    def refuse(constant: str) -> float:
        raise AssertionError(f"invalid JSON constant {constant}")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize("length", ["nan", "inf", "-inf", "-3.41421356", "1e400"])
def test_non_finite_or_negative_optimal_length_is_bad_input_not_a_mismatch(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], length: str
) -> None:
    # These used to count as mismatches (exit 1), and --json printed NaN, which is not JSON.
    scen = write_scen(tmp_path, [GOOD, GOOD.replace("3.41421356", length)])
    assert main(["check-scen", str(scen), "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    column = GOOD.rindex("\t") + 2
    assert captured.err == (
        f"selfrepair: error: {scen}:3:{column}: expected a finite non-negative number "
        f"optimal_length, got {length!r}\n"
    )


def test_json_output_is_strict_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scen = write_scen(tmp_path, [GOOD, BAD])
    assert main(["check-scen", str(scen), "--json"]) == 1
    data = _strict_json(capsys.readouterr().out)
    assert data["checked"] == 2 and len(data["mismatches"]) == 1


def test_map_over_the_cell_limit_is_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scen = write_scen(tmp_path, [GOOD])
    assert main(["check-scen", str(scen), "--max-cells", "100000"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--max-cells" in err and "262,144" in err
    assert main(["check-scen", str(scen), "--max-cells", "262144"]) == 0
