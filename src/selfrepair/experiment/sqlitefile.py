"""The SQLite plumbing of the results store: its failures as one-line input errors naming the
file, retries while another writer holds the lock, and when a read-only database may be read as
an immutable file."""

from __future__ import annotations

import os
import sqlite3
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TypeVar

from selfrepair.errors import InputError

__all__ = ["immutable_is_safe", "retry_locked", "sqlite_errors"]

_T = TypeVar("_T")


@contextmanager
def sqlite_errors(path: Path, what: str, lock_timeout: float) -> Iterator[None]:
    """SQLite failures as one-line :class:`InputError`s naming the file."""
    try:
        yield
    except sqlite3.ProgrammingError:
        raise  # misuse of the connection: a bug, not bad input
    except sqlite3.DatabaseError as exc:
        reason = " ".join(str(exc).split())  # SQLite may quote multi-line schema text
        if "locked" in reason or "busy" in reason:
            reason += f" (another process held it for more than {lock_timeout:g} s)"
        raise InputError(f"{what}: {reason}", source=str(path)) from None
    except UnicodeDecodeError as exc:  # damaged text in a table or in the schema
        byte = exc.object[exc.start]
        raise InputError(
            f"{what}: text that is not UTF-8 ({exc.reason}, byte 0x{byte:02x})",
            source=str(path),
        ) from None


def retry_locked(lock_timeout: float, action: Callable[[], _T]) -> _T:
    """``action()``, tried again (with growing pauses) while SQLite reports the database locked,
    for up to ``lock_timeout`` seconds."""
    deadline = time.monotonic() + lock_timeout
    delay = 0.005
    while True:
        try:
            return action()
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) or time.monotonic() > deadline:
                raise
            time.sleep(delay)
            delay = min(delay * 2, 0.2)


def immutable_is_safe(path: Path) -> bool:
    """Whether the database may be read as an immutable file: its directory is not writable
    and there is no write-ahead log with rows not yet copied into the file."""
    wal = path.with_name(path.name + "-wal")
    has_log = wal.exists() and wal.stat().st_size > 0
    return not has_log and not os.access(path.parent, os.W_OK)
