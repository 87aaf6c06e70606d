"""Fuzzing every reader: any input parses or raises an InputError, and the CLI says so in one line.

Readers: maze text, MovingAI maps and scenarios, route files, replacement-table JSON and experiment
TOML (the results database and trace files are owned elsewhere). Each property runs on text and
on raw bytes written to a file, built three ways: a valid file with a few mutations (inserted
format tokens, hostile characters, deletions), loose soups of format tokens, and arbitrary text.

Property 1 (library): the reader returns a value or raises an
:class:`~selfrepair.errors.InputError` subclass; any other exception fails the test.
Property 2 (CLI): the command that reads the file exits 0 or 1, or exits 2 with exactly one line
on stderr, ``selfrepair: error: ...``, which carries the library's message; a traceback fails.

Default runs are small (:data:`FAST` examples per test) so the suite stays quick; under
``-m slow`` the same properties run with :data:`SLOW` examples (:data:`SLOW_CLI` for those that
run the CLI; 12 minutes in all on the busy 2-core development machine).
"""

from __future__ import annotations

import io
import itertools
import tempfile
from collections.abc import Callable
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.errors import InputError
from selfrepair.experiment.config import load_config, parse_config
from selfrepair.experiment.missions import count_missions
from selfrepair.tables.fileformat import bundled_table, dump_table, load_table, parse_table
from selfrepair.world.loading import load_maze
from selfrepair.world.maze import format_maze, parse_maze
from selfrepair.world.movingai import load_map, load_scenario, parse_map, parse_scenario
from selfrepair.world.routes import load_routes, parse_routes

FAST = 40
SLOW = 2000
SLOW_CLI = 500
EXAMPLES = pytest.mark.parametrize(
    "examples", [FAST, pytest.param(SLOW, marks=pytest.mark.slow, id="slow")]
)
CLI_EXAMPLES = pytest.mark.parametrize(
    "examples", [FAST, pytest.param(SLOW_CLI, marks=pytest.mark.slow, id="slow")]
)
"""Each example of a file-and-CLI property runs a command in-process (tens of milliseconds)."""

# --- input strategies --------------------------------------------------------------------------

HOSTILE = [
    "\n", "\r", "\r\n", "\n\n", "\t", " ", "\x00", "\x0b", "\x0c", "\x1c", "\x1e", "\x85",
    "\u2028", "\u2029", "\ufeff", "\ud800", "é", "²", "١", "𝟙", "\\", '"', "'",
]  # fmt: skip
"""Line separators ``str.splitlines`` knows, control and format characters, a lone surrogate,
non-ASCII digits and quoting characters."""

NUMBERS = ["0", "-1", "1.5", "nan", "inf", "-inf", "1e400", "1e308", "9" * 25, "1" * 5000]

SMALL_MAZE = format_maze(parse_maze("#######\n#S....#\n#.###.#\n#....G#\n#######\n"))
SMALL_MAP = "type octile\nheight 3\nwidth 4\nmap\n@@@@\n@.G@\n@TS@\n"
SMALL_SCEN = "version 1\n0\tsmall.map\t4\t3\t1\t1\t2\t1\t1.00000000\n"
SMALL_ROUTES = "# two routes\nr1 1,1,E 5,3\nr2 5,1,S 1,3\n"
TABLE = dump_table(bundled_table("three-action"))
TOML = """\
name = "fuzz"
seed = 7
repeats = 1
[[mazes]]
bundled = "narrow-short"
[[mazes]]
generate = { width = 15, height = 15, corridor = 1, seed = 3 }
routes = 2
[faults]
sets = ["FL:F", "FL:F,RR:B"]
at = [0]
[planner]
clearance_weights = [0, 0.5]
[[strategies]]
name = "replacement"
tables = ["handwritten"]
recursion = ["flat"]
"""

TOKENS: dict[str, list[str]] = {
    "maze": ["#", ".", "S", "G", "x", "#" * 40, "." * 40, "#.\n" * 5],
    "map": ["type", "octile", "height", "width", "map", "@", ".", "T", "G", "height 3",
            "width 99999999", "height 0", "map\n", "type octile\n"],
    "scen": ["version 1", "\t", "small.map", "4", "3", "-5", "1.0", "\t4\t3\t1\t1\t2\t1\t"],
    "routes": ["r1", "#", ",", "1,1,E", "5,3", "1,1,Q", "1,1", " r9 1,1,N 1,1\n"],
    "table": ["[", "]", "{", "}", ",", ":", '"', "null", "true", "NaN", "Infinity", "-0",
              '"version"', '"entries"', '"candidates"', '"A"', "[" * 3000, '"action": "A"',
              '"parameters": {"k": [[1]]}', '"format": "selfrepair-table"'],
    "toml": ["=", "[", "]", "[[", "]]", "{", "}", ",", '"', "'''", '"""', "#", "true", "[]",
             "1979-05-27", "0x10", "\n[[mazes]]\n", "\n[faults]\n", "routes = []",
             "repeats = true", "[" * 3000, "routes = 10000", "file = 'nowhere.maze'",
             "bundled = 'nowhere'", 'sets = "all"', "window = [64]", "clearance_radius = 64"],
}  # fmt: skip

