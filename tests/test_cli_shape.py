"""The command line as a whole: help text, start-up cost, input lookup and the wording rules
(the library names no command-line flag in its errors)."""

from __future__ import annotations

import ast
import json
import os
import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
import typer

from selfrepair.cli import app, main

ROOT = Path(__file__).parent.parent
SRC = ROOT / "src" / "selfrepair"


def commands() -> Iterator[tuple[str, typer.core.TyperCommand]]:
    """Every command of the CLI, with its full name (``maze show``)."""
    group = typer.main.get_command(app)

    def walk(command: object, prefix: str) -> Iterator[tuple[str, typer.core.TyperCommand]]:
        sub = getattr(command, "commands", None)
        if sub is None:
            yield prefix, command  # type: ignore[misc]
            return
        for name, child in sub.items():
            yield from walk(child, f"{prefix} {name}".strip())

    yield from walk(group, "")


COMMANDS = dict(commands())


def test_the_commands_are_the_documented_ones() -> None:
    assert set(COMMANDS) == {
        "actions", "domains", "plan", "path", "check-scen", "run", "compare", "replay",
        "experiment", "report", "animate", "view", "gym-eval", "pddl", "maze show", "maze list",
        "maze generate", "maze routes", "table show", "table check", "table generate",
        "table coverage", "team run", "team compare", "team replay", "team table", "team frame",
        "tolerance", "physics fidelity", "physics run", "physics experiment",
    }  # fmt: skip


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_help_has_no_type_labels_and_every_option_has_help(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([*name.split(), "--help"]) == 0
    text = capsys.readouterr().out
    assert not re.search(r"<(bool|str|int|float|path|text|integer)>", text), text
    for param in COMMANDS[name].params:
        assert param.help, f"{name}: {param.name} has no help text"
    usage = text.splitlines()[0]
    for argument in re.findall(r"[{\[]([^\]}]+)[}\]]", usage):
        if argument != "OPTIONS":
            assert argument.isupper(), f"{name}: argument {argument} is not upper case"


@pytest.mark.parametrize("group", ["", "maze", "table", "team"])
def test_command_lists_are_not_cut(group: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*group.split(), "--help"]) == 0
    listing = capsys.readouterr().out.split("Commands:", 1)[1]
    assert "..." not in listing, listing


HEAVY = (
    "numba",
    "pydantic",
    "joblib",
    "matplotlib",
    "gymnasium",
    "unified_planning",
    "selenium",
    "scipy",
    "numpy",
    "rich",
)


