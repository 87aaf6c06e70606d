"""Several writers on one results database: created once, work shared, a killed writer's work
taken over; a killed driver takes its workers with it; Ctrl-C is one line and exit 130."""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from selfrepair.experiment.config import parse_config
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.missions import expand
from selfrepair.experiment.store import ResultStore, without_timings

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="uses signals and /proc")

CONFIG = """\
name = "writers"
seed = 3
[[mazes]]
bundled = "narrow-short"
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
recursion = ["flat"]
"""

HERE = Path(__file__).parent


def _missions() -> tuple[Mission, ...]:
    return expand(parse_config(CONFIG))


def slow_fake_mission(mission: Mission) -> dict[str, int | float | str | None]:
    """A stand-in for the executor that takes 20 ms and logs each mission it runs (one line per
    run, appended to the file named by $WRITER_LOG)."""
    time.sleep(0.02)
    with open(os.environ["WRITER_LOG"], "a", encoding="ascii") as log:
        log.write(mission.key + "\n")
    return {"ticks": mission.seed % 101, "reached": 1, "note": mission.settings["strategy"]}


def writer_main(db: str, go: str, jobs: int) -> None:
    """One writer process: wait for the go file, open the store, run every mission."""
    from selfrepair.experiment.runner import run_missions

    missions = _missions()
    Path(go).with_name(f"ready-{os.getpid()}").touch()
    while not Path(go).exists():
        time.sleep(0.001)
    with ResultStore(db) as store:
        summary = run_missions(missions, store, jobs=jobs, execute=slow_fake_mission)
    print(summary.ran, summary.elsewhere, summary.skipped)


def _writer(tmp_path: Path, name: str, jobs: int = 1, go: str = "go") -> subprocess.Popen[str]:
    """A writer process that starts its sweep once the file ``go`` exists in ``tmp_path``."""
    code = (
        f"import sys; sys.path.insert(0, {str(HERE)!r}); import test_experiment_writers as t; "
        f"t.writer_main({str(tmp_path / 'r.sqlite')!r}, {str(tmp_path / go)!r}, {jobs})"
    )
    env = {**os.environ, "WRITER_LOG": str(tmp_path / f"{name}.log")}
    return subprocess.Popen(
        [sys.executable, "-c", code],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )


def _wait_until_imported(tmp_path: Path, writers: int) -> None:
    deadline = time.monotonic() + 120
    while len(list(tmp_path.glob("ready-*"))) < writers:
        assert time.monotonic() < deadline, "the writers did not start"
        time.sleep(0.01)


def _wait_for_log(tmp_path: Path, name: str, lines: int, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 120
    while len(_log(tmp_path, name)) < lines:
        assert proc.poll() is None, f"writer {name} ended early"
        assert time.monotonic() < deadline, f"writer {name} ran nothing"
        time.sleep(0.01)


def _log(tmp_path: Path, name: str) -> list[str]:
    path = tmp_path / f"{name}.log"
    return path.read_text().split() if path.exists() else []


def _stored(db: Path) -> dict[str, dict[str, object]]:
    with ResultStore(db, read_only=True) as store:
        return {str(r["key"]): without_timings(r) for r in store.rows()}


def _finish(proc: subprocess.Popen[str]) -> tuple[int, int, int]:
    out, err = proc.communicate(timeout=240)
    assert proc.returncode == 0, err
    ran, elsewhere, skipped = (int(n) for n in out.split())
    return ran, elsewhere, skipped


@pytest.mark.parametrize("delay", [0.0, 0.5])
def test_two_writers_on_a_new_database_share_the_work(tmp_path: Path, delay: float) -> None:
    """Started together (or the second 0.5 s later) on a database that does not exist yet: both
    succeed, every mission is stored once, and no mission is run by both."""
    total = len(_missions())
    one = _writer(tmp_path, "one", go="go-one")
    two = _writer(tmp_path, "two", go="go-two")
    _wait_until_imported(tmp_path, 2)
    (tmp_path / "go-one").touch()
    time.sleep(delay)
    (tmp_path / "go-two").touch()
    (ran1, elsewhere1, skipped1), (ran2, elsewhere2, skipped2) = _finish(one), _finish(two)
    assert ran1 + ran2 == total
    assert ran1 + elsewhere1 + skipped1 == total and ran2 + elsewhere2 + skipped2 == total
    log1, log2 = _log(tmp_path, "one"), _log(tmp_path, "two")
    assert log1 and log2, "both writers took part"
    assert not set(log1) & set(log2), "a mission was run by both writers"
    assert len(log1) == len(set(log1)) and len(log2) == len(set(log2))
    rows = _stored(tmp_path / "r.sqlite")
    assert set(rows) == {m.key for m in _missions()}
    with sqlite3.connect(tmp_path / "r.sqlite") as con:
        assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0
        assert con.execute("SELECT COUNT(*) FROM writers").fetchone()[0] == 0


def test_sigkill_of_one_writer_the_other_finishes(tmp_path: Path) -> None:
    """One of two writers is killed mid-run: the other takes over its claims; nothing is lost,
    nothing is stored twice, and the rows stored before the kill are unchanged."""
    db = tmp_path / "r.sqlite"
    victim = _writer(tmp_path, "victim", jobs=2, go="go-victim")
    other = _writer(tmp_path, "other", go="go-other")
    _wait_until_imported(tmp_path, 2)
    (tmp_path / "go-victim").touch()
    _wait_for_log(tmp_path, "victim", 10, victim)  # its workers are up
    (tmp_path / "go-other").touch()
    _wait_for_log(tmp_path, "other", 10, other)
    assert victim.poll() is None, "the victim ended before it could be killed"
    os.killpg(victim.pid, signal.SIGKILL)
    victim.wait()
    before = _stored(db)
    _finish(other)
    after = _stored(db)
    assert set(after) == {m.key for m in _missions()}
    assert all(after[k] == v for k, v in before.items())
    with sqlite3.connect(db) as con:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
        assert con.execute("SELECT COUNT(*), COUNT(DISTINCT key) FROM missions").fetchone() == (
            len(after),
            len(after),
        )
        assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0
    # missions run twice are at most those the victim had in flight when it died
    twice = set(_log(tmp_path, "victim")) & set(_log(tmp_path, "other"))
    assert len(twice) <= 2 * 256


# --- the command line --------------------------------------------------------------------------


def _experiment(config: Path, db: Path, jobs: int) -> subprocess.Popen[bytes]:
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
            str(jobs),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=_default_sigint,
    )


