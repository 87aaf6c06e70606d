"""The results store: one SQLite row per finished mission, crash-safe, duplicate-free, shared.

Table ``missions`` has fixed columns (``key`` primary key, ``experiment``, ``seed``, ``version``,
``config`` - the exact canonical configuration JSON -, ``finished_at``, ``worker_seconds``), the
mission's dimension columns (maze, route, faults, variant, ...) and one column per metric of the
executor's result row. Metric columns are added the first time a metric name appears, inside the
same transaction as the rows that bring them.

Why a killed sweep loses nothing and never stores a half or duplicate row: the database runs in
WAL mode; finished missions are written in batches, each batch by ``INSERT OR IGNORE`` in one
transaction. SQLite transactions are atomic, so a SIGKILL leaves either the whole batch or none
of it (a lost batch is simply run again on resume); the primary key on the mission key makes a
re-run of an already stored mission a no-op. ``synchronous=NORMAL`` keeps every committed row
across a process kill (the WAL is in the OS's hands once ``COMMIT`` returns); only a power cut
can lose the last few commits.

Several writers (processes, on this host or others sharing the file) can fill one database at
once. Each registers in table ``writers`` (owner id, host, pid, heartbeat) and *claims* the
missions it is about to run in table ``claims`` (key, owner, time) before running them; a writer
skips what another live writer has claimed. A writer is dead when its heartbeat is older than
:data:`LEASE_SECONDS`, or, on the same host, as soon as its process is gone; its claims are then
free again. The schema is created once, inside one transaction, whoever comes first; every write
is a ``BEGIN IMMEDIATE`` transaction that re-reads the column list under the write lock, so no
writer acts on a stale view of the table.
"""

from __future__ import annotations

import os
import socket
import sqlite3
import time
import uuid
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from pathlib import Path

from selfrepair.errors import InputError, ProblemError
from selfrepair.experiment.export import require_pyarrow, write_csv, write_parquet
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.liveness import LEASE_SECONDS, process_start, writer_is_dead
from selfrepair.experiment.sqlitefile import immutable_is_safe, retry_locked, sqlite_errors
from selfrepair.experiment.storerows import (
    FIXED_COLUMNS,
    SCHEMA,
    Finished,
    Value,
    is_timing_column,
    quote_column,
    stored_row,
    without_timings,
)

__all__ = [
    "FIXED_COLUMNS",
    "LEASE_SECONDS",
    "LOCK_TIMEOUT_SECONDS",
    "Claim",
    "Finished",
    "ResultStore",
    "Value",
    "is_timing_column",
    "require_pyarrow",
    "without_timings",
]

LOCK_TIMEOUT_SECONDS = 60.0
"""How long a write waits for another writer's transaction before giving up."""

_REAP_EVERY_SECONDS = 1.0
"""Dead writers are looked for at most this often (each look asks the OS about their pids)."""


@dataclass(frozen=True, slots=True)
class Claim:
    """What :meth:`ResultStore.claim` found among the keys it looked at, in their order.

    ``claimed``: now this writer's to run; ``stored``: already in the table; ``busy``: claimed
    by another live writer (look again later: it may finish them, or die); ``examined``: how many
    of the given keys were looked at (the rest were not reached because ``limit`` was met).
    """

    claimed: tuple[str, ...]
    stored: tuple[str, ...]
    busy: tuple[str, ...]
    examined: int


