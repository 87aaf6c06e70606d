"""The rows of the results store (:mod:`selfrepair.experiment.store`): the type of a column's
values, the fixed columns, which columns are timings (two runs with the same seed differ only
there), and how a finished mission becomes its stored row."""

from __future__ import annotations

import re
import time
from collections.abc import Mapping
from dataclasses import dataclass

from selfrepair import __version__
from selfrepair.errors import ProblemError
from selfrepair.experiment.keys import Mission

__all__ = [
    "FIXED_COLUMNS",
    "SCHEMA",
    "Finished",
    "Value",
    "check_value",
    "is_timing_column",
    "quote_column",
    "stored_row",
    "without_timings",
]

Value = int | float | str | None

FIXED_COLUMNS = ("key", "experiment", "seed", "version", "config", "finished_at", "worker_seconds")

SCHEMA = (
    """CREATE TABLE IF NOT EXISTS missions (
        key TEXT PRIMARY KEY NOT NULL,
        experiment TEXT NOT NULL,
        seed INTEGER NOT NULL,
        version TEXT NOT NULL,
        config TEXT NOT NULL,
        finished_at TEXT NOT NULL,
        worker_seconds REAL
    )""",
    "CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY NOT NULL, value TEXT NOT NULL)",
    "INSERT OR IGNORE INTO meta VALUES ('schema', '1')",
    """CREATE TABLE IF NOT EXISTS writers (
        owner TEXT PRIMARY KEY NOT NULL,
        host TEXT NOT NULL,
        pid INTEGER NOT NULL,
        pid_start TEXT,
        started_at REAL NOT NULL,
        heartbeat REAL NOT NULL
    )""",
    """CREATE TABLE IF NOT EXISTS claims (
        key TEXT PRIMARY KEY NOT NULL,
        owner TEXT NOT NULL,
        claimed_at REAL NOT NULL
    )""",
    "CREATE INDEX IF NOT EXISTS claims_by_owner ON claims (owner)",
)
"""The tables of a results database, created in one transaction by whichever writer comes first."""

_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


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


@dataclass(frozen=True, slots=True)
class Finished:
    """One finished mission on its way into the store: the mission, its metric row and the
    worker's wall time in seconds."""

    mission: Mission
    metrics: Mapping[str, Value]
    seconds: float


def stored_row(
    mission: Mission, metrics: Mapping[str, Value], worker_seconds: float
) -> dict[str, Value]:
    """The stored row of one mission: fixed columns, its labels, then its metrics."""
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
        row[column] = check_value(name, value)
    return row


def quote_column(name: str) -> str:
    if not _NAME.match(name):
        raise ProblemError(f"metric name {name!r} is not a valid column name")
    return f'"{name}"'


def check_value(name: str, value: object) -> Value:
    if value is None or isinstance(value, int | float | str):
        return value
    raise ProblemError(
        f"metric {name!r} must be int, float, str or None, got {type(value).__name__}"
    )