def _default_sigint() -> None:
    """In the child: Ctrl-C as in a terminal, also when this test runs in a background job
    (where the shell ignores SIGINT, and a Python started with it ignored keeps ignoring it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _count(db: Path) -> int:
    try:
        with sqlite3.connect(db, timeout=5) as con:
            return int(con.execute("SELECT COUNT(*) FROM missions").fetchone()[0])
    except sqlite3.OperationalError:
        return 0


def _wait_for_rows(proc: subprocess.Popen[bytes], db: Path, rows: int) -> None:
    deadline = time.monotonic() + 120
    while _count(db) < rows:
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
        assert time.monotonic() < deadline, "no rows appeared"
        time.sleep(0.01)


def _descendants(pid: int) -> list[int]:
    found: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        for child in (task / "children").read_text().split():
            found += [int(child), *_descendants(int(child))]
    return found


def _living(pids: list[int]) -> list[int]:
    """The pids that still run (a zombie waiting for its new parent to reap it has ended)."""
    alive = []
    for pid in pids:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if state not in ("Z", "X"):
            alive.append(pid)
    return alive


def test_two_experiment_commands_on_a_new_db_both_succeed(tmp_path: Path) -> None:
    config = tmp_path / "writers.toml"
    config.write_text(CONFIG)
    db = tmp_path / "new.sqlite"
    procs = [_experiment(config, db, 1), _experiment(config, db, 1)]
    outs = [p.communicate(timeout=300) for p in procs]
    for proc, (_out, err) in zip(procs, outs, strict=True):
        assert proc.returncode == 0, err.decode()
        assert b"Traceback" not in err
    assert _count(db) == len(_missions())


def test_killed_driver_takes_its_workers_with_it(tmp_path: Path) -> None:
    config = tmp_path / "writers.toml"
    config.write_text(CONFIG)
    db = tmp_path / "r.sqlite"
    proc = _experiment(config, db, 2)
    try:
        _wait_for_rows(proc, db, 5)
        children = _descendants(proc.pid)
        assert children, "no worker processes found"
        os.kill(proc.pid, signal.SIGKILL)  # the driver alone
        proc.wait(timeout=30)
        deadline = time.monotonic() + 10
        while _living(children) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert _living(children) == [], "processes outlived their driver"
    finally:
        for pid in _living(_descendants(proc.pid) if proc.poll() is None else []):
            os.kill(pid, signal.SIGKILL)
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)


@pytest.mark.parametrize("jobs", [1, 2])
def test_ctrl_c_is_one_line_exit_130_and_resumes(tmp_path: Path, jobs: int) -> None:
    config = tmp_path / "writers.toml"
    config.write_text(CONFIG)
    db = tmp_path / "r.sqlite"
    proc = _experiment(config, db, jobs)
    try:
        _wait_for_rows(proc, db, 5)
        children = _descendants(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal sends it: to driver and workers
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    stored = _count(db)
    total = len(_missions())
    assert proc.returncode == 130, err.decode()
    lines = err.decode().splitlines()
    assert len(lines) == 1, lines
    assert lines[0] == (
        f"selfrepair: interrupted: {stored} of {total} missions are stored in {db}; "
        "run the same command again to resume"
    )
    assert 5 <= stored < total
    deadline = time.monotonic() + 10
    while _living(children) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _living(children) == []
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM claims").fetchone()[0] == 0
    again = _experiment(config, db, jobs)
    out, err2 = again.communicate(timeout=300)
    assert again.returncode == 0, err2.decode()
    assert f"{total} missions, {stored} already stored, {total - stored} run".encode() in out