class ResultStore:
    """An open results database. Use as a context manager, or call :meth:`close`."""

    def __init__(
        self,
        path: str | Path,
        *,
        read_only: bool = False,
        lock_timeout: float = LOCK_TIMEOUT_SECONDS,
    ) -> None:
        """Open (and, unless ``read_only``, create) the database at ``path``.

        ``read_only`` opens an existing database without changing it (as the report does), also
        in a directory this process cannot write to, and refuses a file that has no ``missions``
        table. Any SQLite failure (not a database, a damaged file, locked for longer than
        ``lock_timeout`` seconds) is an :class:`~selfrepair.errors.InputError` naming the file.
        """
        self.path = Path(path)
        self._lock_timeout = lock_timeout
        self._owner: str | None = None
        self._last_reap = 0.0
        self._known_columns: frozenset[str] = frozenset()
        try:
            if read_only:
                self._db = self._open_read_only()
            else:
                self._db = self._open_for_writing()
        except OSError as exc:
            raise InputError(
                f"cannot open the database: {exc.strerror}", source=str(self.path)
            ) from None

    # --- opening -------------------------------------------------------------------------------

    def _open_for_writing(self) -> sqlite3.Connection:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self._errors("not a results database"):
            db = sqlite3.connect(self.path, isolation_level=None, timeout=self._lock_timeout)
        self._db = db
        try:
            with self._errors("not a results database"):
                # Changing the journal mode does not wait for other connections: retry.
                retry_locked(
                    self._lock_timeout, lambda: db.execute("PRAGMA journal_mode=WAL").fetchone()
                )
                db.execute("PRAGMA synchronous=NORMAL")
                with self._write():  # the whole schema at once, by whichever writer is first
                    db.execute(SCHEMA[0])
                    self._check_fixed_columns()  # a foreign 'missions' table: nothing is changed
                    for statement in SCHEMA[1:]:
                        db.execute(statement)
        except BaseException:
            db.close()
            raise
        return db

    def _open_read_only(self) -> sqlite3.Connection:
        if not self.path.is_file():
            raise InputError("expected an existing results database", source=str(self.path))
        uri = self.path.resolve().as_uri()
        with self._errors("cannot read the results database"):
            try:
                db = self._open_uri(f"{uri}?mode=ro")
            except sqlite3.OperationalError:
                if not immutable_is_safe(self.path):
                    raise
                # WAL mode needs a shared-memory file next to the database; in a directory this
                # process cannot write, and with no write-ahead log left over, the file alone
                # holds every committed row and may be read as it is.
                db = self._open_uri(f"{uri}?mode=ro&immutable=1")
        self._db = db
        return db

    def _open_uri(self, uri: str) -> sqlite3.Connection:
        db = sqlite3.connect(uri, uri=True, timeout=self._lock_timeout)
        try:
            tables = {row[0] for row in db.execute("SELECT name FROM sqlite_master")}
        except BaseException:
            db.close()
            raise
        if "missions" not in tables:
            db.close()
            raise InputError(
                "expected a results database (a 'missions' table), found none",
                source=str(self.path),
            )
        self._db = db
        self._check_fixed_columns()
        return db

    def _check_fixed_columns(self) -> None:
        missing = [c for c in FIXED_COLUMNS if c not in self.columns]
        if missing:
            raise InputError(
                "expected a results database: table 'missions' has no column "
                + ", ".join(repr(c) for c in missing),
                source=str(self.path),
            )

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the connection (every row is already committed; a writer's claims are freed)."""
        try:
            self.stop_writing()
        except InputError:
            pass  # the claims stay until another writer sees this process is gone and frees them
        finally:
            self._db.close()

    # --- plumbing ------------------------------------------------------------------------------

    def _errors(self, what: str) -> AbstractContextManager[None]:
        """SQLite failures as one-line :class:`InputError`s naming the file."""
        return sqlite_errors(self.path, what, self._lock_timeout)

    @contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        """One ``BEGIN IMMEDIATE`` transaction: all of it is committed, or none of it.

        ``ROLLBACK`` only runs while the transaction is still open: an interrupt that arrives
        just after ``COMMIT`` returned leaves the committed rows alone and is re-raised as it is.
        """
        retry_locked(self._lock_timeout, lambda: self._db.execute("BEGIN IMMEDIATE"))
        try:
            yield self._db
            self._db.execute("COMMIT")
        except BaseException:
            if self._db.in_transaction:
                self._db.execute("ROLLBACK")
            self._known_columns = frozenset()  # an ALTER TABLE may have been rolled back
            raise

    @property
    def columns(self) -> tuple[str, ...]:
        """Every column of the missions table, in table order (read from the database now)."""
        with self._errors("cannot read the results database"):
            return tuple(row[1] for row in self._db.execute("PRAGMA table_info(missions)"))

    # --- reading -------------------------------------------------------------------------------

    def keys(self) -> set[str]:
        """The keys of every stored mission."""
        with self._errors("cannot read the results database"):
            return {row[0] for row in self._db.execute("SELECT key FROM missions")}

    def count(self) -> int:
        """How many missions are stored."""
        with self._errors("cannot read the results database"):
            return int(self._db.execute("SELECT COUNT(*) FROM missions").fetchone()[0])

    def rows(self, where: str = "", params: Iterable[Value] = ()) -> list[dict[str, Value]]:
        """Every stored row as a dict (column -> value), ordered by key."""
        with self._errors("cannot read the results database"):
            cursor = self._db.execute(f"SELECT * FROM missions {where} ORDER BY key", tuple(params))
            names = [d[0] for d in cursor.description]
            return [dict(zip(names, values, strict=True)) for values in cursor]

    # --- writing -------------------------------------------------------------------------------

    def add(self, mission: Mission, metrics: Mapping[str, Value], worker_seconds: float) -> bool:
        """Store one finished mission atomically; False when its key was already stored."""
        return self.add_many([Finished(mission, metrics, worker_seconds)]) == 1

    def add_many(self, finished: Sequence[Finished]) -> int:
        """Store a batch of finished missions in one transaction (all or none); returns how many
        were new (a key already stored keeps its first row). Frees this writer's claims on them.
        """
        rows = [stored_row(f.mission, f.metrics, f.seconds) for f in finished]
        groups: dict[tuple[str, ...], list[list[Value]]] = {}
        for row in rows:
            groups.setdefault(tuple(row), []).append(list(row.values()))
        needed = {name for names in groups for name in names}
        for name in needed:
            quote_column(name)  # bad names are misuse: refused before any write
        added = 0
        with self._errors("cannot write to the results database"), self._write() as db:
            if not needed <= self._known_columns:
                self._known_columns = frozenset(self.columns)  # fresh: under the write lock
                for name in sorted(needed - self._known_columns):
                    db.execute(f"ALTER TABLE missions ADD COLUMN {quote_column(name)}")
            for names, values in groups.items():
                sql = (
                    f"INSERT OR IGNORE INTO missions ({','.join(quote_column(n) for n in names)}) "
                    f"VALUES ({','.join('?' * len(names))})"
                )
                added += db.executemany(sql, values).rowcount
            if self._owner is not None:
                db.executemany(
                    "DELETE FROM claims WHERE key = ? AND owner = ?",
                    [(str(row["key"]), self._owner) for row in rows],
                )
                self._beat(db)
            self._known_columns |= needed
        return added

    # --- several writers -----------------------------------------------------------------------

    def start_writing(self) -> str:
        """Register this process as a writer (needed before :meth:`claim`); returns its owner id.

        Idempotent while registered; :meth:`stop_writing` (also run by :meth:`close`) ends it.
        """
        if self._owner is not None:
            return self._owner
        owner = f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:12]}"
        now = time.time()
        with self._errors("cannot write to the results database"), self._write() as db:
            db.execute(
                "INSERT INTO writers VALUES (?, ?, ?, ?, ?, ?)",
                (owner, socket.gethostname(), os.getpid(), process_start(os.getpid()), now, now),
            )
        self._owner = owner
        return owner

    def stop_writing(self) -> None:
        """Free every claim this writer holds on missions it did not store, and unregister it."""
        if self._owner is None:
            return
        owner, self._owner = self._owner, None
        with self._errors("cannot write to the results database"), self._write() as db:
            db.execute("DELETE FROM claims WHERE owner = ?", (owner,))
            db.execute("DELETE FROM writers WHERE owner = ?", (owner,))

    def heartbeat(self) -> None:
        """Tell other writers this one is alive (every claim and every stored batch does too)."""
        if self._owner is None:
            return
        with self._errors("cannot write to the results database"), self._write() as db:
            self._beat(db)

    def claim(self, keys: Sequence[str], limit: int) -> Claim:
        """Claim, in order, up to ``limit`` of ``keys`` that are neither stored nor claimed by
        another live writer (claims of dead writers are taken over). One transaction."""
        if self._owner is None:
            raise ProblemError("claim() needs start_writing() first")
        claimed: list[str] = []
        stored: list[str] = []
        busy: list[str] = []
        examined = 0
        now = time.time()
        with self._errors("cannot write to the results database"), self._write() as db:
            if now - self._last_reap >= _REAP_EVERY_SECONDS:
                self._reap(db, now)
                self._last_reap = now
            for key in keys:
                if len(claimed) >= limit:
                    break
                examined += 1
                if db.execute("SELECT 1 FROM missions WHERE key = ?", (key,)).fetchone():
                    stored.append(key)
                    continue
                holder = db.execute("SELECT owner FROM claims WHERE key = ?", (key,)).fetchone()
                if holder is not None and holder[0] != self._owner:
                    busy.append(key)
                    continue
                db.execute(
                    "INSERT OR REPLACE INTO claims VALUES (?, ?, ?)", (key, self._owner, now)
                )
                claimed.append(key)
            self._beat(db)
        return Claim(tuple(claimed), tuple(stored), tuple(busy), examined)

    def writers(self) -> list[dict[str, Value]]:
        """The registered writers (owner, host, pid, pid_start, started_at, heartbeat)."""
        with self._errors("cannot read the results database"):
            cursor = self._db.execute("SELECT * FROM writers ORDER BY started_at")
            names = [d[0] for d in cursor.description]
            return [dict(zip(names, values, strict=True)) for values in cursor]

    def _beat(self, db: sqlite3.Connection) -> None:
        db.execute("UPDATE writers SET heartbeat = ? WHERE owner = ?", (time.time(), self._owner))

    def _reap(self, db: sqlite3.Connection, now: float) -> None:
        """Delete dead writers and their claims (inside the caller's write transaction)."""
        dead = [
            owner
            for owner, host, pid, pid_start, heartbeat in db.execute(
                "SELECT owner, host, pid, pid_start, heartbeat FROM writers WHERE owner != ?",
                (self._owner,),
            ).fetchall()
            if writer_is_dead(str(host), int(pid), pid_start, float(heartbeat), now)
        ]
        for owner in dead:
            db.execute("DELETE FROM claims WHERE owner = ?", (owner,))
            db.execute("DELETE FROM writers WHERE owner = ?", (owner,))
        # claims whose owner never registered or is gone (a writer killed between the two)
        db.execute("DELETE FROM claims WHERE owner NOT IN (SELECT owner FROM writers)")

    # --- export --------------------------------------------------------------------------------

    def export_csv(self, path: str | Path) -> int:
        """Write every row to a CSV file (header first); returns the number of rows."""
        rows = self.rows()
        return write_csv(path, self.columns, rows)

    def export_parquet(self, path: str | Path) -> int:
        """Write every row to a Parquet file (needs pyarrow); returns the number of rows."""
        require_pyarrow()
        rows = self.rows()
        return write_parquet(path, self.columns, rows)
