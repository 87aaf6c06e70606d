"""One skip policy for tests that need an optional extra or a platform feature.

A test that needs an extra is skipped with the reason and the install command when the extra is
missing, unless ``SELFREPAIR_REQUIRE_EXTRAS=1`` (set by ``.ci/run``: CI installs every extra the
tests use, so there a missing extra is a failure, not a silent skip). That covers the numba
kernels (whose match with the pure-Python reference must run in CI), LPG (the ``pddl`` extra),
Dask, Parquet, matplotlib and Gymnasium alike.

Two ways to say it:

* inside a test or at the top of a test module, :func:`need` (imports the module or skips /
  fails);
* on a test, a class, a module (``pytestmark``) or a ``pytest.param``, the mark
  :func:`needs_extra`, which ``tests/conftest.py`` applies before the test runs the same way.

Skips for the platform (``sys.platform != "linux"``) stay plain ``skipif``: CI runs on Linux,
where they never skip.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType

import pytest

__all__ = ["LPG", "NUMBA", "REQUIRED", "need", "needs_extra"]

REQUIRED = os.environ.get("SELFREPAIR_REQUIRE_EXTRAS") == "1"


def need(module: str, extra: str) -> ModuleType:
    """Import ``module`` (from the ``extra`` extra) or skip the test saying how to install it
    (fail instead under ``SELFREPAIR_REQUIRE_EXTRAS=1``)."""
    try:
        return importlib.import_module(module)
    except ImportError:
        reason = f"needs {module} from the '{extra}' extra: pip install -e '.[{extra}]'"
        if REQUIRED:
            pytest.fail(f"SELFREPAIR_REQUIRE_EXTRAS=1 but the test {reason}")
        pytest.skip(reason, allow_module_level=True)


def needs_extra(*modules: str, extra: str) -> pytest.MarkDecorator:
    """The mark of a test that needs ``modules`` from ``extra``; see :func:`need`."""
    return pytest.mark.needs_extra(*modules, extra=extra)


NUMBA = needs_extra("numba", extra="fast")
"""The mark of a test of the compiled kernels (numba, from the ``fast`` extra)."""

LPG = needs_extra("unified_planning", "up_lpg", extra="pddl")
"""The mark of a test that runs LPG through unified-planning (the ``pddl`` extra)."""
