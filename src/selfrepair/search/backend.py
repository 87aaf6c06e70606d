"""Which search backend runs: the pure-Python reference or the compiled numba kernels.

``"python"`` is the reference; ``"numba"`` the kernels of :mod:`selfrepair.search._kernels`
(optional: installed with the ``fast`` extra); ``"auto"`` uses numba when it is importable.
Importing this module does not import numba: only asking whether it is available does.
"""

from __future__ import annotations

from selfrepair.errors import ProblemError
from selfrepair.search.astar import BACKENDS

__all__ = ["BACKENDS", "numba_available", "use_numba"]


def numba_available() -> bool:
    """Whether the compiled kernels of :mod:`selfrepair.search._kernels` can be used (numba is
    importable)."""
    from selfrepair.search import _kernels

    return _kernels.NUMBA


def use_numba(backend: str) -> bool:
    """Whether ``backend`` (already checked to be one of :data:`BACKENDS`) means the kernels.

    Raises :class:`ProblemError` when ``"numba"`` is asked for but numba is not installed.
    """
    if backend == "python":
        return False
    if backend == "numba":
        if not numba_available():
            raise ProblemError("backend 'numba' requested but numba is not installed")
        return True
    return numba_available()
