"""The rows of a results database as the experiment report reads them, checked.

:func:`read_results` reads every row of a database written by ``selfrepair experiment`` and
checks each column the report (:mod:`selfrepair.experiment.report`) reads: text where text
belongs, bounded numbers, exact clearance weights, JSON lists. A bad value is one
:class:`~selfrepair.errors.InputError` naming the file, the mission and the column.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from pathlib import Path

from selfrepair.errors import InputError
from selfrepair.experiment.findings import Row
from selfrepair.experiment.store import ResultStore

__all__ = ["check_rows", "load_rows", "read_results"]

_TEXT = ("key", "experiment", "version", "config", "maze", "route", "faults", "variant", "strategy")
"""Columns the report reads as text: each must be there, and hold text in every row."""
_OPTIONAL_TEXT = ("table", "recursion", "finished_at")
_NUMBERS = (
    "worker_seconds",
    "reached",
    "replacements",
    "replans",
    "lookaheads",
    "faulty_encounters",
    "repair_count",
    "compute_per_action_ns",
    "extra_ticks",
    "maze_free_cells",
    "maze_width",
    "plan_distance",
)
"""Columns the report reads as numbers: numbers of magnitude at most :data:`_LARGEST` or empty,
when the column is there."""
_LARGEST = 1e18
"""Larger than any count or time in nanoseconds a mission can have; sums of such numbers over
any number of rows stay finite."""
_EXACT = re.compile(r"^-?[0-9]{1,18}(?:/[1-9][0-9]{0,17}|\.[0-9]{1,18})?$")
"""A clearance weight as stored: an integer, a decimal or a fraction (``1/2``)."""
_NUMBER_LISTS = ("repair_latencies_ns",)
_TEXT_LISTS = ("repair_sources",)


def read_results(db: str | Path) -> list[Row]:
    """Every row of the results database ``db``, checked for what the report reads from it.

    A file that is not a readable results database, a missing column, or a value of the wrong
    kind (text where a number belongs, a ``config`` that is not a JSON object, ...) is an
    :class:`~selfrepair.errors.InputError` naming the file and, for a value, the mission's key
    and the column. The database is never changed (it may lie in a read-only directory).
    """
    columns, rows = load_rows(db)
    return check_rows(columns, rows, str(db))


def load_rows(db: str | Path) -> tuple[set[str], list[Row]]:
    """The columns and the rows of the results database ``db``, unchecked (opened read-only)."""
    with ResultStore(db, read_only=True) as store:  # a report never changes its input
        return set(store.columns), store.rows()


def check_rows(columns: set[str], rows: list[Row], source: str) -> list[Row]:
    """``rows`` when every column the report reads is there and holds what it should; else an
    :class:`~selfrepair.errors.InputError` naming ``source`` (the database)."""
    missing = [c for c in (*_TEXT, "seed", "clearance_weight") if c not in columns]
    if missing:
        raise InputError(
            "expected a results database of `selfrepair experiment`: table 'missions' has no "
            "column " + ", ".join(repr(c) for c in missing),
            source=source,
        )
    if not rows:
        raise InputError("expected a results database with at least one mission", source=source)
    for row in rows:
        _check_row(row, source)
    return rows


def _check_row(row: Row, source: str) -> None:
    key = row.get("key")
    where = f"mission {str(key)[:12]!r}" if isinstance(key, str) else "a mission"

    def bad(column: str, expected: str) -> InputError:
        value = repr(row.get(column))
        shown = value if len(value) <= 40 else value[:37] + "..."
        return InputError(
            f"{where}: column {column!r}: expected {expected}, got {shown}", source=source
        )

    for column in _TEXT:
        if not isinstance(row.get(column), str):
            raise bad(column, "text")
    for column in _OPTIONAL_TEXT:
        if row.get(column) is not None and not isinstance(row.get(column), str):
            raise bad(column, "text")
    if not isinstance(row.get("seed"), int):
        raise bad("seed", "an integer")
    for column in _NUMBERS:
        if not _is_number_or_none(row.get(column)):
            raise bad(column, f"a number of magnitude at most {_LARGEST:g}")
    if not _is_fraction(row.get("clearance_weight")):
        raise bad("clearance_weight", "an exact number such as 1/2")
    for column in _NUMBER_LISTS:
        if not _is_json_list(row.get(column), _is_number):
            raise bad(column, "a JSON list of numbers")
    for column in _TEXT_LISTS:
        if not _is_json_list(row.get(column), lambda v: isinstance(v, str)):
            raise bad(column, "a JSON list of texts")
    try:
        config = json.loads(str(row["config"]))
    except ValueError:
        config = None
    if not isinstance(config, dict) or not isinstance(config.get("faults"), str):
        raise bad("config", "the mission's configuration as a JSON object")


def _is_number(value: object) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and abs(value) <= _LARGEST
    )


def _is_number_or_none(value: object) -> bool:
    return value is None or _is_number(value)


def _is_fraction(value: object) -> bool:
    if value is None or value == "" or _is_number(value):
        return True
    # exact decimals or fractions of bounded length only: Fraction("1e999999999") would build
    # a billion-digit integer
    text = str(value)
    return bool(_EXACT.match(text))


def _is_json_list(value: object, item: Callable[[object], bool]) -> bool:
    if value is None or value == "":
        return True
    try:
        data = json.loads(str(value))
    except (ValueError, RecursionError):
        return False
    return isinstance(data, list) and all(item(v) for v in data)
