"""Test-suite hooks: the ``needs_extra`` mark of :mod:`extras` (one skip policy)."""

from __future__ import annotations

import pytest

from extras import need

pytest_plugins = ("pytester",)  # tests/test_extras.py runs small suites under the policy


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "needs_extra(*modules, extra): skipped without the extra, failed under "
        "SELFREPAIR_REQUIRE_EXTRAS=1 (tests/extras.py)",
    )


def pytest_runtest_setup(item: pytest.Item) -> None:
    for mark in item.iter_markers(name="needs_extra"):
        for module in mark.args:
            need(module, mark.kwargs["extra"])
