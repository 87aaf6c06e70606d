"""Checksums of experiment rows, mission by mission, to prove that a refactoring kept results.

``row_digests`` hashes, per mission key, the values of the non-timing columns named in a golden
file (the columns a row had when the file was written). New columns may appear without breaking
the check; a column that disappears or changes its value in any mission fails it. Columns whose
meaning was changed on purpose are listed in the test with the reason, never silently dropped.

Regenerate (only when a result change is intended and explained in the commit)::

    python tests/golden.py paper results.sqlite tests/data/golden/paper.json
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path

from selfrepair.experiment.store import ResultStore, without_timings


def _digest(row: Mapping[str, object], columns: Iterable[str]) -> str:
    text = json.dumps([[c, row.get(c, "<missing>")] for c in columns], sort_keys=False)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def rows_of(db: Path) -> dict[str, dict[str, object]]:
    """The non-timing columns of every stored row, by mission key."""
    with ResultStore(db) as store:
        return {str(r["key"]): without_timings(r) for r in store.rows()}


def row_digests(
    rows: Mapping[str, Mapping[str, object]], columns: Iterable[str]
) -> dict[str, str]:
    cols = list(columns)
    return {key: _digest(row, cols) for key, row in sorted(rows.items())}


def write_golden(db: Path, out: Path) -> None:
    rows = rows_of(db)
    columns = sorted({c for r in rows.values() for c in r} - {"key"})
    out.write_text(
        json.dumps({"columns": columns, "digests": row_digests(rows, columns)}, indent=0) + "\n"
    )


if __name__ == "__main__":
    write_golden(Path(sys.argv[2]), Path(sys.argv[3]))
