"""numba's ``njit``, or a stand-in without numba (the ``fast`` extra): the one optional import of
numba for every kernel module (the planner's, D* Lite's, the mission loop's and the vector
environment's). Without numba :data:`NUMBA` is false, ``njit`` returns the function itself and
the callers run their pure-Python references instead of the kernels. Imported only by kernel
modules, so that numba's import cost is paid only where a kernel may run."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["NUMBA", "njit", "no_refcount"]

_Fn = TypeVar("_Fn", bound=Callable[..., object])

try:
    from numba import njit

    NUMBA = True
except ImportError:  # pragma: no cover - depends on the environment
    NUMBA = False

    def njit(*args: Any, **kwargs: Any) -> Any:  # type: ignore[no-redef]
        """Stand-in so the kernel modules import without numba (their kernels are then never
        called, or run as plain Python where a module says so)."""
        if args and callable(args[0]):
            return args[0]
        return lambda f: f


def no_refcount(fn: _Fn) -> _Fn:
    """Compile ``fn`` (cached) without numba's reference counting: it allocates nothing, and
    with counting on every array handed to a helper costs atomic updates (a warm hit took ten
    times longer)."""
    options: dict[str, Any] = {"cache": True, "_nrt": False}
    return njit(**options)(fn)  # type: ignore[no-any-return]
