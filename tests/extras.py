"""Tests that need an optional extra: skipped with the reason and the install command when it is
missing, unless ``SELFREPAIR_REQUIRE_EXTRAS=1`` (CI installs every extra the tests use and sets
it, so there a missing extra is a failure, not a silent skip)."""

from __future__ import annotations

import importlib
import os
from types import ModuleType

import pytest

REQUIRED = os.environ.get("SELFREPAIR_REQUIRE_EXTRAS") == "1"


def need(module: str, extra: str) -> ModuleType:
    """Import ``module`` (from the ``extra`` extra) or skip the test saying how to install it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        reason = f"needs {module} from the '{extra}' extra: pip install -e '.[{extra}]'"
        if REQUIRED:
            pytest.fail(f"SELFREPAIR_REQUIRE_EXTRAS=1 but the test {reason}")
        pytest.skip(reason)
