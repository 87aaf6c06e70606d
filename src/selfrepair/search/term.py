"""A cost term per (pose, planning action), as data: what the tolerant planner adds to a plan's
cost (:class:`StepTerm`). It sits in a module of its own, free of mazes and robots, so that the
generic repair layer can build one (:mod:`selfrepair.repair.tolerance_masks`) and the planners
(:mod:`selfrepair.search.lattice`, the kernels) read it."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError

__all__ = ["StepTerm"]


@dataclass(frozen=True, slots=True, eq=False)
class StepTerm:
    """A cost term per (pose, planning action), as data: ``counts[y, x, heading, k]`` is a
    non-negative count for ``actions[k]`` started at ``(x, y, heading)`` (for the tolerant
    planner: the fault sets under which that step would need a replan, see
    :mod:`selfrepair.repair.tolerance_masks`).

    ``penalty`` ``None`` is the **hard** mode: a step with a count above 0 is never taken, so
    the plan found is the cheapest one whose every step counts 0 (``UNSOLVABLE``: none exists).
    A :class:`~fractions.Fraction` is the **soft** mode: each counted unit costs ``penalty``
    ticks, exactly (like the clearance weight). ``actions`` are the planning actions the counts
    were made for (those of :func:`selfrepair.search.lattice.planning_actions` for the faults the
    planner knows); the planner refuses a term made for others. Equality is identity (arrays).
    """

    actions: tuple[object, ...]
    counts: npt.NDArray[np.int32]
    penalty: Fraction | None = None
    label: str = "tolerant"

    def __post_init__(self) -> None:
        shape = self.counts.shape
        if len(shape) != 4 or shape[2] != 4 or shape[3] != len(self.actions):
            raise ProblemError(
                f"step term counts must have shape (height, width, 4, {len(self.actions)}), "
                f"got {shape}"
            )
        if self.penalty is not None and self.penalty < 0:
            raise ProblemError(f"a step term penalty must be >= 0, got {self.penalty}")
        if self.counts.size and int(self.counts.min()) < 0:
            raise ProblemError("step term counts must be >= 0")

    @property
    def hard(self) -> bool:
        """Whether counted steps are forbidden (rather than penalised)."""
        return self.penalty is None
