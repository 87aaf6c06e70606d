"""The integer tables that the vector environment's kernel (:mod:`~.envs._vector_kernels`) reads.

Everything here is tabulated from the one world model, never re-derived: motion (end offset, end
heading, time units, footprint) from the domain's move table (:func:`~selfrepair.execution.moves.
move_table`, itself computed by ``Domain.apply``, ``footprint`` and ``duration``), which actions a
fault set leaves available from :func:`~selfrepair.execution.moves.available_moves` (that is,
``Domain.available``, as the simulator asks it), and which faults a failed attempt reveals from
``Domain.blocking``; with hidden faults, what a command really does from ``Domain.effective``
(the simulator's rule). The fault sets are numbered as they are first met (:class:`FaultSets`); the
mazes of all robots share one padded byte buffer (:class:`GridStore`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError
from selfrepair.execution.moves import MoveTable, available_moves, move_table
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS
from selfrepair.robots.domain import SomeDomain
from selfrepair.world.maze import Maze

__all__ = ["MAX_FAULTS", "FaultSets", "GridStore", "MotionTables", "motion_tables"]

MAX_FAULTS = 64
"""The most faults a domain may have for the vector environment (known faults are a 64-bit
mask)."""


@dataclass(frozen=True, slots=True, eq=False)
class MotionTables:
    """A domain's motion as arrays (see :mod:`selfrepair.envs._vector_kernels` for the columns):
    ``moves[a, h]`` = (dx, dy, end heading, time units), ``footprints[a, h]`` = (cell count, then
    the cells as dx, dy pairs), ``durations[a]`` the duration in ticks as the single environment's
    float, ``failed_units`` a failed attempt's time units; ``table`` is the move table they come
    from and ``reach`` the padding a footprint needs."""

    table: MoveTable
    moves: npt.NDArray[np.int64]
    footprints: npt.NDArray[np.int64]
    durations: npt.NDArray[np.float64]
    failed_units: int
    reach: int


def motion_tables(domain: SomeDomain) -> MotionTables:
    """The :class:`MotionTables` of ``domain``; a :class:`ProblemError` for a domain the kernel
    cannot take (a move that can end off its own footprint, or more than :data:`MAX_FAULTS`
    faults)."""
    table = move_table(domain, 1)
    if not table.ends_covered:
        raise ProblemError(
            f"the vector environment needs every move of the {domain.name!r} robot to end on a "
            "cell of its footprint; use gymnasium.vector.SyncVectorEnv for this robot"
        )
    if len(domain.faults) > MAX_FAULTS:
        raise ProblemError(
            f"the vector environment takes at most {MAX_FAULTS} faults, the {domain.name!r} robot "
            f"has {len(domain.faults)}; use gymnasium.vector.SyncVectorEnv for this robot"
        )
    count = len(domain.actions)
    widest = max(len(shape) for shapes in table.shapes.values() for shape in shapes)
    moves = np.zeros((count, 4, 4), dtype=np.int64)
    footprints = np.zeros((count, 4, 1 + 2 * widest), dtype=np.int64)
    durations = np.zeros(count, dtype=np.float64)
    for index, action in enumerate(domain.actions):
        durations[index] = float(table.moves[action][0].duration)
        for heading, (move, shape) in enumerate(
            zip(table.moves[action], table.shapes[action], strict=True)
        ):
            moves[index, heading] = (move.dx, move.dy, int(move.heading), move.units)
            footprints[index, heading, 0] = len(shape)
            for c, (dx, dy) in enumerate(shape):
                footprints[index, heading, 1 + 2 * c] = dx
                footprints[index, heading, 2 + 2 * c] = dy
    failed = FAILED_ATTEMPT_TICKS * table.unit
    assert failed.denominator == 1
    return MotionTables(table, moves, footprints, durations, int(failed), table.reach)


class FaultSets:
    """Fault sets numbered in the order first met, with per set the faults as a bit mask over
    ``domain.faults``, which actions are available (``avail``) and, per action, the faults that
    forbid it on their own (``blocking``, a mask). Mutable: the arrays grow as sets are met."""

    def __init__(
        self,
        domain: SomeDomain,
        table: MoveTable,
        hidden: bool = False,
        behaviour: str | None = None,
    ) -> None:
        self.domain = domain
        self.table = table
        self.hidden = hidden
        self.behaviour = behaviour
        self.index = {action: i for i, action in enumerate(domain.actions)}
        self.bit_of = {fault: i for i, fault in enumerate(domain.faults)}
        self._ids: dict[frozenset[object], int] = {}
        count = len(domain.actions)
        self.set_bits = np.zeros(16, dtype=np.uint64)
        self.avail = np.zeros((16, count), dtype=np.uint8)
        self.blocking = np.zeros((16, count), dtype=np.uint64)
        self.effective = np.zeros((16, count), dtype=np.int64)

    def __len__(self) -> int:
        return len(self._ids)

    def mask(self, faults: frozenset[object]) -> int:
        """``faults`` as a bit mask over ``domain.faults``."""
        return sum(1 << self.bit_of[f] for f in faults)

    def faults_of(self, mask: int) -> frozenset[object]:
        """The faults of bit mask ``mask``."""
        return frozenset(f for f, i in self.bit_of.items() if mask >> i & 1)

    def id_of(self, faults: frozenset[object]) -> int:
        """The number of fault set ``faults`` (tabulated when first met)."""
        sid = self._ids.get(faults)
        if sid is not None:
            return sid
        sid = len(self._ids)
        if sid == len(self.set_bits):
            self.set_bits = np.concatenate([self.set_bits, np.zeros_like(self.set_bits)])
            self.avail = np.concatenate([self.avail, np.zeros_like(self.avail)])
            self.blocking = np.concatenate([self.blocking, np.zeros_like(self.blocking)])
            self.effective = np.concatenate([self.effective, np.zeros_like(self.effective)])
        available = available_moves(self.table, faults)
        domain = self.domain
        self.set_bits[sid] = self.mask(faults)
        for index, action in enumerate(domain.actions):
            self.avail[sid, index] = action in available
            self.blocking[sid, index] = self.mask(domain.blocking(action, faults))
            self.effective[sid, index] = self._effective(action, faults, action in available)
        self._ids[faults] = sid
        return sid

    def _effective(self, action: object, faults: frozenset[object], available: bool) -> int:
        """With hidden faults, the index of the action the wheels perform when ``action`` is
        commanded under ``faults`` (``Domain.effective``), or -1 when the command fails (a
        forbidden action of a domain without a fault-behaviour model); else the action's own."""
        if available or not self.hidden:
            return self.index[action]
        if not self.domain.behaviours:
            return -1
        return self.index[self.domain.effective(action, faults, self.behaviour)]


