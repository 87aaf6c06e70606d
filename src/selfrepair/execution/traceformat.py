"""The mission trace format (JSON Lines): its name and version, the values a trace is read
into, and typed access to one line's fields.

A trace has one JSON object per line:

1. a header (``"type": "header"``): format name and version, the robot's ``domain`` (absent in
   version-1 traces of the four-wheel robot) and, for a robot defined in a plug-in file, that
   ``plugin`` (``{"path": ..., "sha256": ...}``: the resolved path and the SHA-256 of the
   content that ran; a reader loads it when the robot is not registered yet and the file there
   still has that content, else names the ``--plugin`` flag to pass), the maze (name and
   embedded rows, so the trace stands alone), start, goal, fault schedule, strategy and
   options, planner settings, seed, and the initial plan;
2. one line per repair (``"type": "repair"``), written just before the step at which it takes
   effect: ``step``, ``pose``, the faulty ``action`` (``null`` for the defensive replan when the
   queue ran out), ``status``, ``source``, ``attempts``, the new ``actions``, how many queued
   actions it ``consumed``, ``candidate_index`` and ``depth`` (table replacements) and
   ``latency_ns``;
3. one line per executed step (``"type": "step"``): ``step``, ``action``, ``from`` and ``to`` as
   ``[x, y, "N"]``, ``duration`` (exact, as text such as ``"2/3"``), ``source`` (``plan``,
   ``replacement``, ``lookahead``, ``replan``, ``plan-repair``, ``failed-attempt`` or ``wait``) and
   ``known`` (the faults known when the command was given, as text; a failed attempt's fault is
   known from the next step on); with the faults hidden (version 2), also what the robot
   observed and believed after it: ``read`` (its pose reading), ``bumped`` (its bump switch,
   ``null`` without one), ``seen`` (``[[observer, [x, y, "N"]], ...]``, teammates' readings, when
   it has observers; an observer with the wheel view adds the action it read the wheels
   performing, ``[observer, [x, y, "N"], "SFFF"]``), ``surprise``, and for a strategy that
   keeps a belief ``belief`` (the bit set of the hypotheses still possible, as hexadecimal
   text: bit ``i`` is hypothesis ``i`` of the header's ``hidden.hypotheses``) and ``best``
   (the most probable class, an index into ``hidden.classes``, each a list of hypothesis
   indices);
4. the mission summary (``"type": "summary"``): the row of
   :func:`selfrepair.execution.metrics.mission_row`.

Every field is type-checked when read (:mod:`selfrepair.execution.traceread`): a malformed file
raises :class:`~selfrepair.errors.TraceError` naming the line. Traces are written by
:mod:`selfrepair.execution.tracewrite` and re-simulated by :mod:`selfrepair.execution.replay`;
:mod:`selfrepair.execution.trace` gathers the public names.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, Literal, overload

from selfrepair.errors import InputError, TraceError
from selfrepair.execution.result import TraceStep
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.strategies import RepairSource, RepairStatus
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.registry import plugin_file
from selfrepair.textio import JSONObject

__all__ = [
    "DEFAULT_DOMAIN",
    "TRACE_FORMAT",
    "TRACE_VERSION",
    "Trace",
    "TraceFields",
    "TraceRepair",
    "header_start",
    "pose_json",
]

TRACE_FORMAT = "selfrepair-trace"
TRACE_VERSION = 2
"""The version written. Version 2 adds, with the faults hidden, what the robot observed and
believed after each step (:mod:`selfrepair.execution.traceobserve`); version-1 traces, without
them, still read and replay."""
TRACE_VERSIONS = (1, 2)
"""The versions read."""
DEFAULT_DOMAIN = "four-wheel"
"""The robot of a trace whose header names none (traces written before domains were named)."""


def header_start(trace_format: str, version: int, domain: str) -> JSONObject:
    """The fields a trace header (a mission's or a team's) begins with: its type, format and
    version, the robot domain and, for a plug-in robot, the file that registered it (path and
    SHA-256, so that a replay can check it runs the same robot)."""
    header: JSONObject = {
        "type": "header", "format": trace_format, "version": version, "domain": domain
    }
    origin = plugin_file(domain)
    if origin is not None:
        header["plugin"] = {"path": origin.path, "sha256": origin.sha256}
    return header


def pose_json(pose: Pose) -> list[object]:
    """A pose as traces write it: ``[x, y, "N"]``."""
    return [pose.x, pose.y, pose.heading.name]


@dataclass(frozen=True, slots=True)
class TraceRepair:
    """One repair line, read back: a :class:`~selfrepair.execution.result.RepairRecord` as the
    trace keeps it (the fields are those of the line, see the module docstring)."""

    step: int
    pose: Pose
    action: object | None
    status: RepairStatus
    source: RepairSource
    attempts: tuple[str, ...]
    actions: tuple[object, ...]
    consumed: int
    candidate_index: int | None
    depth: int | None
    latency_ns: int


@dataclass(frozen=True, slots=True)
class TraceObservation:
    """What a step line of a hidden-fault trace (version 2) says the robot observed and believed
    after the step: its own pose reading ``read`` and bump switch ``bumped`` (``None``: no
    switch), the teammates' readings ``seen`` (observer name, pose read and, wheel view, the
    action's text its actuators were read as performing, else ``None``), the bit set
    ``belief`` of the hypotheses still possible and the most probable class ``best`` (both
    ``None`` for a strategy that keeps no belief), and whether the step was a ``surprise`` (the
    reading is not where the command should have taken the robot, it bumped or the command
    failed)."""

    read: Pose
    bumped: bool | None
    seen: tuple[tuple[str, Pose, str | None], ...]
    belief: int | None
    best: int | None
    surprise: bool


@dataclass(frozen=True, slots=True)
class Trace:
    """A parsed trace: the robot, the header object, the steps and repairs (with their line
    numbers) and the summary (``None`` only for a partial trace)."""

    source: str
    domain: SomeDomain
    header: Mapping[str, Any]
    steps: tuple[TraceStep, ...]
    step_lines: tuple[int, ...]
    repairs: tuple[TraceRepair, ...] = ()
    repair_lines: tuple[int, ...] = ()
    summary: Mapping[str, Any] | None = None
    summary_line: int | None = None
    observations: tuple[TraceObservation | None, ...] = ()
    """Per step, what it observed and believed (hidden faults, version 2; ``None`` for a step
    line without them; empty for a trace that records none)."""


class TraceFields:
    """Typed access to one JSON line's fields; every failure is a :class:`TraceError` on that
    line. Mission traces and team traces (:mod:`selfrepair.team.trace`) read their lines with
    it."""

    def __init__(self, data: Mapping[str, Any], source: str, line: int) -> None:
        self.data, self.source, self.line = data, source, line

    def fail(self, what: str) -> TraceError:
        return TraceError(what, source=self.source, line=self.line)

    def get(self, key: str) -> Any:
        if key not in self.data:
            raise self.fail(f"expected a {self.data.get('type', 'line')} with key {key!r}")
        return self.data[key]

    @overload
    def integer(
        self, key: str, *, optional: Literal[False] = False, minimum: int | None = None
    ) -> int: ...

    @overload
    def integer(
        self, key: str, *, optional: Literal[True], minimum: int | None = None
    ) -> int | None: ...

    def integer(
        self, key: str, *, optional: bool = False, minimum: int | None = None
    ) -> int | None:
        """The integer at ``key`` (at least ``minimum``); ``optional``: ``None`` when absent."""
        value = self.data.get(key) if optional else self.get(key)
        if value is None and optional:
            return None
        if type(value) is not int or (minimum is not None and value < minimum):
            bound = "" if minimum is None else f" >= {minimum}"
            raise self.fail(f"expected {key!r} to be an integer{bound}, got {value!r}")
        return value

    @overload
    def text(self, key: str, *, optional: Literal[False] = False) -> str: ...

    @overload
    def text(self, key: str, *, optional: Literal[True]) -> str | None: ...

    def text(self, key: str, *, optional: bool = False) -> str | None:
        """The string at ``key``; ``optional``: ``None`` when absent."""
        value = self.data.get(key) if optional else self.get(key)
        if value is None and optional:
            return None
        if not isinstance(value, str):
            raise self.fail(f"expected {key!r} to be a string, got {value!r}")
        return value

    def texts(self, key: str) -> list[str]:
        value = self.get(key)
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise self.fail(f"expected {key!r} to be a list of strings, got {value!r}")
        return value

    def pose(self, key: str) -> Pose:
        value = self.get(key)
        if (
            not isinstance(value, list)
            or len(value) != 3
            or not all(type(v) is int for v in value[:2])
            or value[2] not in Heading.__members__
        ):
            raise self.fail(f'expected {key!r} as [x, y, "N|E|S|W"], got {value!r}')
        return Pose(value[0], value[1], Heading[value[2]])

    def choice(self, key: str, allowed: Iterable[str]) -> str:
        value = self.text(key)
        options = list(allowed)
        if value not in options:
            raise self.fail(f"expected {key!r} in {', '.join(options)}, got {value!r}")
        return str(value)

    def cell(self, value: object) -> Cell:
        """``value`` as a cell ``[x, y]``."""
        if not isinstance(value, list) or len(value) != 2 or not all(type(v) is int for v in value):
            raise self.fail(f"expected a cell [x, y], got {value!r}")
        return (value[0], value[1])

    def cells(self, key: str) -> tuple[Cell, ...]:
        value = self.get(key)
        if not isinstance(value, list):
            raise self.fail(f"expected {key!r} to be a list of cells, got {value!r}")
        return tuple(self.cell(v) for v in value)

    def parsed(self, what: str, fn: Any, text: str) -> Any:
        """``fn(text)``; its :class:`InputError` or ``ValueError`` becomes this line's error."""
        try:
            return fn(text)
        except (InputError, ValueError) as exc:
            reason = exc.reason if isinstance(exc, InputError) else str(exc)
            raise self.fail(f"bad {what}: {reason}") from None
