"""numba's ``njit`` for the compiled mission loop, or a stand-in without numba (the ``fast``
extra): then :data:`NUMBA` is false, the kernels are never called and every mission runs the
Python loop."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["NUMBA", "njit", "no_refcount"]

_Fn = TypeVar("_Fn", bound=Callable[..., Any])

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


def no_refcount(fn: _Fn) -> _Fn:
    """Compile ``fn`` (cached) without numba's reference counting: it allocates nothing, and
    with counting on every array handed to a helper costs atomic updates (a warm hit took ten
    times longer)."""
    options: dict[str, Any] = {"cache": True, "_nrt": False}
    return njit(**options)(fn)  # type: ignore[no-any-return]
