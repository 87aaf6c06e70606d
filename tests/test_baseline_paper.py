"""Regression guard: the reference experiment gives the same non-timing results, mission by mission.

``tests/data/baseline/paper-v1.toml`` is the ``paper`` experiment as it stood on 2026-12-01, before
the package was reorganised, and ``paper-v1-digests.json`` holds, for each of its 2304 missions, a
digest of every non-timing column that run stored. Refactors and speed-ups must leave these
untouched; a change that is meant to alter results has to regenerate the file and say why.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from selfrepair.cli import main
from selfrepair.experiment.store import ResultStore

DATA = Path(__file__).parent / "data" / "baseline"
LABEL = ("maze", "route", "faults", "variant", "clearance_weight")


def digests(db: Path, columns: list[str]) -> dict[str, str]:
    """Per mission (keyed by its readable labels), the digest of ``columns``."""
    with ResultStore(db, read_only=True) as store:
        rows = store.rows()
    out = {}
    for row in rows:
        label = "|".join(str(row[c]) for c in LABEL)
        payload = json.dumps({c: row.get(c) for c in columns}, sort_keys=True)
        out[label] = hashlib.sha256(payload.encode()).hexdigest()[:16]
    return out


def test_paper_v1_non_timing_columns_unchanged(tmp_path: Path, capsys: object) -> None:
    expected = json.loads((DATA / "paper-v1-digests.json").read_text(encoding="utf-8"))
    db = tmp_path / "paper.sqlite"
    code = main(["experiment", str(DATA / "paper-v1.toml"), "--db", str(db), "--jobs", "2"])
    assert code == 0
    got = digests(db, expected["columns"])
    assert set(got) == set(expected["missions"])
    differing = sorted(k for k, v in expected["missions"].items() if got[k] != v)
    assert not differing, f"{len(differing)} missions changed, e.g. {differing[:5]}"