CHUNKS = st.one_of(
    st.sampled_from(HOSTILE),
    st.sampled_from(NUMBERS),
    st.text(max_size=6),
)


@st.composite
def mutated(draw: st.DrawFn, base: str, tokens: list[str]) -> str:
    """``base`` with one to four slices replaced by tokens, hostile characters or random text."""
    text = base
    pieces = st.one_of(st.sampled_from(tokens), CHUNKS, st.just(""))
    for _ in range(draw(st.integers(1, 4))):
        start = draw(st.integers(0, len(text)))
        end = draw(st.integers(start, min(len(text), start + 12)))
        text = text[:start] + draw(pieces) + text[end:]
    return text


def texts(base: str, kind: str) -> st.SearchStrategy[str]:
    """Mutations of a valid ``base``, soups of the format's tokens, and arbitrary text."""
    tokens = TOKENS[kind]
    soup = st.lists(st.one_of(st.sampled_from(tokens), CHUNKS), max_size=30).map("".join)
    return st.one_of(mutated(base, tokens), soup, st.text(max_size=200))


def files(base: str, kind: str) -> st.SearchStrategy[bytes]:
    """File contents: the texts as UTF-8 (lone surrogates kept), and byte-level corruptions."""
    encoded = texts(base, kind).map(lambda t: t.encode("utf-8", "surrogatepass"))
    corrupt = st.tuples(
        st.integers(0, len(base)), st.sampled_from([b"\xe9", b"\xff", b"\xef\xbb\xbf", b"\xc3"])
    ).map(lambda p: base.encode()[: p[0]] + p[1] + base.encode()[p[0] :])
    return st.one_of(encoded, corrupt, st.binary(max_size=200))


# --- the two properties ------------------------------------------------------------------------


def parses_or_input_error(read: Callable[[], Any]) -> InputError | None:
    """Run a reader: its value is fine, an InputError is returned, anything else propagates."""
    try:
        read()
    except InputError as exc:
        return exc
    return None


def text_check(parse: Callable[[str], Any]) -> Callable[[str], None]:
    """The library property for a reader of text."""

    def check(text: str) -> None:
        parses_or_input_error(lambda: parse(text))

    return check


