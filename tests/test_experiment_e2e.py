"""End to end with the real executor: CLI runs, crash and resume, determinism, exports, report."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from extras import need
from selfrepair.cli import main
from selfrepair.experiment.config import load_config
from selfrepair.experiment.missions import expand
from selfrepair.experiment.store import ResultStore, without_timings

TINY = """\
name = "tiny"
seed = 5
[[mazes]]
bundled = "narrow-short"
[faults]
sets = ["FL:F", "FR:B,RR:B"]
[planner]
clearance_weights = [0, 1]
[[strategies]]
name = "replan"
[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
[[strategies]]
name = "lookahead"
tables = ["handwritten"]
recursion = ["flat"]
window = [2]
"""

# Enough missions that a sweep is still running when the test kills it.
LARGER = """\
name = "larger"
seed = 9
[[mazes]]
bundled = "narrow-long"
[faults]
sets = "paper"
[planner]
clearance_weights = [0, 1]
[[strategies]]
name = "replan"
[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat", "guarded"]
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def _comparable(db: Path) -> dict[str, dict[str, object]]:
    with ResultStore(db) as store:
        return {str(r["key"]): without_timings(r) for r in store.rows()}


def test_tiny_experiment_rows_exports_and_determinism(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = _write(tmp_path, "tiny", TINY)
    expected = expand(load_config(config))
    assert len(expected) == 4 * 2 * 3 * 2
    db = tmp_path / "a.sqlite"
    args = ["experiment", str(config), "--db", str(db), "--jobs", "1"]
    assert main([*args, "--export-csv", str(tmp_path / "a.csv")]) == 0
    out = capsys.readouterr().out
    assert f"{len(expected)} missions, 0 already stored, {len(expected)} run" in out
    assert "replacement[handwritten,flat]" in out and "lookahead[handwritten,flat,k=2]" in out
    assert out.count("Finding ") == 5
    rows = _comparable(db)
    assert set(rows) == {m.key for m in expected}
    assert all(r["reached"] in (0, 1) and r["status"] for r in rows.values())
    assert any(int(r["replacements"] or 0) > 0 for r in rows.values())  # type: ignore[call-overload]
    assert (tmp_path / "a.csv").read_text().count("\n") == len(expected) + 1
    # run again: everything is skipped
    assert main(args) == 0
    assert f"{len(expected)} already stored, 0 run" in capsys.readouterr().out
    # same seed, fresh database, worker processes: identical rows except wall-clock timings
    db2 = tmp_path / "b.sqlite"
    assert main(["experiment", str(config), "--db", str(db2), "--jobs", "2"]) == 0
    assert _comparable(db2) == rows
    # another seed: other keys, other seeds
    _write(tmp_path, "tiny", TINY.replace("seed = 5", "seed = 6"))
    db3 = tmp_path / "c.sqlite"
    assert main(["experiment", str(config), "--db", str(db3), "--jobs", "1"]) == 0
    assert not set(_comparable(db3)) & set(rows)


def test_experiment_exports_parquet(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pq = need("pyarrow.parquet", "parquet")
    config = _write(tmp_path, "tiny", TINY)
    db, out = tmp_path / "a.sqlite", tmp_path / "a.parquet"
    args = ["experiment", str(config), "--db", str(db), "--export-parquet", str(out)]
    assert main(args) == 0
    assert pq.read_table(out).num_rows == len(expand(load_config(config)))


def _count(db: Path) -> int:
    try:
        with sqlite3.connect(db, timeout=5) as con:
            return int(con.execute("SELECT COUNT(*) FROM missions").fetchone()[0])
    except sqlite3.OperationalError:
        return 0


def _start(config: Path, db: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [
            sys.executable,
            "-c",
            "from selfrepair.cli import run; run()",
            "experiment",
            str(config),
            "--db",
            str(db),
            "--jobs",
            "2",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )


def _wait_for_rows(proc: subprocess.Popen[bytes], db: Path, rows: int) -> None:
    deadline = time.monotonic() + 120
    while _count(db) < rows:
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
        assert time.monotonic() < deadline, "no rows appeared"
        time.sleep(0.01)


def _children(pid: int) -> list[int]:
    path = Path(f"/proc/{pid}/task/{pid}/children")
    return [int(p) for p in path.read_text().split()] if path.exists() else []


def _check_resumed(config: Path, db: Path, before: dict[str, dict[str, object]]) -> None:
    with sqlite3.connect(db) as con:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "2"]) == 0
    after = _comparable(db)
    expected = {m.key for m in expand(load_config(config))}
    assert set(after) == expected  # nothing lost, nothing extra
    with sqlite3.connect(db) as con:  # no duplicate and no half row
        assert con.execute("SELECT COUNT(*) FROM missions").fetchone()[0] == len(expected)
        assert con.execute("SELECT COUNT(*) FROM missions WHERE status IS NULL").fetchone()[0] == 0
    assert all(after[k] == v for k, v in before.items())  # rows stored before the kill unchanged


@pytest.mark.skipif(sys.platform != "linux", reason="uses process groups and /proc")
def test_sigkill_mid_run_then_resume(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = _write(tmp_path, "larger", LARGER)
    total = len(expand(load_config(config)))
    db = tmp_path / "r.sqlite"
    proc = _start(config, db)
    try:
        _wait_for_rows(proc, db, 20)
        os.killpg(proc.pid, signal.SIGKILL)  # the driver and its workers, at once
    finally:
        proc.wait(timeout=30)
    before = _comparable(db)
    assert 20 <= len(before) < total, "the sweep was not killed mid-run"
    _check_resumed(config, db, before)
    assert f"{len(before)} already stored" in capsys.readouterr().out


@pytest.mark.skipif(sys.platform != "linux", reason="uses /proc to find worker processes")
def test_killed_worker_then_resume(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = _write(tmp_path, "larger", LARGER)
    db = tmp_path / "r.sqlite"
    proc = _start(config, db)
    try:
        _wait_for_rows(proc, db, 10)
        workers = [  # forked from the driver on Linux (loky's elsewhere): its children
            p
            for p in _children(proc.pid)
            if b"resource_tracker" not in Path(f"/proc/{p}/cmdline").read_bytes()
        ]
        assert workers, "no worker process found"
        os.kill(workers[0], signal.SIGKILL)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    before = _comparable(db)
    # the sweep noticed the dead worker and stopped with one line, keeping what it had stored
    assert proc.returncode == 2, err
    assert b"a worker process died" in err and b"run the same command again" in err
    assert err.count(b"\n") == 1, err
    assert 10 <= len(before) < len(expand(load_config(config)))
    _check_resumed(config, db, before)


def test_report_and_animate(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    need("matplotlib", "viz")
    config = _write(tmp_path, "tiny", TINY)
    db = tmp_path / "r.sqlite"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    out_dir = tmp_path / "report"
    assert main(["report", str(db), "-o", str(out_dir)]) == 0
    names = {
        "report.md",
        "latency.png",
        "latency-vs-size.png",
        "clearance.png",
        "heatmap.png",
        "mission.png",
        "mission.gif",
        "mission.jsonl",
    }
    assert {p.name for p in out_dir.iterdir()} >= names
    for name in names:
        assert (out_dir / name).stat().st_size > 500, name
    for name in names - {"report.md", "mission.jsonl"}:
        head = (out_dir / name).read_bytes()[:6]
        assert head in (b"\x89PNG\r\n", b"GIF89a"), name
    report = (out_dir / "report.md").read_text()
    assert "| replan |" in report and "![One mission](mission.png)" in report
    outcomes = [
        f"**Finding {n}: {o}.**"
        for n in ("1", "1b", "2", "3", "4")
        for o in ("HELD", "NOT HELD", "INCONCLUSIVE")
    ]
    assert sum(report.count(o) for o in outcomes) == 3
    # one table, one recursion mode: findings 3 and 4 do not apply, one line each
    assert report.count("*Finding 3 left out: ") == 1 and report.count("*Finding 4 left out: ") == 1
    # the drawn mission's trace replays, and animate works on it from the CLI
    assert main(["replay", str(out_dir / "mission.jsonl")]) == 0
    gif = tmp_path / "again.gif"
    assert (
        main(["animate", str(out_dir / "mission.jsonl"), "-o", str(gif), "--max-frames", "5"]) == 0
    )
    assert gif.read_bytes()[:6] == b"GIF89a"
    capsys.readouterr()
    assert main(["animate", str(out_dir / "mission.jsonl"), "-o", str(tmp_path / "x.png")]) == 2
    assert ".gif" in capsys.readouterr().err
    assert main(["report", str(tmp_path / "missing.sqlite"), "-o", str(out_dir)]) == 2
    # a trace the robot model does not back is refused, not drawn
    lines = (out_dir / "mission.jsonl").read_text().splitlines()
    step = json.loads(lines[1])
    step["to"] = [999, 8, "S"]
    bad = tmp_path / "bad.jsonl"
    bad.write_text("\n".join([lines[0], json.dumps(step), *lines[2:]]) + "\n")
    capsys.readouterr()
    assert main(["animate", str(bad), "-o", str(tmp_path / "bad.gif")]) == 2
    assert "does not replay" in capsys.readouterr().err
    # a report reads its database and never changes it; a foreign database is refused
    before = db.read_bytes()
    assert main(["report", str(db), "-o", str(tmp_path / "again")]) == 0
    assert db.read_bytes() == before
    other = tmp_path / "other.sqlite"
    sqlite3.connect(other).execute("CREATE TABLE foo (x)").connection.commit()
    assert main(["report", str(other), "-o", str(tmp_path / "o")]) == 2
    assert "'missions' table" in capsys.readouterr().err
    with sqlite3.connect(other) as con:
        assert {r[0] for r in con.execute("SELECT name FROM sqlite_master")} == {"foo"}
    # output paths that cannot be written are one line and exit 2
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["report", str(db), "-o", str(blocker / "out")]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.parametrize("width", [80, 100, 160])
def test_terminal_summary_never_truncates_a_number(
    width: int, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from selfrepair.cli.experiments import print_summary
    from selfrepair.experiment.findings import StrategySummary

    monkeypatch.setenv("COLUMNS", str(width))
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)
    from selfrepair.stats import Interval

    summary = StrategySummary(
        label="replacement[generated-agnostic,guarded] w=1/3",
        missions=192,
        completed=192,
        met_fault=148,
        no_replan=79,
        resolved_locally=0.993,
        replans_per_mission=0.77,
        over_optimum=Interval(20.14, 17.5, 23.25, 192),
        plan_distance_mean=104.0,
        plan_distance_motion_mean=55.5,
        repair_compute_us=Interval(12345.6, 10000.2, 98765.4, 148),
        cold_first_repair_us=Interval(184.0, 51.0, 1234.0, 148),
        warm_first_repair_us=Interval(16.0, 5.0, 18.0, 148),
        latency_median_us=4321.0,
        latency_p99_us=123456.7,
    )
    print_summary([summary], title="t")
    out = capsys.readouterr().out
    assert "…" not in out
    for cell in summary.cells()[1:]:
        assert cell in out, cell


def _long_summary(label: str) -> object:
    from selfrepair.experiment.findings import StrategySummary
    from selfrepair.stats import Interval

    return StrategySummary(
        label=label,
        missions=192,
        completed=192,
        met_fault=148,
        no_replan=79,
        resolved_locally=0.993,
        replans_per_mission=0.77,
        over_optimum=Interval(20.14, 17.5, 23.25, 192),
        plan_distance_mean=104.0,
        plan_distance_motion_mean=55.5,
        repair_compute_us=Interval(12345.6, 10000.2, 98765.4, 148),
        cold_first_repair_us=Interval(184.0, 51.0, 1234.0, 148),
        warm_first_repair_us=Interval(16.0, 5.0, 18.0, 148),
        latency_median_us=4321.0,
        latency_p99_us=123456.7,
    )


@pytest.mark.parametrize("columns", ["80", "200"])
def test_piped_summary_is_never_cut(
    columns: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """Not a terminal (a log, a pipe): full headers and names, whatever COLUMNS says."""
    from selfrepair.cli.experiments import print_summary
    from selfrepair.experiment.findings import StrategySummary

    monkeypatch.setenv("COLUMNS", columns)
    labels = [f"lookahead[generated-agnostic-variant-{i},guarded,k=12] w=1/3" for i in range(12)]
    summaries = [_long_summary(label) for label in labels]
    print_summary(summaries, title="a long experiment name: per strategy")  # type: ignore[arg-type]
    out = capsys.readouterr().out
    assert "…" not in out
    for header in StrategySummary.HEADERS:
        assert header in out, header
    for label in labels:
        assert label in out


def test_findings_are_wrapped(capsys: pytest.CaptureFixture[str]) -> None:
    from selfrepair.cli.experiments import print_findings
    from selfrepair.experiment.findings import Finding, Outcome

    items = tuple(f"variant {i} resolved 99.{i}% of 1234 encounters" for i in range(20))
    finding = Finding("1", "a claim of the original study", Outcome.HELD, ("Intro.", *items))
    print_findings([finding])
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("Finding 1: HELD.")
    assert all(len(line) <= 100 for line in lines)
