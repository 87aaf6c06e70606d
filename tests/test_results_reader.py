"""The results database as input: `report` (and the store's reader) on damaged, altered or
foreign databases gives one line and exit 2, never a traceback; a valid database is read in a
read-only directory; `report -o ""` is refused. Property-based over mutations of a valid file."""

from __future__ import annotations

import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
from collections.abc import Callable
from contextlib import suppress
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from extras import need
from selfrepair.cli import main
from selfrepair.errors import InputError
from selfrepair.experiment.findings import check_findings, summarize
from selfrepair.experiment.report import choose_mission, read_results, render_markdown

TINY = """\
name = "tiny"
seed = 5
[[mazes]]
bundled = "narrow-short"
[faults]
sets = ["FL:F", "FR:B,RR:B"]
[planner]
clearance_weights = [0, 1]
[[strategies]]
name = "replan"
[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
"""


@pytest.fixture(scope="module")
def valid_db(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("valid")
    config = folder / "tiny.toml"
    config.write_text(TINY)
    db = folder / "r.sqlite"
    assert main(["experiment", str(config), "--db", str(db), "--jobs", "1"]) == 0
    return db


def _copy(valid: Path, folder: Path) -> Path:
    db = folder / "r.sqlite"
    shutil.copyfile(valid, db)
    return db


def _report_fails_in_one_line(
    db: Path, out: Path, capsys: pytest.CaptureFixture[str], *expected: str
) -> None:
    capsys.readouterr()
    assert main(["report", str(db), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("selfrepair: error: "), err
    for text in (str(db), *expected):
        assert text in err, err


def test_zeroed_pages(valid_db: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = _copy(valid_db, tmp_path)
    data = bytearray(db.read_bytes())
    data[4096:] = bytes(len(data) - 4096)
    db.write_bytes(bytes(data))
    _report_fails_in_one_line(db, tmp_path / "out", capsys, "malformed")


@pytest.mark.parametrize("column", ["variant", "clearance_weight", "seed"])
def test_missing_column(
    valid_db: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], column: str
) -> None:
    db = _copy(valid_db, tmp_path)
    with sqlite3.connect(db) as con:
        con.execute(f"ALTER TABLE missions DROP COLUMN {column}")
    _report_fails_in_one_line(db, tmp_path / "out", capsys, f"no column {column!r}")


@pytest.mark.parametrize(
    ("config", "expected"),
    [
        ('{"faults": ', "column 'config'"),
        ("[1, 2]", "column 'config'"),
        ('{"faults": "FL:F"}', "stored configuration cannot be run again"),
    ],
)
def test_broken_config(
    valid_db: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    config: str,
    expected: str,
) -> None:
    db = _copy(valid_db, tmp_path)
    with sqlite3.connect(db) as con:
        con.execute("UPDATE missions SET config = ?", (config,))
    _report_fails_in_one_line(db, tmp_path / "out", capsys, expected)


@pytest.mark.parametrize(
    ("column", "value", "expected"),
    [
        ("reached", "yes", "expected a number"),
        ("extra_ticks", float("inf"), "expected a number"),
        ("clearance_weight", "1e999999999", "expected an exact number"),
        ("repair_latencies_ns", "[1, 2", "a JSON list of numbers"),
        ("repair_sources", "[1]", "a JSON list of texts"),
        ("maze", 7, "expected text"),
        ("seed", "x", "an integer"),
    ],
)
def test_values_of_the_wrong_kind(
    valid_db: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    column: str,
    value: object,
    expected: str,
) -> None:
    db = _copy(valid_db, tmp_path)
    with sqlite3.connect(db) as con:
        con.execute(f'UPDATE missions SET "{column}" = ?', (value,))
    _report_fails_in_one_line(db, tmp_path / "out", capsys, expected, column)


def test_empty_output_path_is_refused(
    valid_db: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(tmp_path)
    for out in ("", "  "):
        capsys.readouterr()
        assert main(["report", str(valid_db), "-o", out]) == 2
        assert "empty path" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def _unprivileged(command: list[str]) -> subprocess.CompletedProcess[str]:
    """Run ``command`` as a user that cannot write the test's directories (root can write
    anywhere, so a read-only directory is only read-only to someone else)."""
    if os.geteuid() != 0:
        return subprocess.run(command, capture_output=True, text=True, check=False)
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        pytest.skip("running as root without setpriv: cannot drop privileges")
    return subprocess.run(
        [setpriv, "--reuid=65534", "--regid=65534", "--clear-groups", *command],
        capture_output=True,
        text=True,
        check=False,
    )


@pytest.mark.skipif(sys.platform != "linux", reason="file modes and setpriv")
def test_valid_database_in_a_read_only_directory_is_read(valid_db: Path) -> None:
    folder = Path(tempfile.mkdtemp(prefix="selfrepair-ro-"))
    try:
        db = _copy(valid_db, folder)
        db.chmod(0o644)
        folder.chmod(0o555)
        code = (
            "import sys; from selfrepair.experiment.report import read_results; "
            "print(len(read_results(sys.argv[1])))"
        )
        done = _unprivileged([sys.executable, "-c", code, str(db)])
        assert done.returncode == 0, done.stderr
        assert int(done.stdout) == len(read_results(valid_db))
        assert sorted(p.name for p in folder.iterdir()) == ["r.sqlite"]  # nothing written there
    finally:
        folder.chmod(0o755)
        shutil.rmtree(folder)


# --- property: any mutation of a valid database is read or refused in one error -------------------

_VALUES = st.one_of(
    st.none(),
    st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=20),
    st.binary(max_size=8),
    st.sampled_from(["[1, 2]", '["replan"]', "{}", "[[", "1/0", "1e999999", '{"faults": 1}', ""]),
)


def _set_cells(cells: list[tuple[int, int, object]]) -> Callable[[sqlite3.Connection], None]:
    def apply(con: sqlite3.Connection) -> None:
        columns = [r[1] for r in con.execute("PRAGMA table_info(missions)")]
        keys = [r[0] for r in con.execute("SELECT key FROM missions ORDER BY key")]
        for row, column, value in cells:
            # a NULL or repeated key: SQLite itself refuses the change
            with suppress(sqlite3.IntegrityError):
                con.execute(
                    f'UPDATE missions SET "{columns[column % len(columns)]}" = ? WHERE key = ?',
                    (value, keys[row % len(keys)]),
                )

    return apply


def _drop_column(index: int) -> Callable[[sqlite3.Connection], None]:
    def apply(con: sqlite3.Connection) -> None:
        columns = [r[1] for r in con.execute("PRAGMA table_info(missions)")]
        with suppress(sqlite3.OperationalError):  # the primary key cannot be dropped
            con.execute(f'ALTER TABLE missions DROP COLUMN "{columns[index % len(columns)]}"')

    return apply


def _statement(sql: str) -> Callable[[sqlite3.Connection], None]:
    return lambda con: con.execute(sql) and None


_SQL_MUTATIONS = st.one_of(
    st.lists(
        st.tuples(st.integers(0, 99), st.integers(0, 199), _VALUES), min_size=1, max_size=4
    ).map(_set_cells),
    st.integers(0, 199).map(_drop_column),
    st.sampled_from(
        [
            "DELETE FROM missions",
            "ALTER TABLE missions RENAME TO other",
            "DROP TABLE meta",
            "CREATE TABLE x (y)",
        ]
    ).map(_statement),
)


@st.composite
def _byte_mutation(draw: st.DrawFn) -> tuple[str, int, bytes]:
    kind = draw(st.sampled_from(["zero", "noise", "truncate"]))
    return kind, draw(st.integers(0, 2**20)), draw(st.binary(min_size=1, max_size=64))


def _mutate_bytes(db: Path, mutation: tuple[str, int, bytes]) -> None:
    kind, where, noise = mutation
    data = bytearray(db.read_bytes())
    where %= len(data)
    if kind == "truncate":
        del data[where:]
    elif kind == "zero":
        data[where : where + 4096] = bytes(len(data[where : where + 4096]))
    else:
        data[where : where + len(noise)] = noise
    db.write_bytes(bytes(data))


def _read_or_refuse(db: Path) -> None:
    """The property: rows that pass the reader carry the whole report's text; anything else is
    one InputError naming the file."""
    try:
        rows = read_results(db)
    except InputError as exc:
        assert str(db) in str(exc) and "\n" not in str(exc)
        return
    chosen = choose_mission(rows)
    text = render_markdown(
        rows, summarize(rows), check_findings(rows), chosen, str(db), heatmap_variant=None
    )
    assert text.startswith("# ")


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(mutation=_SQL_MUTATIONS)
def test_any_altered_database_is_read_or_refused(valid_db: Path, mutation: object) -> None:
    with tempfile.TemporaryDirectory() as folder:
        db = _copy(valid_db, Path(folder))
        with sqlite3.connect(db) as con:
            mutation(con)  # type: ignore[operator]
        con.close()
        _read_or_refuse(db)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(mutation=_byte_mutation())
@example(mutation=("noise", 3195, b"\x80"))  # found by this test: text that is not UTF-8
@example(mutation=("noise", 3154, b"["))  # found by this test: a message with line breaks
def test_any_damaged_file_is_read_or_refused(
    valid_db: Path, mutation: tuple[str, int, bytes]
) -> None:
    with tempfile.TemporaryDirectory() as folder:
        db = _copy(valid_db, Path(folder))
        _mutate_bytes(db, mutation)
        _read_or_refuse(db)


@pytest.mark.slow
@settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(mutation=_SQL_MUTATIONS)
def test_report_on_any_altered_database_is_written_or_one_line(
    valid_db: Path, mutation: object
) -> None:
    need("matplotlib", "viz")
    with tempfile.TemporaryDirectory() as folder:
        db = _copy(valid_db, Path(folder))
        with sqlite3.connect(db) as con:
            mutation(con)  # type: ignore[operator]
        con.close()
        code = main(["report", str(db), "-o", str(Path(folder) / "out")])
        assert code in (0, 2)
