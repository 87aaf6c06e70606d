"""Exporting the results store's rows: CSV (header first), or Parquet with one Arrow type per
column (needs pyarrow, the ``parquet`` extra)."""

from __future__ import annotations

import csv
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from selfrepair.errors import ProblemError
from selfrepair.experiment.storerows import Value

__all__ = ["require_pyarrow", "write_csv", "write_parquet"]


def write_csv(path: str | Path, columns: Sequence[str], rows: Sequence[dict[str, Value]]) -> int:
    """Write ``rows`` to a CSV file (header ``columns`` first); returns the number of rows."""
    with Path(path).open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for row in rows:
            writer.writerow(["" if row[c] is None else row[c] for c in columns])
    return len(rows)


def write_parquet(
    path: str | Path, columns: Sequence[str], rows: Sequence[dict[str, Value]]
) -> int:
    """Write ``rows`` to a Parquet file (needs pyarrow); returns the number of rows."""
    require_pyarrow()
    import pyarrow as pa
    import pyarrow.parquet as pq

    values = {c: [row[c] for row in rows] for c in columns}
    table = pa.table({c: pa.array(v, type=arrow_type(pa, v)) for c, v in values.items()})
    pq.write_table(table, str(path))
    return len(rows)


def require_pyarrow() -> None:
    """Raise :class:`ProblemError` when pyarrow (needed for Parquet export) is missing."""
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise ProblemError(
            "Parquet export needs pyarrow, which is not installed: pip install "
            "'selfrepair[parquet]' (or export CSV instead)"
        ) from None


def arrow_type(pa: Any, values: list[Value]) -> Any:
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
