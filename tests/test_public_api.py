"""`import selfrepair as sr` gives the public names on first use, typed, and the same objects as
their modules; `import selfrepair` alone imports none of the package."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

import selfrepair
from selfrepair import _api

NAMES = sorted(set(selfrepair.__all__) - {"__version__"})


def test_the_package_and_the_api_module_list_the_same_names() -> None:
    assert sorted(_api.__all__) == NAMES
    assert len(NAMES) == len(set(_api.__all__))


def test_type_checkers_see_the_same_names_from_the_same_modules() -> None:
    def imports(path: str, body: str) -> set[tuple[str | None, str]]:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"))
        nodes = (
            tree.body
            if body == "module"
            else next(n for n in tree.body if isinstance(n, ast.If)).body
        )
        return {(n.module, a.name) for n in nodes if isinstance(n, ast.ImportFrom) for a in n.names}

    typed = imports(selfrepair.__file__, "if")
    assert typed == imports(_api.__file__, "module") - {("__future__", "annotations")}
    assert sorted(name for _, name in typed) == NAMES


@pytest.mark.parametrize("name", NAMES)
def test_each_public_name_is_the_object_its_module_defines(name: str) -> None:
    value = getattr(selfrepair, name)
    assert value is getattr(_api, name) and name in dir(selfrepair)
    home = getattr(value, "__module__", None)
    if home is not None and home.startswith("selfrepair."):  # not re-exported from elsewhere
        assert getattr(sys.modules[home], name) is value


def test_an_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'run_missions'"):
        _ = selfrepair.run_missions  # type: ignore[attr-defined]


def test_import_selfrepair_imports_nothing_until_a_name_is_used() -> None:
    code = (
        "import sys, selfrepair\n"
        "print(sorted(m for m in sys.modules if m.startswith('selfrepair.') or m == 'numpy'))\n"
        "selfrepair.run_mission\n"
        "print('selfrepair.execution.executor' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["[]", "True"]


def test_the_docstring_example_runs(capsys: pytest.CaptureFixture[str]) -> None:
    match = re.search(r"::\n\n((?:    .*\n|\n)+)", selfrepair.__doc__ or "")
    assert match is not None, "the package docstring has no example"
    code = "\n".join(line[4:] for line in match.group(1).splitlines())
    exec(compile(code, "selfrepair/__init__.py", "exec"), {})
    assert capsys.readouterr().out == "reached\n"
