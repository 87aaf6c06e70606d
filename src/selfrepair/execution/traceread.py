"""Reading mission traces (format in :mod:`selfrepair.execution.traceformat`) into a
type-checked :class:`~selfrepair.execution.traceformat.Trace`, and a trace's header back into
the :class:`~selfrepair.execution.result.MissionSpec` it ran.

A malformed file raises :class:`~selfrepair.errors.TraceError` naming the line. A trace without
its summary line was cut short (a crash, a full disk): :func:`read_trace` refuses it
("truncated after step N") unless ``partial=True``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.diagnosis import (
    DEFAULT_CONFIDENCE,
    DEFAULT_FAULT_PRIOR,
    DEFAULT_MAX_FAULTS,
    ObservationModel,
)
from selfrepair.diagnosis.cooperative import Metric, Observer, ObserverView, SensingRange
from selfrepair.errors import InputError, TraceError
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec, StepSource, TraceStep
from selfrepair.execution.traceformat import (
    DEFAULT_DOMAIN,
    TRACE_FORMAT,
    TRACE_VERSIONS,
    Trace,
    TraceFields,
    TraceObservation,
    TraceRepair,
)
from selfrepair.execution.traceobserve import parse_observation
from selfrepair.geometry import Heading
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.repair.strategies import RepairSource, RepairStatus, StrategyName, StrategyOptions
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.registry import PluginFile, get_domain, load_recorded_plugin
from selfrepair.tables.fileformat import default_table
from selfrepair.tables.generate import GENERATOR_SOURCE
from selfrepair.tables.model import SomeTable
from selfrepair.textio import read_text
from selfrepair.world.events import WorldSchedule
from selfrepair.world.maze import parse_maze

__all__ = ["parse_trace", "read_trace", "read_trace_text", "spec_from_header"]


def _parse_step(domain: SomeDomain, f: TraceFields) -> TraceStep:
    action = f.parsed("action", domain.parse_action, f.text("action"))
    known: set[object] = set()
    for text in f.texts("known"):
        known |= f.parsed("known fault", domain.parse_faults, text)
    duration_text = f.text("duration")
    try:
        duration = Fraction(duration_text)
    except (ValueError, ZeroDivisionError):
        raise f.fail(
            f"expected 'duration' as an exact number such as '2/3', got {duration_text!r}"
        ) from None
    source = StepSource(f.choice("source", (s.value for s in StepSource)))
    number = f.integer("step", minimum=0)
    return TraceStep(
        number, action, f.pose("from"), f.pose("to"), duration, source, frozenset(known)
    )


def _parse_repair(domain: SomeDomain, f: TraceFields, next_step: int) -> TraceRepair:
    """A repair line, type-checked; it must come just before step line ``next_step``."""
    step = f.integer("step", minimum=0)
    if step != next_step:
        raise f.fail(f"expected a repair for step {next_step} (the next step line), got {step}")
    action = f.text("action", optional=True)
    return TraceRepair(
        step=step,
        pose=f.pose("pose"),
        action=None if action is None else f.parsed("action", domain.parse_action, action),
        status=RepairStatus(f.choice("status", (s.value for s in RepairStatus))),
        source=RepairSource(f.choice("source", (s.value for s in RepairSource))),
        attempts=tuple(f.texts("attempts")),
        actions=tuple(f.parsed("action", domain.parse_action, t) for t in f.texts("actions")),
        consumed=f.integer("consumed", minimum=0),
        candidate_index=f.integer("candidate_index", optional=True, minimum=0),
        depth=f.integer("depth", optional=True, minimum=0),
        latency_ns=f.integer("latency_ns", minimum=0),
    )


def _header(data: Any, source: str, number: int) -> tuple[Mapping[str, Any], SomeDomain]:
    kind = data.get("type") if isinstance(data, dict) else None
    if kind != "header" or data.get("format") != TRACE_FORMAT:
        raise TraceError(
            f'expected a header line with "format": "{TRACE_FORMAT}"', source=source, line=number
        )
    version = data.get("version")
    if type(version) is not int or version not in TRACE_VERSIONS:
        raise TraceError(
            f"expected trace version {' or '.join(map(str, TRACE_VERSIONS))}, got {version!r}",
            source=source,
            line=number,
        )
    name = data.get("domain", DEFAULT_DOMAIN)
    if not isinstance(name, str):
        raise TraceError(f"expected 'domain' to be a string, got {name!r}", source=source, line=1)
    _load_robot(name, data.get("plugin"), source, number)
    try:
        domain = get_domain(name)
    except InputError as exc:
        raise TraceError(
            f"the trace's robot {name!r} is not registered here ({exc.reason}): pass "
            "--plugin FILE with the file that defines it",
            source=source,
            line=number,
        ) from None
    return data, domain


def _load_robot(name: str, plugin: Any, source: str, number: int) -> None:
    """Make the trace's robot known from the plug-in file its header records (see
    :func:`selfrepair.robots.registry.load_recorded_plugin`)."""
    if plugin is None:
        return
    if not (
        isinstance(plugin, dict)
        and isinstance(plugin.get("path"), str)
        and isinstance(plugin.get("sha256"), str)
    ):
        raise TraceError(
            f'expected \'plugin\' to be {{"path": ..., "sha256": ...}}, got {plugin!r}',
            source=source,
            line=number,
        )
    try:
        load_recorded_plugin(name, PluginFile(plugin["path"], plugin["sha256"]), "trace")
    except InputError as exc:
        raise TraceError(exc.reason, source=source, line=number) from None


def parse_trace(text: str, source: str = "<trace>", *, partial: bool = False) -> Trace:
    """Parse trace text; structure and type errors raise :class:`TraceError` naming the line. A
    trace without a summary line is refused as truncated unless ``partial``."""
    header: Mapping[str, Any] | None = None
    domain: SomeDomain | None = None
    summary: Mapping[str, Any] | None = None
    summary_line: int | None = None
    steps: list[TraceStep] = []
    lines: list[int] = []
    repairs: list[TraceRepair] = []
    repair_lines: list[int] = []
    observations: list[TraceObservation | None] = []
    for number, raw in enumerate(text.split("\n"), start=1):
        if not raw.strip():
            continue
        try:
            data = json.loads(raw)
        except (json.JSONDecodeError, RecursionError) as exc:
            msg = exc.msg if isinstance(exc, json.JSONDecodeError) else "nested too deeply"
            raise TraceError(
                f"expected one JSON object per line: {msg}", source=source, line=number
            ) from None
        if header is None or domain is None:
            header, domain = _header(data, source, number)
            continue
        kind = data.get("type") if isinstance(data, dict) else None
        if summary is not None:
            raise TraceError("expected nothing after the summary line", source=source, line=number)
        if kind == "step":
            fields = TraceFields(data, source, number)
            steps.append(_parse_step(domain, fields))
            observations.append(parse_observation(fields))
            lines.append(number)
        elif kind == "repair":
            next_step = len(steps)
            repairs.append(_parse_repair(domain, TraceFields(data, source, number), next_step))
            repair_lines.append(number)
        elif kind == "summary":
            summary, summary_line = data, number
        else:
            raise TraceError(
                f"expected a step, repair or summary line, got type {kind!r}",
                source=source,
                line=number,
            )
    if header is None or domain is None:
        raise TraceError("expected a header line, got an empty file", source=source)
    if summary is None and not partial:
        last = f"step {steps[-1].step}" if steps else "the header"
        raise TraceError(
            f"truncated after {last}: no summary line (pass partial=True, or --partial, to read "
            "it anyway)",
            source=source,
        )
    return Trace(
        source,
        domain,
        header,
        tuple(steps),
        tuple(lines),
        tuple(repairs),
        tuple(repair_lines),
        summary,
        summary_line,
        tuple(observations) if any(o is not None for o in observations) else (),
    )


def read_trace(
    path: str | Path, *, partial: bool = False, max_trace_bytes: int | None = MAX_TRACE_BYTES
) -> Trace:
    """Read and parse a trace file (see :func:`parse_trace`); a file over ``max_trace_bytes``
    (:data:`selfrepair.limits.MAX_TRACE_BYTES`; ``None``: no limit) is refused unread."""
    path = Path(path)
    text = read_trace_text(path, "JSON Lines trace", max_trace_bytes)
    return parse_trace(text, source=str(path), partial=partial)


def read_trace_text(path: str | Path, what: str, max_trace_bytes: int | None) -> str:
    """The text of the trace file ``path`` (a single robot's or a team's, named by ``what`` in
    messages); a file over ``max_trace_bytes`` is refused unread, other problems raise
    :class:`~selfrepair.errors.TraceError`."""
    return read_text(
        path, what=what, error=TraceError, max_bytes=max_trace_bytes, limit="max_trace_bytes"
    )


def spec_from_header(header: Mapping[str, Any], source: str = "<trace>") -> MissionSpec:
    """The mission spec a trace header describes (so the mission can be run again)."""
    try:
        name = str(header.get("domain", DEFAULT_DOMAIN))
        _load_robot(name, header.get("plugin"), source, 1)
        domain = get_domain(name)
        maze_data = header["maze"]
        maze = parse_maze(
            "\n".join(maze_data["rows"]), source=source, name=str(maze_data.get("name", ""))
        )
        f = TraceFields(header, source, 1)
        gx, gy = header["goal"]
        heading = header.get("goal_heading")
        options = header.get("options", {})
        planner = header.get("planner", {})
        hidden = header.get("hidden") or {}
        return MissionSpec(
            maze=maze,
            start=f.pose("start"),
            goal=(int(gx), int(gy)),
            goal_heading=None if heading is None else Heading[heading],
            schedule=FaultSchedule.from_json(header.get("schedule", {}), domain, source),
            world=WorldSchedule.from_json(header.get("world", {}), source),
            strategy=str(header.get("strategy", StrategyName.REPLACEMENT)),
            options=StrategyOptions(
                table=_table(str(options.get("table", "handwritten")), domain),
                recursion=str(options.get("recursion", "flat")),  # type: ignore[arg-type]
                max_depth=int(options.get("max_depth", 2)),
                window=int(options.get("window", 3)),
                lookahead_expansions=int(options.get("lookahead_expansions", 20_000)),
                lpg_time_limit_s=float(options.get("lpg_time_limit_s", 5.0)),
                lpg_seed=int(options.get("lpg_seed", 0)),
                max_wait=int(options.get("max_wait", 0)),  # older traces: made without waits
                max_faults=int(hidden.get("max_faults", DEFAULT_MAX_FAULTS)),
                fault_prior=float(hidden.get("fault_prior", DEFAULT_FAULT_PRIOR)),
                confidence=float(hidden.get("confidence", DEFAULT_CONFIDENCE)),
            ),
            behaviour=hidden.get("behaviour"),
            observation=ObservationModel(
                float(hidden.get("noise", 0.0)), bool(hidden.get("bumps", True))
            ),
            observers=tuple(
                Observer(
                    str(o["name"]),
                    float(o["noise"]),
                    SensingRange(int(o["range"]), Metric(o.get("metric", "chebyshev"))),
                    ObserverView(o.get("view", "pose")),
                )
                for o in hidden.get("observers", ())
            ),
            clearance_weight=Fraction(str(planner.get("clearance_weight", "0"))),
            clearance_radius=int(planner.get("clearance_radius", 2)),
            seed=int(header.get("seed", 0)),
            heuristic=str(planner.get("heuristic", "grid-distance")),
            backend=str(planner.get("backend", "auto")),
            replan_max_expansions=planner.get("max_expansions"),
            initial_faults_known=bool(header.get("initial_faults_known", False)),
            max_steps=header.get("max_steps"),
            domain=domain,
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        # AttributeError: a field that must be an object (options, planner, schedule) is not
        if isinstance(exc, InputError):
            raise TraceError(exc.reason, source=source, line=1) from None
        raise TraceError(f"expected a complete header: {exc!r}", source=source, line=1) from None


def _table(label: str, domain: SomeDomain) -> str | SomeTable:
    """The table a trace names: a bundled name or a file path as written, and a generated table
    (recorded by its source, ``<generator>``) as the robot's default generated table, the only
    generated table the command line runs with (:func:`~selfrepair.tables.fileformat.default_table`;
    a table file made by ``table generate`` is recorded by its path)."""
    if label == GENERATOR_SOURCE:
        return default_table(domain)
    return label