class GridStore:
    """Every robot's maze as free (1) and wall (0) bytes in one flat buffer, each maze padded with
    ``margin`` wall cells. The mazes of the environment's fixed sources are stored once and shared;
    any other maze (a generated one, one given by a reset option) goes to the robot's own region,
    which grows (the buffer is rebuilt) when a larger maze comes. Mutable."""

    def __init__(self, fixed: tuple[Maze, ...], robots: int, margin: int, region: int) -> None:
        self.margin = margin
        self._fixed = fixed
        self._robots = robots
        self._own: list[Maze | None] = [None] * robots
        parts = [self._padded(maze) for maze in fixed]
        self._starts = [0]
        for part in parts:
            self._starts.append(self._starts[-1] + part.size)
        self._fixed_bytes = np.concatenate(parts) if parts else np.zeros(0, dtype=np.uint8)
        self._region = region
        self.grid = self._build()

    def _padded(self, maze: Maze) -> npt.NDArray[np.uint8]:
        data = maze.free_grid(self.margin).data
        return np.frombuffer(data, dtype=np.uint8)

    def _size(self, maze: Maze) -> int:
        side = 2 * self.margin
        return (maze.width + side) * (maze.height + side)

    def _build(self) -> npt.NDArray[np.uint8]:
        grid = np.zeros(self._fixed_bytes.size + self._robots * self._region, dtype=np.uint8)
        grid[: self._fixed_bytes.size] = self._fixed_bytes
        for robot, maze in enumerate(self._own):
            if maze is not None:
                start = self._own_start(robot)
                grid[start : start + self._size(maze)] = self._padded(maze)
        return grid

    def _own_start(self, robot: int) -> int:
        return self._fixed_bytes.size + robot * self._region

    def _layout(self, maze: Maze) -> tuple[int | None, int, int]:
        """Where ``maze`` is stored if it is a fixed source's (else ``None``), its row stride,
        and the offset of its cell ``(0, 0)`` from the start of its padded bytes."""
        stride = maze.width + 2 * self.margin
        pad = self.margin * stride + self.margin
        for index, fixed in enumerate(self._fixed):
            if fixed is maze:
                return self._starts[index], stride, pad
        return None, stride, pad

    def place(self, robot: int, maze: Maze) -> tuple[int, int, bool]:
        """Store ``maze`` for ``robot``; the buffer index of its cell ``(0, 0)``, its row stride,
        and whether the buffer was rebuilt (every robot with a maze of its own then moved)."""
        start, stride, pad = self._layout(maze)
        if start is not None:
            self._own[robot] = None
            return start + pad, stride, False
        rebuilt = False
        self._own[robot] = maze
        if self._size(maze) > self._region:
            self._region = max(self._size(maze), 2 * self._region)
            self.grid = self._build()
            rebuilt = True
        else:
            start = self._own_start(robot)
            self.grid[start : start + self._size(maze)] = self._padded(maze)
        return self._own_start(robot) + pad, stride, rebuilt

    def base_of(self, robot: int, maze: Maze) -> int:
        """The buffer index of cell ``(0, 0)`` of ``robot``'s maze ``maze`` (already placed)."""
        start, _, pad = self._layout(maze)
        if start is None:
            if self._own[robot] is not maze:
                raise ProblemError(f"robot {robot}'s maze is not stored")
            start = self._own_start(robot)
        return start + pad
