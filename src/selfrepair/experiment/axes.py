"""Factor axes: an experiment's missions are the cross product of named value lists.

Single-robot experiments (:func:`selfrepair.experiment.missions.expand`) cross routes, fault
sets, fault times, detections, replicates and strategy variants; team experiments
(:mod:`selfrepair.experiment.teams`) cross team sizes, loads, equipment and replicates. Both
expand through :func:`cross`, one :func:`itertools.product` whose last axis varies fastest, so the
order of missions is defined by the order of the axes and of their values.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["Axis", "cross", "describe", "total"]


@dataclass(frozen=True, slots=True)
class Axis:
    """One factor of an experiment: ``name`` (the key in each point of :func:`cross`), its
    ``values`` in order, and ``what`` they are, in the plural, for messages ("fault sets")."""

    name: str
    values: tuple[object, ...]
    what: str


def cross(axes: Sequence[Axis]) -> Iterator[dict[str, Any]]:
    """Every combination of one value per axis, as ``{axis name: value}``, the last axis
    varying fastest (the order of nested loops written in the order of ``axes``)."""
    names = [axis.name for axis in axes]
    for values in itertools.product(*(axis.values for axis in axes)):
        yield dict(zip(names, values, strict=True))


def total(axes: Sequence[Axis]) -> int:
    """How many points :func:`cross` gives: the product of the axes' lengths."""
    return math.prod(len(axis.values) for axis in axes)


def describe(axes: Sequence[Axis]) -> str:
    """How :func:`total` comes about, for a message: ``"routes 16 x fault sets 12"``."""
    return " x ".join(f"{axis.what} {len(axis.values):,}" for axis in axes)
