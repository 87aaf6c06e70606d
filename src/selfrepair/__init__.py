"""selfrepair: self-repairing robot plans.

A robot executes a plan; when an actuator fault makes some actions unavailable, a replacement
system swaps each faulty action for a precomputed sub-plan with the same start and end state,
falling back to replanning only when no replacement fits. See the README for the big picture.

``selfrepair.__version__`` is looked up on first use (reading the installed metadata costs more
than the rest of a quick command's start-up).
"""

from __future__ import annotations

__all__ = ["__version__"]


def __getattr__(name: str) -> str:
    if name != "__version__":
        raise AttributeError(f"module 'selfrepair' has no attribute {name!r}")
    from importlib.metadata import PackageNotFoundError, version

    try:
        found = version("selfrepair")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
        found = "0.0.0"
    globals()["__version__"] = found
    return found