def cli_is_one_line_or_success(args: list[str], library_error: InputError | None) -> None:
    """Run the CLI in-process; exit 2 must be exactly one stderr line (the library's message)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(args)
    message = err.getvalue()
    if library_error is not None:
        assert code == 2, (code, message)
    if code == 2:
        assert message.startswith("selfrepair: error: ") and message.count("\n") == 1, message
        assert message.endswith("\n") and "Traceback" not in message
        if library_error is not None:
            assert " ".join(str(library_error).split()) in message
    else:
        assert code in (0, 1), (code, message)


def fuzz(
    strategy: st.SearchStrategy[Any],
    check: Callable[[Any], None],
    examples: int,
    known: tuple[Any, ...] = (),
) -> None:
    """Run ``check`` on the ``known`` inputs (the reliability audit's findings, so a regression
    fails at once) and on ``examples`` inputs drawn from ``strategy``."""
    test = given(strategy)(check)
    for case in known:
        test = example(case)(test)
    settings(
        max_examples=examples,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )(test)()


_counter = itertools.count()


def write(folder: Path, name: str, data: bytes) -> Path:
    """A fresh file (its own directory, so a mutation can never name a neighbour by accident)."""
    directory = folder / f"case{next(_counter)}"
    directory.mkdir()
    path = directory / name
    path.write_bytes(data)
    return path


@pytest.fixture(scope="module")
def folder() -> Any:
    with tempfile.TemporaryDirectory(prefix="selfrepair-fuzz-") as name:
        yield Path(name)


# --- maze text ---------------------------------------------------------------------------------


@EXAMPLES
def test_maze_text(examples: int) -> None:
    known = ("\ufeff" + SMALL_MAZE, SMALL_MAZE.replace("\n", "\u2028", 2), "#" * 5000 + "1")
    fuzz(texts(SMALL_MAZE, "maze"), text_check(parse_maze), examples, known)


@CLI_EXAMPLES
def test_maze_file_and_cli(folder: Path, examples: int) -> None:
    def check(data: bytes) -> None:
        path = write(folder, "m.maze", data)
        error = parses_or_input_error(lambda: load_maze(path))
        cli_is_one_line_or_success(["maze", "show", str(path)], error)

    fuzz(files(SMALL_MAZE, "maze"), check, examples, (b"\xef\xbb\xbf#.#\n", b"#\xe9#\n"))


# --- MovingAI maps and scenarios ---------------------------------------------------------------


@EXAMPLES
def test_movingai_map_text(examples: int) -> None:
    known = ("", SMALL_MAP.replace("height 3", "height 3\nheight 4"), "height 1" + "0" * 5000)
    fuzz(texts(SMALL_MAP, "map"), text_check(parse_map), examples, known)


@CLI_EXAMPLES
def test_movingai_map_file_and_cli(folder: Path, examples: int) -> None:
    def check(data: bytes) -> None:
        path = write(folder, "m.map", data)
        error = parses_or_input_error(lambda: load_map(path))
        cli_is_one_line_or_success(["maze", "show", str(path)], error)

    fuzz(files(SMALL_MAP, "map"), check, examples, (b"", b"type octile\n\xff"))


@EXAMPLES
def test_movingai_scenario_text(examples: int) -> None:
    maze = parse_map(SMALL_MAP)

    def check(text: str) -> None:
        parses_or_input_error(lambda: parse_scenario(text))
        parses_or_input_error(lambda: parse_scenario(text, maze=maze))

    known = (SMALL_SCEN.replace("1.00000000", "nan"), SMALL_SCEN.replace("\t1\t1", "\t1" * 5000))
    fuzz(texts(SMALL_SCEN, "scen"), check, examples, known)


@CLI_EXAMPLES
def test_movingai_scenario_file_and_cli(folder: Path, examples: int) -> None:
    def check(data: bytes) -> None:
        path = write(folder, "s.map.scen", data)
        (path.parent / "small.map").write_text(SMALL_MAP, encoding="utf-8")
        error = parses_or_input_error(lambda: load_scenario(path))
        cli_is_one_line_or_success(["check-scen", str(path), "--json"], error)

    known = tuple(SMALL_SCEN.replace("1.00000000", n).encode() for n in ("nan", "inf", "-1"))
    fuzz(files(SMALL_SCEN, "scen"), check, examples, known)


# --- route files -------------------------------------------------------------------------------


@EXAMPLES
def test_route_text(examples: int) -> None:
    maze = parse_maze(SMALL_MAZE)

    def check(text: str) -> None:
        parses_or_input_error(lambda: parse_routes(text))
        parses_or_input_error(lambda: parse_routes(text, maze=maze))

    fuzz(texts(SMALL_ROUTES, "routes"), check, examples, ("r1 1" + "0" * 5000 + ",1,E 5,3",))


@CLI_EXAMPLES
def test_route_file_and_cli(folder: Path, examples: int) -> None:
    def check(data: bytes) -> None:
        path = write(folder, "m.routes", data)
        maze = path.parent / "m.maze"
        maze.write_text(SMALL_MAZE, encoding="utf-8")
        error = parses_or_input_error(lambda: load_routes(path, maze=parse_maze(SMALL_MAZE)))
        cli_is_one_line_or_success(["maze", "show", str(maze), "--routes"], error)

    fuzz(files(SMALL_ROUTES, "routes"), check, examples)


# --- replacement tables ------------------------------------------------------------------------


@EXAMPLES
def test_table_json_text(examples: int) -> None:
    known = ("[" * 100_000, TABLE.replace('"version": 1', '"version": 1' + "0" * 5000))
    fuzz(texts(TABLE, "table"), text_check(parse_table), examples, known)


@CLI_EXAMPLES
def test_table_file_and_cli(folder: Path, examples: int) -> None:
    def check(data: bytes) -> None:
        path = write(folder, "t.json", data)
        error = parses_or_input_error(lambda: load_table(path))
        cli_is_one_line_or_success(["table", "show", str(path)], error)

    fuzz(files(TABLE, "table"), check, examples, (b"[" * 100_000, b"\xef\xbb\xbf" + b"{}"))


# --- experiment TOML ---------------------------------------------------------------------------


@EXAMPLES
def test_experiment_toml_text(examples: int) -> None:
    def check(text: str) -> None:
        try:
            config = parse_config(text)
        except InputError:
            return
        parses_or_input_error(lambda: count_missions(config))

    known = ("a = " + "[" * 5000 + "]" * 5000, "seed = " + "1" * 5000)
    fuzz(texts(TOML, "toml"), check, examples, known)


@CLI_EXAMPLES
def test_experiment_file_and_cli(folder: Path, examples: int) -> None:
    def check(data: bytes) -> None:
        path = write(folder, "e.toml", data)
        error = parses_or_input_error(lambda: load_config(path))
        if error is not None:  # a valid file would run the whole experiment
            db = str(path.parent / "r.sqlite")
            cli_is_one_line_or_success(["experiment", str(path), "--jobs", "1", "--db", db], error)

    fuzz(files(TOML, "toml"), check, examples, (TOML.encode() + b"# caf\xe9\n",))
