"""The trace of a compiled mission, read from the kernel's trace rows: :class:`ArrayTrace`.

The Python loop records one :class:`~selfrepair.execution.result.TraceStep` per step as it goes;
the compiled loop writes one integer row per step (``tr``, columns ``T_*`` of
:mod:`selfrepair.execution.compiled.kernel`). Making a ``TraceStep`` and two ``Pose`` values for
every row once the mission had ended cost more than the kernel's whole run on the paper's
missions, and an experiment never reads them: its row needs the number of steps and of waits,
which the rows give directly. So the compiled mission's result keeps the rows, and
:class:`ArrayTrace` makes the steps from them when they are read (indexing, iterating, comparing),
each time, the same values the Python loop would have recorded.
"""

from __future__ import annotations

import operator
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, overload

import numpy as np
import numpy.typing as npt

from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.result import StepSource, TraceStep
from selfrepair.geometry import Heading, Pose, make_pose

__all__ = ["ArrayTrace"]

SOURCES = (
    StepSource.PLAN,
    StepSource.REPLACEMENT,
    StepSource.REPLAN,
    StepSource.FAILED_ATTEMPT,
    StepSource.WAIT,
    StepSource.LOOKAHEAD,
)
"""The step source of each kernel source code (``k.SRC_*``)."""

_HEADINGS = tuple(Heading)


@dataclass(frozen=True, slots=True, eq=False)
class ArrayTrace(Sequence[TraceStep]):
    """The steps of a compiled mission as a read-only sequence of
    :class:`~selfrepair.execution.result.TraceStep`, made from the kernel's rows when read.

    ``rows`` holds one row per step (``k.T_COLS`` columns, read-only); ``actions`` are the
    domain's actions by index, ``known`` the fault set of each known mask in the rows and
    ``unit`` the domain's time unit (a duration is ``Fraction(units, unit)``). It equals any
    sequence of the same steps (a tuple of the Python loop's steps, say) and hashes like the
    tuple of its steps."""

    rows: npt.NDArray[np.int64]
    actions: tuple[object, ...]
    known: Mapping[int, frozenset[object]]
    unit: int

    @classmethod
    def of(
        cls,
        rows: npt.NDArray[np.int64],
        actions: tuple[object, ...],
        known: Mapping[int, frozenset[object]],
        unit: int,
    ) -> ArrayTrace:
        """A trace over a read-only copy of ``rows`` (the kernel's buffer is reused)."""
        own = np.array(rows, dtype=np.int64, copy=True)
        own.flags.writeable = False
        return cls(own, actions, known, unit)

    def __len__(self) -> int:
        return int(self.rows.shape[0])

    @overload
    def __getitem__(self, index: int) -> TraceStep: ...

    @overload
    def __getitem__(self, index: slice) -> tuple[TraceStep, ...]: ...

    def __getitem__(self, index: int | slice) -> TraceStep | tuple[TraceStep, ...]:
        if isinstance(index, slice):
            return tuple(self._steps(self.rows[index]))
        n = len(self)
        i = operator.index(index)
        i = i + n if i < 0 else i
        if not 0 <= i < n:
            raise IndexError(f"trace index {index} out of range for {n} steps")
        return next(self._steps(self.rows[i : i + 1]))

    def __iter__(self) -> Iterator[TraceStep]:
        return self._steps(self.rows)

    def _steps(self, rows: npt.NDArray[np.int64]) -> Iterator[TraceStep]:
        actions, known, unit = self.actions, self.known, self.unit
        poses: dict[int, Pose] = {}
        durations: dict[int, Fraction] = {}

        def pose(x: int, y: int, h: int) -> Pose:
            key = (y << 34) | (x << 2) | h
            found = poses.get(key)
            if found is None:
                found = poses[key] = make_pose(x, y, _HEADINGS[h])
            return found

        for step, a, x, y, h, ex, ey, eh, units, source, mask in rows.tolist():
            duration = durations.get(units)
            if duration is None:
                duration = durations[units] = Fraction(units, unit)
            yield TraceStep(step, actions[a], pose(x, y, h), pose(ex, ey, eh), duration,
                            SOURCES[source], known[mask])  # fmt: skip

    def count_source(self, source: StepSource) -> int:
        """How many steps have ``source`` (read from the rows, no step made)."""
        if source not in SOURCES:
            return 0
        return int(np.count_nonzero(self.rows[:, k.T_SOURCE] == SOURCES.index(source)))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Sequence) or isinstance(other, str | bytes):
            return NotImplemented
        if len(other) != len(self):
            return False
        return all(a == b for a, b in zip(self, other, strict=True))

    def __hash__(self) -> int:
        return hash(tuple(self))

    def __repr__(self) -> str:
        return f"ArrayTrace({len(self)} steps)"

    def __reduce__(self) -> tuple[Any, ...]:
        return (ArrayTrace.of, (self.rows, self.actions, dict(self.known), self.unit))
