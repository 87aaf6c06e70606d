"""Results store: atomic rows, no duplicates, dynamic metric columns, CSV and Parquet export."""

from __future__ import annotations

import csv
import json
import sqlite3
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from extras import need
from selfrepair.errors import ProblemError
from selfrepair.experiment.config import parse_config
from selfrepair.experiment.missions import expand
from selfrepair.experiment.store import ResultStore

CONFIG = """\
name = "store"
[[mazes]]
bundled = "narrow-short"
[faults]
sets = ["FL:F", "RR:B"]
[[strategies]]
name = "replan"
"""


def _missions():
    return expand(parse_config(CONFIG))


def test_add_is_idempotent_and_keeps_config(tmp_path: Path) -> None:
    missions = _missions()
    with ResultStore(tmp_path / "r.sqlite") as store:
        assert store.add(missions[0], {"ticks": 12, "success": 1}, 0.5)
        assert not store.add(missions[0], {"ticks": 99, "success": 0}, 0.5)
        assert store.count() == 1
        (row,) = store.rows()
        assert row["ticks"] == 12
        assert json.loads(str(row["config"]))["faults"] == dict(missions[0].labels)["faults"]
        assert row["seed"] == missions[0].seed and row["version"]
    # reopened: the row survived and WAL mode is on
    with ResultStore(tmp_path / "r.sqlite") as store:
        assert store.keys() == {missions[0].key}
    mode = sqlite3.connect(tmp_path / "r.sqlite").execute("PRAGMA journal_mode").fetchone()[0]
    assert mode == "wal"


def test_new_metric_columns_appear_and_collisions_are_prefixed(tmp_path: Path) -> None:
    a, b = _missions()[:2]
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.add(a, {"ticks": 1}, 0.1)
        store.add(b, {"ticks": 2, "extra": "x", "strategy": "other"}, 0.1)
        assert {"ticks", "extra", "result_strategy", "strategy"} <= set(store.columns)
        rows = {r["key"]: r for r in store.rows()}
        assert rows[a.key]["extra"] is None and rows[b.key]["extra"] == "x"
        assert rows[b.key]["strategy"] == "replan" and rows[b.key]["result_strategy"] == "other"


def test_bad_metric_value_rolls_back(tmp_path: Path) -> None:
    a = _missions()[0]
    with ResultStore(tmp_path / "r.sqlite") as store:
        with pytest.raises(Exception, match="must be int, float, str or None"):
            store.add(a, {"ticks": [1, 2]}, 0.1)  # type: ignore[dict-item]
        assert store.count() == 0
        assert store.add(a, {"ticks": 3}, 0.1)


def test_export_csv_and_parquet(tmp_path: Path) -> None:
    missions = _missions()
    with ResultStore(tmp_path / "r.sqlite") as store:
        for n, m in enumerate(missions):
            store.add(m, {"ticks": n, "latency": n / 3, "note": None if n else "first"}, 0.1)
        assert store.export_csv(tmp_path / "r.csv") == len(missions)
        with (tmp_path / "r.csv").open() as handle:
            rows = list(csv.DictReader(handle))
        assert len(rows) == len(missions) and {r["ticks"] for r in rows} == {
            str(n) for n in range(len(missions))
        }
        pq = need("pyarrow.parquet", "parquet")  # the rest needs the parquet extra
        assert store.export_parquet(tmp_path / "r.parquet") == len(missions)
    table = pq.read_table(tmp_path / "r.parquet")
    assert table.num_rows == len(missions)
    assert str(table.schema.field("ticks").type) == "int64"
    assert str(table.schema.field("latency").type) == "double"


def test_not_a_database(tmp_path: Path) -> None:
    path = tmp_path / "x.sqlite"
    path.write_text("hello, this is not sqlite at all" * 10)
    with pytest.raises(Exception, match="not a results database"):
        ResultStore(path)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 7), st.integers(-5, 5)), max_size=30))
def test_any_sequence_of_adds_keeps_one_row_per_key(adds: list[tuple[int, int]]) -> None:
    """Whatever order and repetition results arrive in, the first result per key is kept."""
    missions = _missions()
    with tempfile.TemporaryDirectory() as folder, ResultStore(Path(folder) / "r.sqlite") as store:
        first: dict[str, int] = {}
        for index, value in adds:
            mission = missions[index % len(missions)]
            assert store.add(mission, {"value": value}, 0.0) == (mission.key not in first)
            first.setdefault(mission.key, value)
        assert {str(r["key"]): r["value"] for r in store.rows()} == first


def test_parquet_without_pyarrow_is_a_clear_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    with ResultStore(tmp_path / "r.sqlite") as store:
        store.add(_missions()[0], {"ticks": 1}, 0.1)
        with pytest.raises(ProblemError, match=r"needs pyarrow.*selfrepair\[parquet\]"):
            store.export_parquet(tmp_path / "r.parquet")
    assert not (tmp_path / "r.parquet").exists()


# --- batches, interrupts, several writers ---------------------------------------------------------


def test_a_batch_is_stored_whole_or_not_at_all(tmp_path: Path) -> None:
    from selfrepair.experiment.store import Finished

    missions = _missions()
    with ResultStore(tmp_path / "r.sqlite") as store:
        bad = [Finished(m, {"ticks": n}, 0.1) for n, m in enumerate(missions)]
        bad[-1] = Finished(missions[-1], {"ticks": [1]}, 0.1)  # type: ignore[dict-item]
        with pytest.raises(ProblemError):
            store.add_many(bad)
        assert store.count() == 0
        fresh = [Finished(m, {"ticks": 1, "new": "x"}, 0.1) for m in missions]
        assert store.add_many(fresh) == len(missions)
        assert store.add_many([Finished(missions[0], {"ticks": 2}, 0.1)]) == 0
        assert store.count() == len(missions)


