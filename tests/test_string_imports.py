"""No module reaches another by a string import, where import-linter cannot see it.

The layers contract of ``pyproject.toml`` checks the imports written as import statements; a
module imported by name through ``importlib.import_module`` or ``__import__`` (as the strategy
registry once did with ``"selfrepair.baselines.adapt:start_lpg_adapt"``, a layer up) escapes it.
Only the plug-in loader (:mod:`selfrepair.robots.registry`, which imports what a user names), the
optional-dependency helper (:mod:`selfrepair.optional`, which imports third-party extras) and the
package root's lazy public API (above every folder) call an import function, and a string that
names one of the package's modules (for such a loader, or for Gymnasium's ``entry_point``) names
one of the module's own folder, never another folder's (but in the root): a folder reaches
another only by an import statement, which the contracts check.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "selfrepair"

LOADERS = frozenset({"robots/registry.py", "optional.py", "__init__.py"})
"""The modules allowed to import by name: the plug-in loader, the optional-dependency helper, and
the package root, whose lazy public API (``import selfrepair as sr``) names modules of every
folder: it stands above all of them, so it reaches down, never up."""

ROOT = "__init__.py"
"""The package root: the one module that may name any folder's modules by string."""

DYNAMIC = frozenset({"import_module", "__import__", "import_extra"})
"""Functions that import a module named by a string."""

OWN_TARGET = re.compile(r"^selfrepair(\.[A-Za-z_]\w*)+(:[A-Za-z_]\w*)?$")
"""A string naming one of the package's modules (``"selfrepair.x.y"`` or ``"selfrepair.x:f"``)."""


def _modules() -> list[Path]:
    return sorted(SRC.rglob("*.py"))


def _name(call: ast.Call) -> str:
    func = call.func
    if isinstance(func, ast.Attribute):
        return func.attr
    return func.id if isinstance(func, ast.Name) else ""


def _is_module(dotted: str) -> bool:
    """Whether ``dotted`` (before any ``:attribute``) is a module or package of the package."""
    path = SRC.parent.joinpath(*dotted.partition(":")[0].split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def _folder(dotted: str) -> str:
    """The concept folder of a module (``"selfrepair.repair.lookups"`` -> ``"repair"``)."""
    parts = dotted.partition(":")[0].split(".")
    return parts[1] if len(parts) > 1 else ""


def string_imports(source: str, *, loader: bool) -> list[str]:
    """Every call of an import function in ``source`` outside a loader (the optional-dependency
    helper's own callers excepted: they name third-party modules)."""
    found: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Call):
            continue
        name = _name(node)
        if name in DYNAMIC and not loader and name != "import_extra":
            found.append((node.lineno, f"line {node.lineno}: {name}(...)"))
    return [text for _, text in sorted(found)]


def module_targets(source: str, folder: str) -> list[str]:
    """String constants of ``source`` (a module of ``folder``) that name a module of another
    folder of the package (``"selfrepair.x.y"`` or ``"selfrepair.x.y:name"``)."""
    return [
        f"line {node.lineno}: {node.value!r}"
        for node in sorted(
            (n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.Constant)),
            key=lambda n: (n.lineno, n.col_offset),
        )
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and OWN_TARGET.match(node.value)
        and _is_module(node.value)
        and _folder(node.value) != folder
    ]


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(SRC)))
def test_no_string_import_of_the_package(path: Path) -> None:
    relative = str(path.relative_to(SRC))
    source = path.read_text(encoding="utf-8")
    folder = relative.split("/")[0] if "/" in relative else ""
    found = string_imports(source, loader=relative in LOADERS)
    if relative != ROOT:
        found += module_targets(source, folder)
    assert not found, f"{relative} imports by name: {'; '.join(found)}"


def test_the_check_sees_what_the_old_registry_did() -> None:
    old = (
        "import importlib\n"
        "_BUILT_ELSEWHERE = {'lpg-adapt': 'selfrepair.baselines.adapt:start_lpg_adapt'}\n"
        "def get(target):\n"
        "    module, _, attribute = target.partition(':')\n"
        "    return getattr(importlib.import_module(module), attribute)\n"
        "unified = importlib.import_module('selfrepair.baselines.unified')\n"
    )
    assert string_imports(old, loader=False) == [
        "line 5: import_module(...)",
        "line 6: import_module(...)",
    ]
    assert string_imports(old, loader=True) == []
    assert module_targets(old, "repair") == [
        "line 2: 'selfrepair.baselines.adapt:start_lpg_adapt'",
        "line 6: 'selfrepair.baselines.unified'",
    ]
    assert module_targets(old, "baselines") == []
    assert string_imports("from selfrepair.baselines import adapt\n", loader=False) == []
