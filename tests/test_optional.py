"""Optional dependencies: a missing one is a ProblemError naming the extra that brings it."""

from __future__ import annotations

import sys

import pytest

from selfrepair.errors import ProblemError
from selfrepair.optional import import_extra, matplotlib


def test_a_missing_extra_names_its_install_command(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import now raises ImportError
    with pytest.raises(ProblemError) as caught:
        matplotlib()
    assert str(caught.value) == (
        "figures need matplotlib, which is not installed: pip install 'selfrepair[viz]'"
    )


def test_an_installed_module_is_returned() -> None:
    assert import_extra("json", "none", need="tests").__name__ == "json"
