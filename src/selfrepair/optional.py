"""Optional dependencies: import one, or say which extra brings it.

The extras of ``pyproject.toml`` (``viz``, ``dask``, ``ray``, ``gym``, ``pddl``, ...) are imported
only where they are used, so that the rest of the package works without them. A module that needs
one calls :func:`import_extra`, which gives the module or raises a :class:`ProblemError` whose
message names the install command, the same way everywhere.

This module sits at the bottom of the package beside :mod:`selfrepair.errors`.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from selfrepair.errors import ProblemError

__all__ = ["import_extra", "matplotlib"]


def import_extra(module: str, extra: str, *, need: str) -> ModuleType:
    """The module ``module``, or a :class:`ProblemError` saying that ``need`` (what wants it, e.g.
    ``"figures"``) needs it and that ``pip install 'selfrepair[extra]'`` brings it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ProblemError(
            f"{need} need {module}, which is not installed: pip install 'selfrepair[{extra}]'"
        ) from None


def matplotlib() -> ModuleType:
    """matplotlib (the ``viz`` extra), for figures and animations."""
    return import_extra("matplotlib", "viz", need="figures")
