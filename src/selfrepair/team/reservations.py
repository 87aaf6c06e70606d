"""The reservation table: which robot holds which cell over which stretch of time.

Time is in integer units (see :attr:`selfrepair.robots.domain.Domain.time_unit`). A reservation is a
half-open interval ``[start, end)`` of one cell for one robot; ``end`` may be :data:`FOREVER`
(a robot parked at the end of its planned path holds its cell until it plans again). A moving
robot holds every cell of its action's footprint (``Domain.footprint``) for the whole duration of
the action, so two robots never share a cell or the cells an action sweeps at the same time:
swaps and overtakes inside one action are conflicts too. A robot that leaves a cell at ``t`` and
another that enters it at ``t`` do not conflict (the intervals are half-open).

This is the table of prioritised, cooperative space-time planning (Silver 2005): each robot plans
its drive around what the others have reserved, then reserves its own path and its parking cell.
The table is mutable by nature (it is the engine's scratch state for one mission); it is never
kept between missions.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from selfrepair.geometry import Cell, Pose

__all__ = ["FOREVER", "Reservations", "TimedStep"]

FOREVER = 1 << 60
"""The end of a reservation that lasts until the robot plans again."""


@dataclass(frozen=True, slots=True)
class TimedStep:
    """One primitive action of a robot placed in time: from ``before`` at ``start`` to ``after``
    at ``end`` (units), sweeping ``cells``."""

    start: int
    end: int
    action: object
    before: Pose
    after: Pose
    cells: tuple[Cell, ...]


class Reservations:
    """Cell reservations of every robot of one mission (see the module docstring)."""

    __slots__ = ("_by_robot", "_cells")

    def __init__(self) -> None:
        self._cells: dict[Cell, list[tuple[int, int, str]]] = {}
        self._by_robot: dict[str, list[tuple[Cell, int, int]]] = {}

    def reserve(self, robot: str, cells: Iterable[Cell], start: int, end: int) -> None:
        """Hold ``cells`` for ``robot`` during ``[start, end)`` (no check: callers check first)."""
        if end <= start:
            return
        mine = self._by_robot.setdefault(robot, [])
        for cell in dict.fromkeys(cells):
            self._cells.setdefault(cell, []).append((start, end, robot))
            mine.append((cell, start, end))

    def reserve_path(self, robot: str, steps: Iterable[TimedStep], park: Pose, at: int) -> None:
        """Reserve every step of a planned path, then ``park``'s cell from ``at`` on."""
        for step in steps:
            self.reserve(robot, step.cells, step.start, step.end)
        self.park(robot, park.cell, at)

    def park(self, robot: str, cell: Cell, at: int) -> None:
        """Hold ``cell`` for ``robot`` from ``at`` until it plans again."""
        self.reserve(robot, (cell,), at, FOREVER)

    def release_from(self, robot: str, at: int) -> None:
        """Drop ``robot``'s reservations from ``at`` on (an interval that spans ``at`` is cut)."""
        kept: list[tuple[Cell, int, int]] = []
        for cell, start, end in self._by_robot.get(robot, []):
            entries = self._cells[cell]
            entries.remove((start, end, robot))
            if start < at:
                new_end = min(end, at)
                entries.append((start, new_end, robot))
                kept.append((cell, start, new_end))
        self._by_robot[robot] = kept

    def forget_before(self, at: int) -> None:
        """Drop every interval that ended by ``at`` (the past no longer matters to planning)."""
        for cell, entries in list(self._cells.items()):
            kept = [e for e in entries if e[1] > at]
            if kept:
                self._cells[cell] = kept
            else:
                del self._cells[cell]
        for robot, mine in self._by_robot.items():
            self._by_robot[robot] = [e for e in mine if e[2] > at]

    def holders(self, cell: Cell, start: int, end: int, robot: str) -> list[tuple[int, int, str]]:
        """Other robots' intervals on ``cell`` that overlap ``[start, end)``."""
        return [
            e for e in self._cells.get(cell, ()) if e[2] != robot and e[0] < end and start < e[1]
        ]

    def free(self, cells: Iterable[Cell], start: int, end: int, robot: str) -> bool:
        """Whether no other robot holds any of ``cells`` during ``[start, end)``."""
        for cell in cells:
            for s, e, who in self._cells.get(cell, ()):
                if who != robot and s < end and start < e:
                    return False
        return True

    def clear_after(self, cells: Iterable[Cell], start: int, end: int, robot: str) -> int:
        """The earliest ``t >= start`` from which no other robot holds ``cells`` during
        ``[t, t + (end - start))``; :data:`FOREVER` when some holder never lets go."""
        length = end - start
        t = start
        cells = tuple(cells)
        while t < FOREVER:
            blocking = [e for c in cells for e in self.holders(c, t, t + length, robot)]
            if not blocking:
                return t
            t = max(e[1] for e in blocking)
        return FOREVER

    def conflicting_robots(self, robot: str) -> set[str]:
        """Robots whose reservations overlap one of ``robot``'s (stale plans to be redone)."""
        out: set[str] = set()
        for cell, start, end in self._by_robot.get(robot, []):
            out.update(e[2] for e in self.holders(cell, start, end, robot))
        return out

    def snapshot(self, robot: str, after: int) -> dict[Cell, list[tuple[int, int]]]:
        """Other robots' intervals that end after ``after``, per cell (for one search)."""
        out: dict[Cell, list[tuple[int, int]]] = {}
        for cell, entries in self._cells.items():
            kept = [(s, e) for s, e, who in entries if who != robot and e > after]
            if kept:
                out[cell] = kept
        return out

    def parked(self, robot: str) -> set[Cell]:
        """Cells other robots hold until they plan again (now or from some time on)."""
        return {
            cell
            for cell, entries in self._cells.items()
            if any(e[2] != robot and e[1] >= FOREVER for e in entries)
        }

    def of_robot(self, robot: str) -> list[tuple[Cell, int, int]]:
        """``robot``'s reservations as ``(cell, start, end)``."""
        return list(self._by_robot.get(robot, []))
