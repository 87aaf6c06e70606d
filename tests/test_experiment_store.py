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
        assert store.export_parquet(tmp_path / "r.parquet") == len(missions)
    with (tmp_path / "r.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(missions) and {r["ticks"] for r in rows} == {
        str(n) for n in range(len(missions))
    }
    pq = pytest.importorskip("pyarrow.parquet")
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
        with pytest.raises(ProblemError, match=r"Parquet export needs pyarrow.*--export-csv"):
            store.export_parquet(tmp_path / "r.parquet")
    assert not (tmp_path / "r.parquet").exists()
