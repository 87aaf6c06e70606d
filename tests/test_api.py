"""The curated public API: ``import selfrepair as sr`` gives the names a user needs, lazily, and
every package and module lists in ``__all__`` only names it has."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

import pytest

import selfrepair as sr
from extras import need

HEAVY = ("numba", "matplotlib", "scipy", "pydantic", "gymnasium")


def test_every_public_name_resolves_to_its_home() -> None:
    names = [n for n in sr.__all__ if n != "__version__"]
    assert names == sorted(names) and len(set(names)) == len(names)
    for name in names:
        home = sr._home(name)
        assert home is not None, name
        value = getattr(sr, name)
        assert value is getattr(home, name), name
    assert sr._home("nonsense") is None
    assert isinstance(sr.__version__, str)
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        _ = sr.nonsense  # type: ignore[attr-defined]


def test_the_names_the_issue_asks_for_are_there() -> None:
    wanted = {
        "run_mission", "MissionSpec", "FaultSchedule", "StrategyOptions", "mission_row", "plan",
        "load_bundled", "get_domain", "register_domain", "register_strategy", "run_team",
    }  # fmt: skip
    assert wanted <= set(sr.__all__)


def test_import_selfrepair_loads_no_heavy_library() -> None:
    code = (
        "import sys, selfrepair\n"
        "selfrepair.__all__, selfrepair.__doc__\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_the_first_use_of_a_name_imports_its_home_only() -> None:
    code = (
        "import sys, selfrepair as sr\n"
        "sr.MissionSpec, sr.FaultSchedule, sr.get_domain\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "matplotlib" not in out.stdout and "scipy" not in out.stdout


def _modules() -> list[str]:
    names = ["selfrepair"]
    for info in pkgutil.walk_packages(sr.__path__, "selfrepair."):
        names.append(info.name)
    return sorted(names)


@pytest.mark.parametrize("name", [n for n in _modules() if n.rsplit(".", 1)[-1] != "__main__"])
def test_every_module_lists_only_names_it_has(name: str) -> None:
    if name.startswith("selfrepair.envs"):
        need("gymnasium", "gym")
    module = importlib.import_module(name)
    exported = getattr(module, "__all__", None)
    if hasattr(module, "__path__"):  # a package
        assert exported is not None, f"package {name} has no __all__"
    for item in exported or ():
        assert hasattr(module, item), f"{name}.__all__ names {item!r}, which it lacks"
