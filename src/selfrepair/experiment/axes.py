"""Factor axes: an experiment's missions are the cross product of named value lists.

Single-robot experiments (:func:`selfrepair.experiment.missions.expand`) cross routes, fault
sets, fault times, detections, replicates and strategy variants; team experiments
(:mod:`selfrepair.experiment.teams`) cross team sizes, loads, equipment and replicates. Both
expand through :func:`cross`, one :func:`itertools.product` whose last axis varies fastest, so the
order of missions is defined by the order of the axes and of their values.

Both count their missions with :func:`total` and say how the count comes about with
:func:`describe`, over the same axes, before any mission is built. A factor whose values cannot
be built yet (the routes of maze files not read) enters the count as a :class:`Tally`: its name
and its size alone.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["Axis", "Factor", "Tally", "cross", "describe", "total"]


@dataclass(frozen=True, slots=True)
class Axis:
    """One factor of an experiment: ``name`` (the key in each point of :func:`cross`), its
    ``values`` in order, and ``what`` they are, in the plural, for messages ("fault sets").

    An axis whose only value is ``None`` stands for a section the experiment does not have (no
    ``[world]``, no ``[physics]``): it multiplies by one and :func:`describe` leaves it out."""

    name: str
    values: tuple[object, ...]
    what: str

    @property
    def size(self) -> int:
        """How many values the axis has."""
        return len(self.values)


@dataclass(frozen=True, slots=True)
class Tally:
    """A factor counted from the configuration before its values are built: ``what`` it
    counts, in the plural, and its ``size``."""

    what: str
    size: int


Factor = Axis | Tally
"""What :func:`total` and :func:`describe` multiply."""


def cross(axes: Sequence[Axis]) -> Iterator[dict[str, Any]]:
    """Every combination of one value per axis, as ``{axis name: value}``, the last axis
    varying fastest (the order of nested loops written in the order of ``axes``)."""
    names = [axis.name for axis in axes]
    for values in itertools.product(*(axis.values for axis in axes)):
        yield dict(zip(names, values, strict=True))


def total(factors: Sequence[Factor]) -> int:
    """How many points :func:`cross` gives: the product of the factors' sizes."""
    return math.prod(factor.size for factor in factors)


def describe(factors: Sequence[Factor]) -> str:
    """How :func:`total` comes about, for a message: ``"routes 16 x fault sets 12"`` (an absent
    section's axis left out, see :class:`Axis`)."""
    return " x ".join(
        f"{factor.what} {factor.size:,}" for factor in factors if not _absent(factor)
    )


def _absent(factor: Factor) -> bool:
    return isinstance(factor, Axis) and factor.values == (None,)
