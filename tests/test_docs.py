"""The docs show tables and pictures generated from the code; these tests keep them in step."""

from __future__ import annotations

import builtins
import importlib
import importlib.util
import re
import shlex
from pathlib import Path
from typing import Any

import pytest

from selfrepair.robots import four_wheel_docs
from selfrepair.robots.registry import ENTRY_POINT_GROUP
from selfrepair.world import bundled
from selfrepair.world.render import render_ascii, route_layers

DOCS = Path(__file__).parent.parent / "docs"


def generated_block(text: str, name: str) -> str:
    match = re.search(
        rf"<!-- BEGIN generated: {name} -->\n(.*?)<!-- END generated: {name} -->", text, re.S
    )
    assert match is not None, f"docs block {name} is missing"
    return match.group(1)


@pytest.mark.parametrize(
    "name",
    ["markdown_action_table", "markdown_single_fault_table", "markdown_double_fault_summary"],
)
def test_robot_doc_tables_match_the_code(name: str) -> None:
    text = (DOCS / "robot.md").read_text(encoding="utf-8")
    assert generated_block(text, name) == getattr(four_wheel_docs, name)()


def test_action_table_has_81_rows_in_code_order() -> None:
    text = (DOCS / "robot.md").read_text(encoding="utf-8")
    table = generated_block(text, "markdown_action_table")
    rows = [line.split("|")[1].strip() for line in table.splitlines()[2:]]
    assert len(rows) == 81 and rows[0] == "FFFF" and rows[-1] == "BBBB"


@pytest.mark.parametrize("name", bundled.maze_names())
def test_maze_doc_shows_each_maze_with_its_routes(name: str) -> None:
    text = (DOCS / "mazes.md").read_text(encoding="utf-8")
    picture = render_ascii(bundled.load_bundled(name), route_layers(bundled.bundled_routes(name)))
    assert f"```text\n{picture}```" in text
    for route in bundled.bundled_routes(name):
        assert f"`{route.start}` | `{route.goal[0]},{route.goal[1]}`" in text


def test_readme_library_example_prints_what_the_readme_says(
    capsys: pytest.CaptureFixture[str],
) -> None:
    readme = (DOCS.parent / "README.md").read_text(encoding="utf-8")
    match = re.search(r"```python\n(.*?)```", readme, re.S)
    assert match is not None, "README has no python example"
    code = match.group(1)
    expected = [line[2:] for line in code.splitlines() if line.startswith("# ")]
    assert expected, "the example states its output in '# ' comment lines"
    exec(compile(code, "README.md", "exec"), {})
    assert capsys.readouterr().out.splitlines() == expected


def test_team_doc_table_matches_the_code() -> None:
    from selfrepair.team.table import HANDWRITTEN, markdown_team_table

    text = (DOCS / "team.md").read_text(encoding="utf-8")
    assert generated_block(text, "markdown_team_table") == markdown_team_table(HANDWRITTEN)


# --- every name the docs give exists in the code ----------------------------------------------

ROOT = DOCS.parent
PACKAGE = ROOT / "src" / "selfrepair"
TREES = ("src", "tests", "benchmarks", "examples", "docs")
PAGES = (*sorted(DOCS.glob("*.md")), ROOT / "README.md")
OUTPUTS = ("benchmarks/results/", "results/")
"""Folders the docs name as where commands write (created on first run, not in the tree)."""
VARIABLES = ("self", "np")
"""Short dotted names may start with a module or one of these (``self._options`` of LPG's code,
``np`` for numpy)."""

