"""numba's ``njit`` for the compiled mission loop, or a stand-in without numba (the ``fast``
extra): then :data:`NUMBA` is false, the kernels are never called and every mission runs the
Python loop."""

from __future__ import annotations

from typing import Any

__all__ = ["NUMBA", "njit"]

try:
    from numba import njit

    NUMBA = True
except ImportError:  # pragma: no cover - depends on the environment
    NUMBA = False

    def njit(*args: Any, **kwargs: Any) -> Any:  # type: ignore[no-redef]
        """Stand-in so the modules import without numba (their kernels are then never called)."""
        if args and callable(args[0]):
            return args[0]
        return lambda f: f
