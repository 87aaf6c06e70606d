"""The team trace format: its name and version, and the parsed trace's values.

A team trace has one JSON object per line, like a single-robot trace
(:mod:`selfrepair.execution.trace`) but for several robots:

1. a header (``"type": "header"``, ``"format": "selfrepair-team-trace"``, ``"version"``): the
   robot ``domain`` (and, for a plug-in robot, ``plugin``: the path and SHA-256 of its file,
   which the reader loads when it still has that content), ``scale`` (time units per tick),
   the scenario's name and file
   (``scenario_file``: ``path`` and ``sha256`` of its text, so that the header can be checked
   against the file), the maze (name, rows and ``sha256`` of the rows, one a line), the robots
   (name, start pose, gripper), the tasks, the team faults, the world events and sensing
   (``world``, as a single-robot trace writes them; absent when the world never changes), the
   options, the robots' own table as used (``robot_table``) and the initial team plan (each
   robot's actions as text);
2. event lines in time order (times in units): ``fault`` (fault ``index`` became ``active`` or
   cleared), ``incident`` (robot, action, kind, load), ``repair`` (what the team strategy did:
   outcome, source, candidate, helper, pre-emption, disturbed robots, messages, plans, latency,
   the actions inserted per robot, items given up), ``own-repair`` (a robot's own single-robot
   repair), ``act`` (a pick, drop or handover with the cells its robots stood on) and ``move``
   (one primitive action of one robot: ``robot``, ``start``, ``end``, ``action``, ``from``,
   ``to`` as ``[x, y, "N"]``, ``source``: a ``failed-attempt`` or a ``bumped`` command moves
   nothing and lasts one tick);
3. the summary (``"type": "summary"``): the row of :func:`selfrepair.team.metrics.team_row`.

Written by :mod:`selfrepair.team.tracewrite`, read by :mod:`selfrepair.team.traceread`,
re-simulated by :mod:`selfrepair.team.replay`. Version 1 traces (before the file digests) are
still read; their header cannot be checked against a file.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from selfrepair.execution.traceformat import pose_json
from selfrepair.geometry import Cell
from selfrepair.team.model import TeamScenario
from selfrepair.team.result import ActRecord, FaultRecord, MoveRecord, TeamOptions

__all__ = [
    "TEAM_TRACE_FORMAT",
    "TEAM_TRACE_VERSION",
    "TEAM_TRACE_VERSIONS",
    "TeamTrace",
    "TraceAct",
    "TraceFault",
    "TraceMove",
    "cell_json",
    "maze_digest",
    "pose_json",
]

TEAM_TRACE_FORMAT = "selfrepair-team-trace"
"""The header's ``format``."""
TEAM_TRACE_VERSION = 2
"""The version written (2: the header records the scenario file and the maze's digest)."""
TEAM_TRACE_VERSIONS = (1, 2)
"""The versions read."""


def cell_json(cell: Cell) -> list[int]:
    """A cell as the trace writes it: ``[x, y]``."""
    return [cell[0], cell[1]]


def maze_digest(rows: Sequence[str]) -> str:
    """The SHA-256 of a maze's rows, one a line (each ending in a newline)."""
    return hashlib.sha256("".join(f"{r}\n" for r in rows).encode("utf-8")).hexdigest()


@dataclass(frozen=True, slots=True)
class TraceMove(MoveRecord):
    """A ``move`` line, read back: the move and the ``line`` it stood on."""

    line: int


@dataclass(frozen=True, slots=True)
class TraceAct(ActRecord):
    """An ``act`` line, read back: the act and the ``line`` it stood on."""

    line: int


@dataclass(frozen=True, slots=True)
class TraceFault(FaultRecord):
    """A ``fault`` line, read back: the fault record and the ``line`` it stood on."""

    line: int


@dataclass(frozen=True, slots=True)
class TeamTrace:
    """A parsed team trace: the scenario and options rebuilt from the header, the scale, every
    event line (``other`` keeps incident, repair and own-repair lines as read, with their line
    numbers in ``other_lines``) and the summary."""

    source: str
    scenario: TeamScenario
    options: TeamOptions
    scale: int
    header: Mapping[str, Any]
    moves: tuple[TraceMove, ...]
    acts: tuple[TraceAct, ...]
    faults: tuple[TraceFault, ...]
    other: tuple[Mapping[str, Any], ...]
    summary: Mapping[str, Any] | None
    other_lines: tuple[int, ...] = ()