class _InterruptAfterCommit:
    """A connection whose COMMIT succeeds and is then interrupted, as a Ctrl-C can be."""

    def __init__(self, db: sqlite3.Connection) -> None:
        self._db = db

    def __getattr__(self, name: str) -> object:
        return getattr(self._db, name)

    def execute(self, sql: str, *args: object) -> sqlite3.Cursor:
        cursor = self._db.execute(sql, *args)
        if sql == "COMMIT":
            raise KeyboardInterrupt
        return cursor


def test_interrupt_just_after_commit_keeps_the_rows_and_raises_no_rollback_error(
    tmp_path: Path,
) -> None:
    missions = _missions()
    with ResultStore(tmp_path / "r.sqlite") as store:
        real = store._db
        store._db = _InterruptAfterCommit(real)  # type: ignore[assignment]
        with pytest.raises(KeyboardInterrupt):
            store.add(missions[0], {"ticks": 1}, 0.1)
        store._db = real
        assert store.keys() == {missions[0].key}
        assert store.add(missions[1], {"ticks": 2}, 0.1)  # the connection is usable


def test_a_second_connection_with_a_stale_column_list_adds_rows(tmp_path: Path) -> None:
    """Two writers bring the same new metric column: the second must not add it again."""
    a, b = _missions()[:2]
    with ResultStore(tmp_path / "r.sqlite") as one, ResultStore(tmp_path / "r.sqlite") as two:
        assert one.add(a, {"fresh": 1}, 0.1)
        assert two.add(b, {"fresh": 2}, 0.1)
        assert {str(r["key"]): r["fresh"] for r in one.rows()} == {a.key: 1, b.key: 2}


def test_writers_claim_disjoint_missions_and_free_them(tmp_path: Path) -> None:
    keys = [m.key for m in _missions()][:4]
    with ResultStore(tmp_path / "r.sqlite") as one, ResultStore(tmp_path / "r.sqlite") as two:
        one.start_writing()
        two.start_writing()
        first = one.claim(keys, 2)
        second = two.claim(keys, 2)
        assert first.claimed == tuple(keys[:2]) and first.examined == 2
        assert second.busy == tuple(keys[:2]) and second.claimed == tuple(keys[2:4])
        one.add(_missions()[0], {"ticks": 1}, 0.1)  # stored: its claim is gone
        again = two.claim(keys[:2], 4)
        assert again.stored == (keys[0],) and again.busy == (keys[1],) and not again.claimed
        one.stop_writing()  # frees keys[1]
        assert two.claim(keys, 4).claimed == (keys[1], keys[2], keys[3])
        assert len(two.writers()) == 1


def test_claims_of_dead_writers_are_taken_over(tmp_path: Path) -> None:
    import socket
    import subprocess
    import time

    gone = subprocess.Popen([sys.executable, "-c", "pass"])  # a pid that is gone once reaped
    gone.wait()
    keys = [m.key for m in _missions()]
    now = time.time()
    with ResultStore(tmp_path / "r.sqlite") as store:
        writers = [
            ("dead-here", socket.gethostname(), gone.pid, None, now, now),
            ("silent-elsewhere", "another-host", 1, None, now - 10_000, now - 10_000),
            ("alive-elsewhere", "another-host", 1, None, now, now),
        ]
        store._db.executemany("INSERT INTO writers VALUES (?, ?, ?, ?, ?, ?)", writers)
        store._db.executemany(
            "INSERT INTO claims VALUES (?, ?, ?)",
            [
                (keys[0], "dead-here", now),
                (keys[1], "silent-elsewhere", now),
                (keys[2], "alive-elsewhere", now),
                (keys[3], "never-registered", now),
            ],
        )
        store.start_writing()
        claim = store.claim(keys, 3)
        assert claim.claimed == (keys[0], keys[1], keys[3]) and claim.busy == (keys[2],)
        assert {w["owner"] for w in store.writers()} >= {"alive-elsewhere"}
        assert "dead-here" not in {w["owner"] for w in store.writers()}


def test_malformed_database_is_one_input_error(tmp_path: Path) -> None:
    from selfrepair.errors import InputError

    path = tmp_path / "r.sqlite"
    with ResultStore(path) as store:
        for m in _missions():
            store.add(m, {"ticks": 1, "text": "x" * 3000}, 0.1)
    data = bytearray(path.read_bytes())
    data[4096:] = bytes(len(data) - 4096)  # every page after the first zeroed
    path.write_bytes(bytes(data))
    with pytest.raises(InputError, match="malformed"), ResultStore(path, read_only=True) as store:
        store.rows()
    with pytest.raises(InputError, match=r"r\.sqlite"), ResultStore(path) as store:
        store.add(_missions()[0], {"ticks": 1}, 0.1)


def test_foreign_missions_table_is_refused_and_left_alone(tmp_path: Path) -> None:
    from selfrepair.errors import InputError

    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as con:
        con.execute("CREATE TABLE missions (id INTEGER)")
    with pytest.raises(InputError, match="no column 'key'"):
        ResultStore(path)
    with sqlite3.connect(path) as con:
        assert {r[0] for r in con.execute("SELECT name FROM sqlite_master")} == {"missions"}
