"""Which search backend runs: the pure-Python reference or the compiled numba kernels.

``"python"`` is the reference; ``"numba"`` the kernels of :mod:`selfrepair.search._kernels`
(optional: installed with the ``fast`` extra); ``"auto"`` uses numba when it is importable and
the robot fits the kernels. Importing this module does not import numba: only asking whether it
is available does.

The lattice kernels take a robot whose every action, from every heading, ends and sweeps within
the 3x3 cells around the robot, with at most 255 motion classes (:func:`kernel_refusal` says why
a robot does not fit). For another robot ``"auto"`` runs the pure-Python planner, which gives the
same plans, and the result rows say so (:func:`backend_ran`); an explicit ``"numba"`` is refused
with the reason rather than silently run on the reference.
"""

from __future__ import annotations

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.astar import BACKENDS
from selfrepair.search.openmoves import open_moves

__all__ = ["BACKENDS", "backend_ran", "kernel_refusal", "numba_available", "use_numba"]

MAX_KERNEL_CLASSES = 255
"""Most motion classes (planning actions) the lattice kernels index."""


def numba_available() -> bool:
    """Whether the compiled kernels can be used (numba is importable; imported on the first
    call, see :mod:`selfrepair.jit`)."""
    from selfrepair import jit

    return jit.NUMBA


_REFUSALS: BoundedCache[SomeDomain, str | None] = BoundedCache(
    "kernel refusals", 16, kind=CacheKind.PLAN
)
""":func:`kernel_refusal` by domain (a process knows a few domains)."""


def kernel_refusal(domain: SomeDomain) -> str | None:
    """Why the compiled lattice kernels cannot plan for ``domain`` (one line), or ``None`` when
    they can: an action that ends or sweeps outside the 3x3 cells around the robot from some
    heading, or more than :data:`MAX_KERNEL_CLASSES` motion classes. Checked once per domain."""
    return _REFUSALS.get(domain, lambda: _refusal(domain))


_NINE = frozenset((x, y) for x in (-1, 0, 1) for y in (-1, 0, 1))
"""The 3x3 cells around the robot, relative to its cell."""


def _refusal(domain: SomeDomain) -> str | None:
    classes = len({domain.motion_class(a) for a in domain.actions})
    if classes > MAX_KERNEL_CLASSES:
        return f"it has {classes} motion classes, more than the kernels' {MAX_KERNEL_CLASSES}"
    moves = open_moves(domain)
    reached = {(dx, dy) for per in moves.ends for dx, dy, _ in per}
    reached.update(cell for per in moves.footprints for cells in per for cell in cells)
    if reached <= _NINE:  # the usual answer, in one set comparison
        return None
    for i, action in enumerate(domain.actions):
        for heading, (dx, dy, _), footprint in zip(
            Heading, moves.ends[i], moves.footprints[i], strict=True
        ):
            cells = ((dx, dy), *footprint)
            if any(x < -1 or x > 1 or y < -1 or y > 1 for x, y in cells):
                return (
                    f"action {domain.format_action(action)} facing {heading.name} leaves the 3x3 "
                    "cells around the robot"
                )
    return None


def use_numba(backend: str, domain: SomeDomain | None = None) -> bool:
    """Whether ``backend`` (already checked to be one of :data:`BACKENDS`) means the kernels, for
    the robot ``domain`` when one is given (searches over cells alone give none).

    Raises :class:`ProblemError` when ``"numba"`` is asked for but numba is not installed, or
    the kernels cannot take ``domain`` (:func:`kernel_refusal`); ``"auto"`` then means the
    pure-Python planner.
    """
    if backend == "python":
        return False
    if backend == "numba":
        if not numba_available():
            raise ProblemError("backend 'numba' requested but numba is not installed")
        reason = None if domain is None else kernel_refusal(domain)
        if domain is not None and reason is not None:
            raise ProblemError(
                f"backend 'numba' cannot plan for the {domain.name} robot: {reason} (the "
                "compiled planner takes moves within those cells only); use backend auto or "
                "python"
            )
        return True
    return numba_available() and (domain is None or kernel_refusal(domain) is None)


def backend_ran(backend: str, domain: SomeDomain) -> str:
    """The backend that plans for ``domain`` when ``backend`` is asked for: ``"numba"`` or
    ``"python"`` (raises as :func:`use_numba` does)."""
    return "numba" if use_numba(backend, domain) else "python"
