"""The installed package's version, looked up once on first use (reading the installed metadata
costs more than the rest of a quick command's start-up). A ground module, so that a results
store can record the version without importing the package's public API."""

from __future__ import annotations

from functools import cache
from importlib.metadata import PackageNotFoundError, version

__all__ = ["package_version"]


@cache
def package_version() -> str:
    """The version of the installed ``selfrepair`` distribution (``"0.0.0"`` without one)."""
    try:
        return version("selfrepair")
    except PackageNotFoundError:  # pragma: no cover - a source tree without install
        return "0.0.0"
