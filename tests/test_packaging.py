"""What `make demo` and `make test` install: only the extras they need (no gymnasium, Dask or
pyarrow), and every extra a test needs is either installed by `make test` or added by CI."""

from __future__ import annotations

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
    for stamp in ("DEMO_STAMP", "STAMP"):
        names = installed_by(stamp)
        assert not names & {"gymnasium", "dask", "pyarrow", "ray"}, (stamp, names)
    assert {"numba", "matplotlib"} <= installed_by("DEMO_STAMP")
    assert {"pytest", "mypy", "ruff", "selenium", "numba", "matplotlib"} <= installed_by("STAMP")


def test_demo_and_test_targets_use_their_stamps() -> None:
    assert re.search(r"^demo: \$\(DEMO_STAMP\)", MAKEFILE, re.M)
    assert re.search(r"^lint: \$\(STAMP\)", MAKEFILE, re.M)


def test_ci_installs_and_requires_the_extras_the_tests_skip_without() -> None:
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "SELFREPAIR_REQUIRE_EXTRAS=1" in ci
    installed = set().union(*(requirements(e) for e in re.findall(r"-e '\.\[([^\]]+)\]'", ci)))
    used = set()
    for test in (ROOT / "tests").glob("test_*.py"):
        used |= set(re.findall(r'need\("[\w.]+", "(\w+)"\)', test.read_text(encoding="utf-8")))
    assert used, "no test declares an extra"
    for extra in used:
        assert requirements(extra) <= installed, extra


def test_dev_brings_every_extra_but_ray() -> None:
    dev = requirements("dev")
    for extra in set(EXTRAS) - {"dev", "ray"}:
        assert requirements(extra) <= dev, extra