def _heavy_modules_after(argvs: list[list[str]]) -> dict[str, list[str]]:
    """Run each command line in turn in one fresh interpreter (where nothing else has imported
    anything) and return, per command line, the heavy modules loaded so far."""
    code = (
        "import sys, io, json, contextlib\n"
        "from selfrepair.cli import main\n"
        "loaded = {}\n"
        f"for argv in {argvs!r}:\n"
        "    with contextlib.redirect_stdout(io.StringIO()):\n"
        "        assert main(argv) == 0, argv\n"
        f"    loaded[' '.join(argv)] = sorted(m for m in {HEAVY!r} if m in sys.modules)\n"
        "print(json.dumps(loaded))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    result: dict[str, list[str]] = json.loads(out)
    return result


@pytest.mark.parametrize("argv", [["actions"], ["actions", "--json"], ["domains"]])
def test_quick_commands_load_no_heavy_module(argv: list[str]) -> None:
    """Start-up: these commands import none of the heavy libraries."""
    assert _heavy_modules_after([argv]) == {" ".join(argv): []}


def test_no_help_loads_a_heavy_module() -> None:
    """``selfrepair --help``, every group's and every command's ``--help`` import none of the
    heavy libraries (one interpreter runs them all: the first to load one is named)."""
    groups = sorted({name.split()[0] for name in COMMANDS if " " in name})
    argvs = [["--help"], *([g, "--help"] for g in groups)]
    argvs += [[*name.split(), "--help"] for name in sorted(COMMANDS)]
    loaded = _heavy_modules_after(argvs)
    assert {argv: mods for argv, mods in loaded.items() if mods} == {}


def test_the_cli_defaults_match_the_library() -> None:
    from selfrepair.baselines.pddl import MAX_PDDL_CELLS
    from selfrepair.cli.pddl import PDDL_CELLS_DEFAULT
    from selfrepair.cli.view import VIEW_STEPS_DEFAULT
    from selfrepair.experiment.viewer import MAX_VIEW_STEPS
    from selfrepair.limits import MAX_TRACE_BYTES

    assert VIEW_STEPS_DEFAULT == MAX_VIEW_STEPS and PDDL_CELLS_DEFAULT == MAX_PDDL_CELLS
    defaults = {p.name: p.default for p in COMMANDS["replay"].params}
    assert defaults["max_trace_bytes"] == MAX_TRACE_BYTES == 256 * 1024 * 1024


# --- input lookup --------------------------------------------------------------------------------


README_MAP = "tests/data/movingai/maze512-1-0.map"


def test_readme_movingai_paths_work_from_another_directory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The README's path/check-scen commands name the repository paths; they run from any
    directory of a source checkout (the README's commands are run from a temporary one)."""
    monkeypatch.chdir(tmp_path)
    assert main(["path", README_MAP, "--from", "1,1", "--to", "511,511", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["status"] == "solved"
    scen = README_MAP + ".scen"
    assert main(["check-scen", scen, "--sample", "3"]) == 0
    assert "0 mismatches" in capsys.readouterr().out


def test_a_bare_movingai_name_points_to_the_checkout_copy(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["path", "maze512-1-0.map", "--from", "1,1", "--to", "3,1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and README_MAP in err


def test_a_file_in_the_working_directory_wins(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tests" / "data" / "movingai").mkdir(parents=True)
    (tmp_path / README_MAP).write_text("type octile\nheight 1\nwidth 3\nmap\n...\n")
    assert main(["path", README_MAP, "--from", "0,0", "--to", "2,0", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["cost"] == 2


# --- wording -------------------------------------------------------------------------------------

FLAG = re.compile(r"(?<![\w-])--[a-z][a-z-]+")
ALLOWED = {
    # execution/traceread.py is owned by another change; its message names a flag that `replay`
    # now has (--partial). Limit messages may name the flag that raises the limit.
    ("execution/traceread.py", "--partial"),
    # A file that records a plug-in robot (a trace) whose file is gone or changed: the one way to
    # give the robot to any command is the global --plugin (issue 29 item 3 asks to name it).
    ("robots/registry.py", "--plugin"),
    ("execution/traceread.py", "--plugin"),
}


def _raised_texts(tree: ast.AST) -> Iterator[tuple[int, str]]:
    for node in ast.walk(tree):
        if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call):
            for part in ast.walk(node.exc):
                if isinstance(part, ast.Constant) and isinstance(part.value, str):
                    yield node.lineno, part.value


def test_library_errors_name_no_command_line_flag() -> None:
    found = []
    for path in sorted(SRC.rglob("*.py")):
        relative = path.relative_to(SRC).as_posix()
        if relative.startswith("cli/"):
            continue
        source = path.read_text(encoding="utf-8")
        for line, text in _raised_texts(ast.parse(source)):
            for flag in FLAG.findall(text):
                limit = re.search(r"\braise\b.*--", text) is not None  # "raise it with --flag"
                if not limit and (relative, flag) not in ALLOWED:
                    found.append(f"{relative}:{line}: {flag}")
    assert found == []


def test_console_script_help_in_a_pipe(tmp_path: Path) -> None:
    """The installed script prints the same plain help in a pipe (no colour codes, no cut)."""
    script = Path(sys.executable).parent / "selfrepair"
    if not script.exists():
        pytest.skip("the selfrepair script is not installed next to this interpreter")
    env = {**os.environ, "COLUMNS": "60"}
    out = subprocess.run(
        [str(script), "--help"], capture_output=True, text=True, check=True, env=env
    ).stdout
    assert "\x1b[" not in out and "compare" in out
