"""Team experiments are as reliable as single-robot sweeps (issue 29, item 21): a sweep killed
with SIGKILL (driver and workers at once) resumes with nothing lost or duplicated and the rows
stored before the kill unchanged, and two writers on one new database both finish with every
row stored once (the store's claims keep them off each other's missions)."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from selfrepair.cli import main
from selfrepair.experiment.store import ResultStore, without_timings
from selfrepair.experiment.teams import TeamExperimentConfig, expand_team, load_experiment

CONFIG = """kind = "team"
name = "team-reliable"
seed = 11
repeats = 2

[[mazes]]
bundled = "wide-short"

[team]
sizes = [2, 3]
tasks_per_robot = [1, 2]

[faults]
cases = ["immobilised", "gripper-carrying", "blocked"]
persistence = ["permanent", "transient"]
duration = 20

[[strategies]]
name = "team-replacement"

[[strategies]]
name = "alone"
"""


def _config(tmp_path: Path) -> tuple[Path, set[str]]:
    path = tmp_path / "team.toml"
    path.write_text(CONFIG, encoding="utf-8")
    config = load_experiment(path)
    assert isinstance(config, TeamExperimentConfig)
    return path, {m.key for m in expand_team(config)}


def _start(config: Path, db: Path, jobs: int) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-c", "from selfrepair.cli import run; run()", "experiment",
         str(config), "--db", str(db), "--jobs", str(jobs)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
    )  # fmt: skip


def _count(db: Path) -> int:
    try:
        with sqlite3.connect(db, timeout=5) as con:
            return int(con.execute("SELECT COUNT(*) FROM missions").fetchone()[0])
    except sqlite3.OperationalError:
        return 0


def _comparable(db: Path) -> dict[str, dict[str, object]]:
    with ResultStore(db) as store:
        return {str(r["key"]): without_timings(r) for r in store.rows()}


@pytest.mark.skipif(sys.platform != "linux", reason="uses process groups")
def test_sigkill_mid_team_sweep_then_resume(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config, keys = _config(tmp_path)
    assert len(keys) == 2 * 2 * 2 * (3 * 2) * 2  # sizes x loads x repeats x faults x strategies
    db = tmp_path / "r.sqlite"
    proc = _start(config, db, 2)
    try:
        deadline = time.monotonic() + 180
        while _count(db) < 10:
            assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
            assert time.monotonic() < deadline, "no rows appeared"
            time.sleep(0.01)
        os.killpg(proc.pid, signal.SIGKILL)  # the driver and its workers, at once
    finally:
        proc.wait(timeout=30)
    before = _comparable(db)
    assert 10 <= len(before) < len(keys), "the sweep was not killed mid-run"
    with sqlite3.connect(db) as con:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "2"]) == 0
    assert f"{len(before)} already stored" in capsys.readouterr().out
    after = _comparable(db)
    assert set(after) == keys  # nothing lost, nothing extra
    with sqlite3.connect(db) as con:  # no duplicate, no half row, no claim left
        assert con.execute("SELECT COUNT(*) FROM missions").fetchone()[0] == len(keys)
        assert con.execute("SELECT COUNT(*) FROM missions WHERE status IS NULL").fetchone()[0] == 0
        assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0
    assert all(after[k] == v for k, v in before.items())  # rows stored before the kill unchanged


def test_two_team_writers_on_a_new_db_both_finish(tmp_path: Path) -> None:
    config, keys = _config(tmp_path)
    db = tmp_path / "new.sqlite"
    procs = [_start(config, db, 1), _start(config, db, 1)]
    outs = [p.communicate(timeout=600) for p in procs]
    for proc, (_out, err) in zip(procs, outs, strict=True):
        assert proc.returncode == 0, err.decode()
        assert b"Traceback" not in err
    with sqlite3.connect(db) as con:
        stored = [r[0] for r in con.execute("SELECT key FROM missions")]
    assert sorted(stored) == sorted(keys)  # every row once
    ran = [int(out.decode().split(" run")[0].rsplit(", ", 1)[1]) for out, _ in outs]
    assert sum(ran) >= len(keys), ran  # every mission was run by one of them