SPAN = re.compile(r"(\[)?`([^`\n]+)`(\]\([^)]*\))?")
LINK = re.compile(r"\]\(([^)\s#]+)")
REPO_PATH = re.compile(
    r"(?<![\w./-])((?:\.\./)*(?:[\w.-]+/)+[\w.-]+\.(?:py|md|toml|json|js|css|html))\b"
)
BARE_MODULE = re.compile(r"(?<![\w./-])([A-Za-z_]\w*\.py)\b")
DOTTED = re.compile(r"\bselfrepair(?:\.\w+)+")
SHORT_DOTTED = re.compile(r"^([a-z_]\w*(?:\.[A-Za-z_]\w*)+)(?:\(.*\))?$")
FILE_SUFFIXES = (
    *("py", "md", "toml", "json", "png", "gif", "html", "js", "css", "jsonl", "sqlite", "map"),
    *("scen", "txt"),
)
TEST_NAME = re.compile(r"^(test_\w+)$")
TEST_REF = re.compile(r"^((?:tests|benchmarks)/[\w/]+\.py)::(\w+)$")


def _tree() -> tuple[set[str], set[str]]:
    files: set[str] = {p.name for p in ROOT.iterdir() if p.is_file()}
    folders: set[str] = set(TREES)
    for tree in TREES:
        for path in (ROOT / tree).rglob("*"):
            if "__pycache__" in path.parts:
                continue
            (files if path.is_file() else folders).add(path.relative_to(ROOT).as_posix())
    return files, folders


FILES, FOLDERS = _tree()
PYPROJECT = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
MODULE_FILES = {p.name for p in PACKAGE.rglob("*.py")}
MODULES = sorted(
    ".".join(p.relative_to(PACKAGE.parent).with_suffix("").parts)
    for p in PACKAGE.rglob("*.py")
    if p.name != "__init__.py"
)
TEST_NAMES = {
    match.group(1)
    for path in (ROOT / "tests").rglob("*.py")
    for match in re.finditer(r"^(?:async )?def (test_\w+)", path.read_text(encoding="utf-8"), re.M)
}


def _path_exists(token: str, page: Path) -> bool:
    """A path written in a page: relative to the page, to the repository root, or to the
    package (``search/lattice.py``), as the docs write them."""
    if any(token.startswith(out) for out in OUTPUTS):
        return True
    here = (page.parent / token).resolve()
    if here.is_relative_to(ROOT.resolve()) and here.exists():
        return True
    tail = token.lstrip("./")
    return tail in FILES or tail in FOLDERS or f"src/selfrepair/{tail}" in FILES


