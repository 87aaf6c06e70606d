"""The one skip policy (tests/extras.py): a missing extra skips with the install command, and
fails under SELFREPAIR_REQUIRE_EXTRAS=1, whether asked for with need() or with the mark."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

import extras

SUITE = """
import pytest
from extras import need, needs_extra

@needs_extra("no_such_module_for_selfrepair", extra="fast")
def test_marked():
    pass

@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=needs_extra(
    "no_such_module_for_selfrepair", extra="fast"))])
def test_param(backend):
    pass

def test_called():
    need("no_such_module_for_selfrepair", "fast")
"""


def _run(pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch, required: bool) -> Any:
    monkeypatch.setattr(extras, "REQUIRED", required)
    pytester.makeconftest((Path(__file__).parent / "conftest.py").read_text(encoding="utf-8"))
    pytester.makepyfile(SUITE)
    monkeypatch.syspath_prepend(str(Path(__file__).parent))
    return pytester.runpytest_inprocess("-p", "no:cacheprovider", "-ra")


def test_a_missing_extra_is_skipped_with_the_install_command(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    result = _run(pytester, monkeypatch, required=False)
    result.assert_outcomes(passed=1, skipped=3)
    result.stdout.fnmatch_lines(["*pip install -e '.[[]fast[]]'*"])


def test_a_missing_extra_fails_when_extras_are_required(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    result = _run(pytester, monkeypatch, required=True)
    result.assert_outcomes(passed=1, failed=1, errors=2)
    result.stdout.fnmatch_lines(["*SELFREPAIR_REQUIRE_EXTRAS=1 but the test needs*"])


def test_an_installed_module_is_returned() -> None:
    module, extra = "json", "standard library"  # always there
    assert extras.need(module, extra).dumps([1]) == "[1]"
