"""The results store: one SQLite row per finished mission, crash-safe and duplicate-free.

Table ``missions`` has fixed columns (``key`` primary key, ``experiment``, ``seed``, ``version``,
``config`` - the exact canonical configuration JSON -, ``finished_at``, ``worker_seconds``), the
mission's dimension columns (maze, route, faults, variant, ...) and one column per metric of the
executor's result row. Metric columns are added the first time a metric name appears, inside the
same transaction as the row that brings it.

Why a killed sweep loses nothing and never stores a half or duplicate row: the database runs in
WAL mode; each finished mission is written by a single ``INSERT OR IGNORE`` in its own
transaction, committed before the next result is taken. SQLite transactions are atomic, so a
SIGKILL leaves either the whole row or none of it; the primary key on the mission key makes a
re-run of an already stored mission a no-op. ``synchronous=NORMAL`` keeps every committed row
across a process kill (the WAL is in the OS's hands once ``COMMIT`` returns); only a power cut
can lose the last few commits.
"""

from __future__ import annotations

import csv
import json
import re
import sqlite3
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from selfrepair import __version__
from selfrepair.errors import InputError, ProblemError
from selfrepair.experiment.missions import Mission

__all__ = [
    "FIXED_COLUMNS",
    "ResultStore",
    "Value",
    "is_timing_column",
    "require_pyarrow",
    "without_timings",
]

Value = int | float | str | None

FIXED_COLUMNS = ("key", "experiment", "seed", "version", "config", "finished_at", "worker_seconds")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_SCHEMA = """
CREATE TABLE IF NOT EXISTS missions (
    key TEXT PRIMARY KEY NOT NULL,
    experiment TEXT NOT NULL,
    seed INTEGER NOT NULL,
    version TEXT NOT NULL,
    config TEXT NOT NULL,
    finished_at TEXT NOT NULL,
    worker_seconds REAL
);
CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY NOT NULL, value TEXT NOT NULL);
INSERT OR IGNORE INTO meta VALUES ('schema', '1');
"""


def is_timing_column(name: str) -> bool:
    """Whether a column holds wall-clock measurements (which differ between identical runs)."""
    return name in (
        "finished_at",
        "worker_seconds",
        "version",
        "compute_per_action_ns",
    ) or name.endswith("_ns")


def without_timings(row: Mapping[str, Value]) -> dict[str, Value]:
    """``row`` without its timing columns: what two runs with the same seed must agree on."""
    return {k: v for k, v in row.items() if not is_timing_column(k)}