def _resolves(dotted: str) -> bool:
    """``selfrepair.a.b.c``: the longest importable module, then attributes."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        name = ".".join(parts[:cut])
        if name not in MODULES and not (PACKAGE.parent / name.replace(".", "/")).is_dir():
            continue
        value: object = importlib.import_module(name)
        for attribute in parts[cut:]:
            if not hasattr(value, attribute):
                return False
            value = getattr(value, attribute)
        return True
    return False


def _short_resolves(dotted: str) -> bool | None:
    """``lattice.plan`` or ``search.lattice.plan``: a name relative to the package or to a module
    of it (any module of that name), an attribute of the module or a field of one of its classes.
    ``None`` when the first part names no module (``spec.domain`` is a variable)."""
    parts = dotted.split(".")
    candidates = [m for m in MODULES if f".{parts[0]}." in f"{m}." or m.endswith(f".{parts[0]}")]
    if not candidates:
        return None
    for module in candidates:
        rest = parts[len(module.split(".")) - module.split(".").index(parts[0]) :]
        if not rest:
            return True
        if _resolves(f"{module}.{'.'.join(rest)}"):
            return True
        value = importlib.import_module(module)
        classes = [v for v in vars(value).values() if isinstance(v, type)]
        if len(rest) == 1 and any(
            hasattr(c, rest[0]) or rest[0] in getattr(c, "__dataclass_fields__", {})
            for c in classes
        ):
            return True
    return False


def _outside_module(first: str) -> bool:
    """Whether ``first`` names a module outside selfrepair (the standard library, a dependency or
    an extra of ``pyproject.toml``), a builtin, or one of :data:`VARIABLES`."""
    if first in VARIABLES or hasattr(builtins, first):
        return True
    if importlib.util.find_spec(first) is not None:
        return True
    return re.search(rf"\"{re.escape(first)}\s*[<>=~!\[;\"]", PYPROJECT) is not None


def stale_names(page: Path) -> list[str]:
    """Every module path, ``file.py``, dotted ``selfrepair`` name, short dotted module name and
    test name that ``page`` gives and the code does not have, as ``page:line: name``. Fenced code
    is checked for ``selfrepair.`` names only (its other names are the example's own)."""
    found: list[str] = []
    in_code = False
    for number, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        where = f"{page.name}:{number}"
        in_code ^= line.startswith("```")
        names = [m for m in DOTTED.findall(line) if m != ENTRY_POINT_GROUP and not _resolves(m)]
        if not in_code:
            names += [
                f"link {target}"
                for target in LINK.findall(line)
                if "://" not in target and not _path_exists(target, page)
            ]
            for bracket, span, link in SPAN.findall(line):
                names += _stale_in_span(span, page, linked=bool(bracket and link))
        found += [f"{where}: {name}" for name in names]
    return found


def _stale_in_span(span: str, page: Path, *, linked: bool) -> list[str]:
    """The names of one code span that the code does not have (see :func:`stale_names`)."""
    if "://" in span:
        return []
    stale = [m for m in REPO_PATH.findall(span) if not _path_exists(m, page)]
    # a command line or a key (``plugins = ["robot.py"]``) names the user's files; the text of a
    # link names its target, which is checked as a link
    if not linked and "=" not in span and " " not in span.strip():
        stale += [name for name in BARE_MODULE.findall(span) if name not in MODULE_FILES]
    reference = TEST_REF.match(span)
    if reference:
        path, name = reference.groups()
        text = (ROOT / path).read_text(encoding="utf-8") if path in FILES else ""
        if not re.search(rf"^(?:async )?def {name}\b", text, re.M):
            stale.append(span)
    test = TEST_NAME.match(span)
    if test and test.group(1) not in TEST_NAMES:
        stale.append(span)
    short = SHORT_DOTTED.match(span)
    dotted = short.group(1) if short else ""
    first, _, rest = dotted.partition(".")
    if first == "sr":  # import selfrepair as sr
        return [*stale, *([dotted] if not _resolves(f"selfrepair.{rest}") else [])]
    if dotted and first != "selfrepair" and dotted.rsplit(".", 1)[-1] not in FILE_SUFFIXES:
        known = _short_resolves(dotted)
        if known is False or (known is None and not _outside_module(first)):
            stale.append(dotted)
    return stale


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_name_the_docs_give_exists_in_the_code(page: Path) -> None:
    assert stale_names(page) == []


def test_the_checker_finds_names_that_are_gone(tmp_path: Path) -> None:
    page = tmp_path / "old.md"
    page.write_text(
        "This page describes `src/selfrepair/robot.py` and `tablegen.py`, with\n"
        "`robot.MOTIONS`, `lattice.plan`, `selfrepair.search.lattice.plan` and\n"
        "`selfrepair.robots.four_wheel.NO_SUCH_NAME`; see [the planner](../nowhere.md),\n"
        "`tests/test_docs.py::test_no_such_test`, `test_no_such_test_either`,\n"
        '`plugins = ["mine.py"]`, `search/lattice.py`, `Heading.rotated`, `sr.run_mission`\n'
        "and `sr.run_missions`.\n",
        encoding="utf-8",
    )
    assert stale_names(page) == [
        "old.md:1: src/selfrepair/robot.py",
        "old.md:1: tablegen.py",
        "old.md:2: robot.MOTIONS",
        "old.md:3: selfrepair.robots.four_wheel.NO_SUCH_NAME",
        "old.md:3: link ../nowhere.md",
        "old.md:4: tests/test_docs.py::test_no_such_test",
        "old.md:4: test_no_such_test_either",
        "old.md:6: sr.run_missions",
    ]


def test_the_geometry_example_of_docs_extending_holds() -> None:
    text = (DOCS / "extending.md").read_text(encoding="utf-8")
    match = re.search(r"```python\n(from selfrepair.geometry import .*?)```", text, re.S)
    assert match is not None, "docs/extending.md has no geometry example"
    exec(compile(match.group(1), "extending.md", "exec"), {})


# --- every command line the docs give names commands and options that exist -------------------

COMMAND_SPAN = re.compile(r"`(selfrepair [^`\n]+)`")
COMMAND_LINE = re.compile(r"^\s*(?:\$ )?selfrepair\b|\bselfrepair \$\w+ ")
SHELL_BREAK = ("|", "||", "&&", ";", ">", ">>", "2>", "<")


def _options(command: Any) -> set[str]:
    names = {"--help"}
    for parameter in command.params:
        names |= {*parameter.opts, *parameter.secondary_opts}
    return names


def stale_options(line: str, root: Any) -> list[str]:
    """The commands and options of one ``selfrepair ...`` command line that the CLI does not
    have. ``A|B`` is either; upper-case words, ``[...]`` and ``$VAR`` are placeholders."""
    try:
        words = shlex.split(line, comments=True)
    except ValueError:
        words = line.split()
    words = [w.strip("[]()") for w in words]
    if "selfrepair" not in words:
        return []
    index, globals_ = words.index("selfrepair") + 1, _options(root)
    while index < len(words) and (words[index] in globals_ or words[index].startswith("$")):
        index += 2 if words[index] == "--plugin" else 1
    commands, path = [root], []
    while index < len(words) and not words[index].startswith("-"):
        groups = [c for c in commands if hasattr(c, "commands")]
        if not groups or words[index].isupper() or words[index] == "...":
            break
        names = words[index].split("|")
        missing = [n for n in names if not any(n in g.commands for g in groups)]
        if missing:
            return [f"selfrepair {' '.join([*path, *missing])}"]
        commands = [g.commands[n] for g in groups for n in names if n in g.commands]
        path.append(words[index])
        index += 1
    if any(hasattr(c, "commands") for c in commands):
        return []
    known = globals_.union(*(_options(c) for c in commands))
    stale = []
    for word in words[index:]:
        if word in SHELL_BREAK:
            break
        for option in (part.split("=")[0] for part in word.split("|")):
            if re.fullmatch(r"--?[a-z][\w-]*", option) and option not in known:
                stale.append(f"selfrepair {' '.join(path)} {option}")
    return stale


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_command_line_the_docs_give_runs_here(page: Path) -> None:
    import typer

    from selfrepair.cli import app

    root = typer.main.get_command(app)
    found, in_code, held = [], False, ""
    for number, text in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        if text.startswith("```"):
            in_code = not in_code
            continue
        if in_code and text.endswith("\\"):  # a shell line continued on the next
            held += text[:-1] + " "
            continue
        line, held = held + text, ""
        lines = [line] if in_code and COMMAND_LINE.search(line) else []
        lines += [] if in_code else COMMAND_SPAN.findall(line)
        found += [
            f"{page.name}:{number}: {name}" for text in lines for name in stale_options(text, root)
        ]
    assert found == []


def test_the_command_check_finds_what_is_gone() -> None:
    import typer

    from selfrepair.cli import app

    root = typer.main.get_command(app)
    assert stale_options("selfrepair run narrow-long --strategy replan --trace t.jsonl", root) == []
    assert stale_options("selfrepair table show|check FILE", root) == []
    assert (
        stale_options("selfrepair --plugin r.py table generate -o FILE  # a --comment", root) == []
    )
    assert stale_options("selfrepair run MAZE --no-such-flag", root) == [
        "selfrepair run --no-such-flag"
    ]
    assert stale_options("selfrepair table shwo FILE", root) == ["selfrepair table shwo"]
