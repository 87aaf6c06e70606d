"""selfrepair: self-repairing robot plans.

A robot executes a plan; when an actuator fault makes some actions unavailable, a replacement
system swaps each faulty action for a precomputed sub-plan with the same start and end state,
falling back to replanning only when no replacement fits. See the README for the big picture.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("selfrepair")
except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
    __version__ = "0.0.0"

__all__ = ["__version__"]