class ResultStore:
    """An open results database. Use as a context manager, or call :meth:`close`."""

    def __init__(self, path: str | Path, *, read_only: bool = False) -> None:
        """Open (and, unless ``read_only``, create) the database at ``path``.

        ``read_only`` opens an existing database without changing it (as the report does) and
        refuses a file that has no ``missions`` table.
        """
        self.path = Path(path)
        try:
            if read_only:
                self._db = self._open_read_only()
            else:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._db = sqlite3.connect(self.path, isolation_level=None, timeout=30.0)
                self._db.execute("PRAGMA journal_mode=WAL")
                self._db.execute("PRAGMA synchronous=NORMAL")
                self._db.executescript(_SCHEMA)
        except sqlite3.DatabaseError as exc:
            raise InputError(f"not a results database: {exc}", source=str(self.path)) from None
        except OSError as exc:
            raise InputError(
                f"cannot open the database: {exc.strerror}", source=str(self.path)
            ) from None
        self._columns = self._read_columns()

    def _open_read_only(self) -> sqlite3.Connection:
        if not self.path.is_file():
            raise InputError("expected an existing results database", source=str(self.path))
        db = sqlite3.connect(f"{self.path.resolve().as_uri()}?mode=ro", uri=True)
        tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master")}
        if "missions" not in tables:
            db.close()
            raise InputError(
                "expected a results database (a 'missions' table), found none",
                source=str(self.path),
            )
        return db

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the connection (every row is already committed)."""
        self._db.close()

    def _read_columns(self) -> list[str]:
        return [row[1] for row in self._db.execute("PRAGMA table_info(missions)")]

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column of the missions table, in table order."""
        return tuple(self._columns)

    def keys(self) -> set[str]:
        """The keys of every stored mission."""
        return {row[0] for row in self._db.execute("SELECT key FROM missions")}

    def count(self) -> int:
        """How many missions are stored."""
        return int(self._db.execute("SELECT COUNT(*) FROM missions").fetchone()[0])

    def add(self, mission: Mission, metrics: Mapping[str, Value], worker_seconds: float) -> bool:
        """Store one finished mission atomically; False when its key was already stored."""
        row: dict[str, Value] = {
            "key": mission.key,
            "experiment": mission.experiment,
            "seed": mission.seed,
            "version": __version__,
            "config": mission.config,
            "finished_at": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "worker_seconds": float(worker_seconds),
        }
        for name, label in mission.labels:
            row[name] = label
        for name, value in metrics.items():
            column = name if name not in row else f"result_{name}"
            row[column] = _check_value(name, value)
        names = list(row)
        placeholders = ",".join("?" * len(names))
        sql = f"INSERT OR IGNORE INTO missions ({','.join(_quote(n) for n in names)}) "
        sql += f"VALUES ({placeholders})"
        self._db.execute("BEGIN IMMEDIATE")
        try:
            for name in names:
                if name not in self._columns:
                    self._db.execute(f"ALTER TABLE missions ADD COLUMN {_quote(name)}")
            cursor = self._db.execute(sql, [row[n] for n in names])
            self._db.execute("COMMIT")
        except BaseException:
            self._db.execute("ROLLBACK")
            self._columns = self._read_columns()
            raise
        if not set(names) <= set(self._columns):
            self._columns = self._read_columns()
        return cursor.rowcount == 1

    def rows(self, where: str = "", params: Iterable[Value] = ()) -> list[dict[str, Value]]:
        """Every stored row as a dict (column -> value), ordered by key."""
        cursor = self._db.execute(f"SELECT * FROM missions {where} ORDER BY key", tuple(params))
        names = [d[0] for d in cursor.description]
        return [dict(zip(names, values, strict=True)) for values in cursor]

    def export_csv(self, path: str | Path) -> int:
        """Write every row to a CSV file (header first); returns the number of rows."""
        rows = self.rows()
        with Path(path).open("w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(self._columns)
            for row in rows:
                writer.writerow(["" if row[c] is None else row[c] for c in self._columns])
        return len(rows)

    def export_parquet(self, path: str | Path) -> int:
        """Write every row to a Parquet file (needs pyarrow); returns the number of rows."""
        require_pyarrow()
        import pyarrow as pa
        import pyarrow.parquet as pq

        rows = self.rows()
        columns = {c: [row[c] for row in rows] for c in self._columns}
        table = pa.table({c: pa.array(v, type=_arrow_type(pa, v)) for c, v in columns.items()})
        pq.write_table(table, str(path))
        return len(rows)


def require_pyarrow() -> None:
    """Raise :class:`ProblemError` when pyarrow (needed for Parquet export) is missing."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise ProblemError(
            "Parquet export needs pyarrow, which is not installed: pip install pyarrow "
            "(or use --export-csv)"
        ) from None


def _quote(name: str) -> str:
    if not _NAME.match(name):
        raise ProblemError(f"metric name {name!r} is not a valid column name")
    return f'"{name}"'


def _check_value(name: str, value: object) -> Value:
    if value is None or isinstance(value, int | float | str):
        return value
    raise ProblemError(
        f"metric {name!r} must be int, float, str or None, got {type(value).__name__}"
    )


def _arrow_type(pa: Any, values: list[Value]) -> Any:
    """One Arrow type per column: int64, float64 (ints and floats mixed) or string."""
    kinds = {type(v) for v in values if v is not None}
    if kinds <= {int, bool} and kinds:
        return pa.int64()
    if kinds <= {int, float, bool} and kinds:
        return pa.float64()
    if not kinds:
        return pa.null()
    if kinds - {str}:
        for i, v in enumerate(values):
            if v is not None and not isinstance(v, str):
                values[i] = json.dumps(v) if not isinstance(v, int | float) else str(v)
    return pa.string()
