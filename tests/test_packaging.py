"""What `make demo` and `make test` install: only the extras they need (no gymnasium, Dask or
pyarrow), and every extra a test needs is either installed by `make test` or added by CI."""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
EXTRAS: dict[str, list[str]] = PYPROJECT["project"]["optional-dependencies"]
MAKEFILE = (ROOT / "Makefile").read_text(encoding="utf-8")


def requirements(extras: str) -> set[str]:
    """The distribution names an ``-e '.[extras]'`` install brings, self-references expanded."""
    names: set[str] = set()
    for extra in extras.split(","):
        for requirement in EXTRAS[extra.strip()]:
            inner = re.fullmatch(r"selfrepair\[(.+)\]", requirement)
            if inner:
                names |= requirements(inner.group(1))
            else:
                names.add(re.split(r"[\[<>=!~ ]", requirement, maxsplit=1)[0].lower())
    return names


def installed_by(stamp: str) -> set[str]:
    """What the recipe of a Makefile stamp target installs."""
    recipe = re.search(rf"^\$\({stamp}\):.*\n((?:\t.*\n)+)", MAKEFILE, re.M)
    assert recipe is not None, stamp
    found = re.findall(r"-e '\.\[([^\]]+)\]'", recipe.group(1))
    assert found, f"{stamp} installs no extras"
    return set().union(*(requirements(e) for e in found))


def test_demo_and_test_install_no_unused_extra() -> None:
    demo, test = installed_by("DEMO_STAMP"), installed_by("STAMP")
    assert not demo & {"gymnasium", "scipy", "dask", "pyarrow", "ray"}, demo
    assert not test & {"dask", "pyarrow", "ray"}, test  # their tests skip (CI adds them)
    assert {"numba", "matplotlib"} <= demo
    assert {"pytest", "mypy", "ruff", "selenium", "numba", "matplotlib"} <= test


EXTRA_OF = {
    "numba": "fast",
    "matplotlib": "viz",
    "PIL": "viz",
    "gymnasium": "gym",
    "scipy": "gym",
    "distributed": "dask",
    "dask": "dask",
    "pyarrow": "parquet",
    "ray": "ray",
    "unified_planning": "pddl",
    "up_lpg": "pddl",
    "selenium": "test",
    "hypothesis": "test",
    "mujoco": "physics",
    "imageio": "physics",
}


def test_make_test_installs_what_tests_import_unconditionally() -> None:
    """A test module that imports an extra's library at its top runs (and fails without it)
    instead of skipping, so `make test` must install that extra."""
    test = installed_by("STAMP")
    for path in sorted((ROOT / "tests").glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            modules = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom)
                else []
            )
            for module in modules:
                extra = EXTRA_OF.get(module.split(".")[0])
                if extra is not None:
                    assert requirements(extra) <= test, (path.name, module, extra)


def test_demo_and_test_targets_use_their_stamps() -> None:
    assert re.search(r"^demo: \$\(DEMO_STAMP\)", MAKEFILE, re.M)
    assert re.search(r"^lint: \$\(STAMP\)", MAKEFILE, re.M)


def test_ci_installs_and_requires_the_extras_the_tests_skip_without() -> None:
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "SELFREPAIR_REQUIRE_EXTRAS=1" in ci
    installed = set().union(*(requirements(e) for e in re.findall(r"-e '\.\[([^\]]+)\]'", ci)))
    used = set()
    for test in [*(ROOT / "tests").glob("test_*.py"), ROOT / "tests" / "extras.py"]:
        text = test.read_text(encoding="utf-8")
        used |= set(re.findall(r'need\("[\w.]+", "(\w+)"\)', text))
        used |= set(re.findall(r'needs_extra\([^)]*extra="(\w+)"\)', text))  # tests/extras.py marks
    assert used, "no test declares an extra"
    for extra in used:
        assert requirements(extra) <= installed, extra


def test_dev_brings_every_extra_but_ray() -> None:
    dev = requirements("dev")
    for extra in set(EXTRAS) - {"dev", "ray"}:
        assert requirements(extra) <= dev, extra
