"""Mission traces (JSON Lines) and their replay.

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
   known from the next step on);
4. the mission summary (``"type": "summary"``): the row of
   :func:`selfrepair.execution.metrics.mission_row`.

Every field is type-checked when read: a malformed file raises
:class:`~selfrepair.errors.TraceError` naming the line. A trace without its summary line was cut
short (a crash, a full disk): :func:`read_trace` refuses it ("truncated after step N") unless
``partial=True``. :func:`replay` re-simulates the steps with the robot's domain and the fault
schedule and returns a :class:`ReplayReport` naming the first step that does not hold.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.errors import InputError, TraceError
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import (
    MissionResult,
    MissionSpec,
    RepairRecord,
    StepSource,
    TraceStep,
)
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.repair.strategies import RepairSource, RepairStatus, StrategyName, StrategyOptions
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import PluginFile, get_domain, load_recorded_plugin, plugin_file
from selfrepair.textio import read_text
from selfrepair.world.maze import format_maze, parse_maze

__all__ = [
    "TRACE_FORMAT",
    "TRACE_VERSION",
    "ReplayReport",
    "Trace",
    "TraceFields",
    "TraceRepair",
    "header_json",
    "parse_trace",
    "read_trace",
    "replay",
    "spec_from_header",
    "trace_lines",
    "write_trace",
]

TRACE_FORMAT = "selfrepair-trace"
TRACE_VERSION = 1
DEFAULT_DOMAIN = "four-wheel"
"""The robot of a trace whose header names none (traces written before domains were named)."""


def _pose_json(pose: Pose) -> list[Any]:
    return [pose.x, pose.y, pose.heading.name]


def header_json(spec: MissionSpec, initial_plan: Iterable[Any] = ()) -> dict[str, Any]:
    """The header line's object for ``spec``."""
    options = spec.options
    domain = spec.domain
    origin = plugin_file(domain.name)
    plugin = {} if origin is None else {"plugin": {"path": origin.path, "sha256": origin.sha256}}
    return {
        "type": "header",
        "format": TRACE_FORMAT,
        "version": TRACE_VERSION,
        "domain": domain.name,
        **plugin,
        "maze": {"name": spec.maze.name, "rows": format_maze(spec.maze).splitlines()},
        "start": _pose_json(spec.start),
        "goal": [spec.goal[0], spec.goal[1]],
        "goal_heading": None if spec.goal_heading is None else spec.goal_heading.name,
        "schedule": spec.schedule.to_json(domain),
        "strategy": str(spec.strategy),
        "options": {
            "table": options.table_label,
            "recursion": options.recursion.value,
            "max_depth": options.max_depth,
            "window": options.window,
            "lookahead_expansions": options.lookahead_expansions,
            "lpg_time_limit_s": options.lpg_time_limit_s,
            "lpg_seed": options.lpg_seed,
            "max_wait": options.max_wait,
        },
        "planner": {
            "heuristic": spec.heuristic,
            "backend": spec.backend,
            "clearance_weight": str(spec.clearance_weight),
            "clearance_radius": spec.clearance_radius,
            "max_expansions": spec.replan_max_expansions,
        },
        "seed": spec.seed,
        "initial_faults_known": spec.initial_faults_known,
        "max_steps": spec.max_steps,
        "initial_plan": [domain.format_action(a) for a in initial_plan],
    }


def _fault_texts(domain: Domain[Any, Any], faults: Iterable[Any]) -> list[str]:
    return sorted(domain.format_faults([f]) for f in faults)


def step_json(domain: Domain[Any, Any], step: TraceStep) -> dict[str, Any]:
    """One step line's object."""
    return {
        "type": "step",
        "step": step.step,
        "action": domain.format_action(step.action),
        "from": _pose_json(step.start),
        "to": _pose_json(step.end),
        "duration": str(step.duration),
        "source": step.source.value,
        "known": _fault_texts(domain, step.known),
    }


def repair_json(domain: Domain[Any, Any], record: RepairRecord) -> dict[str, Any]:
    """One repair line's object."""
    repair = record.repair
    return {
        "type": "repair",
        "step": record.step,
        "pose": _pose_json(record.pose),
        "action": None if record.action is None else domain.format_action(record.action),
        "status": repair.status.value,
        "source": repair.source.value,
        "attempts": [str(a) for a in repair.attempts],
        "actions": [domain.format_action(a) for a in repair.actions],
        "consumed": repair.consumed,
        "candidate_index": repair.candidate_index,
        "depth": repair.depth,
        "latency_ns": record.latency_ns,
    }


def trace_lines(result: MissionResult) -> list[str]:
    """The trace of ``result``, one JSON text per line (no newlines inside)."""
    domain = result.spec.domain
    lines = [json.dumps(header_json(result.spec, result.initial_plan.actions))]
    repairs = list(result.repairs)
    for step in result.steps:
        while repairs and repairs[0].step <= step.step:
            lines.append(json.dumps(repair_json(domain, repairs.pop(0))))
        lines.append(json.dumps(step_json(domain, step)))
    lines.extend(json.dumps(repair_json(domain, r)) for r in repairs)
    lines.append(json.dumps({"type": "summary", **mission_row(result)}))
    return lines


def write_trace(result: MissionResult, path: str | Path) -> None:
    """Write the trace of ``result`` to ``path``."""
    Path(path).write_text("\n".join(trace_lines(result)) + "\n", encoding="utf-8")


@dataclass(frozen=True, slots=True)
class TraceRepair:
    """One repair line, read back: a :class:`~selfrepair.execution.result.RepairRecord` as the
    trace keeps it (the fields are those of the line, see the module docstring)."""

    step: int
    pose: Pose
    action: Any | None
    status: RepairStatus
    source: RepairSource
    attempts: tuple[str, ...]
    actions: tuple[Any, ...]
    consumed: int
    candidate_index: int | None
    depth: int | None
    latency_ns: int


@dataclass(frozen=True, slots=True)
class Trace:
    """A parsed trace: the robot, the header object, the steps and repairs (with their line
    numbers) and the summary (``None`` only for a partial trace)."""

    source: str
    domain: Domain[Any, Any]
    header: Mapping[str, Any]
    steps: tuple[TraceStep, ...]
    step_lines: tuple[int, ...]
    repairs: tuple[TraceRepair, ...] = ()
    repair_lines: tuple[int, ...] = ()
    summary: Mapping[str, Any] | None = None
    summary_line: int | None = None


# --- reading --------------------------------------------------------------------------------------


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

    def integer(self, key: str, *, optional: bool = False, minimum: int | None = None) -> Any:
        value = self.data.get(key) if optional else self.get(key)
        if value is None and optional:
            return None
        if type(value) is not int or (minimum is not None and value < minimum):
            bound = "" if minimum is None else f" >= {minimum}"
            raise self.fail(f"expected {key!r} to be an integer{bound}, got {value!r}")
        return value

    def text(self, key: str, *, optional: bool = False) -> Any:
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

    def cell(self, value: Any) -> Cell:
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


def _parse_step(domain: Domain[Any, Any], f: TraceFields) -> TraceStep:
    action = f.parsed("action", domain.parse_action, f.text("action"))
    known: set[Any] = set()
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


def _parse_repair(domain: Domain[Any, Any], f: TraceFields, next_step: int) -> TraceRepair:
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


def _header(data: Any, source: str, number: int) -> tuple[Mapping[str, Any], Domain[Any, Any]]:
    kind = data.get("type") if isinstance(data, dict) else None
    if kind != "header" or data.get("format") != TRACE_FORMAT:
        raise TraceError(
            f'expected a header line with "format": "{TRACE_FORMAT}"', source=source, line=number
        )
    version = data.get("version")
    if type(version) is not int or version != TRACE_VERSION:
        raise TraceError(
            f"expected trace version {TRACE_VERSION}, got {version!r}", source=source, line=number
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
            f"expected 'plugin' to be {{\"path\": ..., \"sha256\": ...}}, got {plugin!r}",
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
    domain: Domain[Any, Any] | None = None
    summary: Mapping[str, Any] | None = None
    summary_line: int | None = None
    steps: list[TraceStep] = []
    lines: list[int] = []
    repairs: list[TraceRepair] = []
    repair_lines: list[int] = []
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
            steps.append(_parse_step(domain, TraceFields(data, source, number)))
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
    )


def read_trace(
    path: str | Path, *, partial: bool = False, max_trace_bytes: int | None = MAX_TRACE_BYTES
) -> Trace:
    """Read and parse a trace file (see :func:`parse_trace`); a file over ``max_trace_bytes``
    (:data:`selfrepair.limits.MAX_TRACE_BYTES`; ``None``: no limit) is refused unread."""
    path = Path(path)
    text = read_text(
        path,
        what="JSON Lines trace",
        error=TraceError,
        max_bytes=max_trace_bytes,
        limit="max_trace_bytes",
    )
    return parse_trace(text, source=str(path), partial=partial)


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
        return MissionSpec(
            maze=maze,
            start=f.pose("start"),
            goal=(int(gx), int(gy)),
            goal_heading=None if heading is None else Heading[heading],
            schedule=FaultSchedule.from_json(header.get("schedule", {}), domain, source),
            strategy=str(header.get("strategy", StrategyName.REPLACEMENT)),
            options=StrategyOptions(
                table=str(options.get("table", "handwritten")),
                recursion=str(options.get("recursion", "flat")),  # type: ignore[arg-type]
                max_depth=int(options.get("max_depth", 2)),
                window=int(options.get("window", 3)),
                lookahead_expansions=int(options.get("lookahead_expansions", 20_000)),
                lpg_time_limit_s=float(options.get("lpg_time_limit_s", 5.0)),
                lpg_seed=int(options.get("lpg_seed", 0)),
                max_wait=int(options.get("max_wait", 0)),  # older traces: made without waits
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


# --- replay ---------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ReplayReport:
    """The outcome of a replay. ``ok`` when every step holds; otherwise ``first_bad_step`` (the
    step number, or ``None`` for a problem with the summary), its ``line`` and the ``reason``.
    ``partial`` when the trace had no summary to check."""

    ok: bool
    steps_checked: int
    first_bad_step: int | None = None
    line: int | None = None
    reason: str = ""
    partial: bool = False

    def __str__(self) -> str:
        if self.ok:
            tail = " (partial trace: no summary to check)" if self.partial else ""
            return f"ok: all {self.steps_checked} steps replay{tail}"
        where = "summary" if self.first_bad_step is None else f"step {self.first_bad_step}"
        return f"{where} (line {self.line}) does not hold: {self.reason}"


def replay(trace: Trace | str | Path) -> ReplayReport:
    """Re-simulate every step of ``trace`` and report the first one that does not hold.

    Every step must start where the previous one ended and use an action available under the
    faults it recorded as known; with detection ``now`` those must be the faults the sensors
    report at that step (the true ones). A moving step must also be allowed by the true faults
    of the schedule at that step, sweep only free cells, and end at the pose and after the
    duration that the domain's ``step`` gives. A failed attempt must use an action the true
    faults forbid, stay put and last one tick. The summary, when present, must agree on the
    number of steps, the final pose, the ticks and whether the goal was reached.
    """
    if not isinstance(trace, Trace):
        trace = read_trace(trace)
    spec = spec_from_header(trace.header, trace.source)
    pose = spec.start
    ticks = Fraction(0)
    for index, (step, line) in enumerate(zip(trace.steps, trace.step_lines, strict=True)):
        problem = _check_step(spec, index, step, pose, ticks)
        if problem is not None:
            return ReplayReport(False, index, step.step, line, problem)
        pose = step.end
        ticks += step.duration
    return _check_summary(trace, spec, pose, ticks)


def _check_step(
    spec: MissionSpec, index: int, step: TraceStep, pose: Pose, ticks: Fraction
) -> str | None:
    domain = spec.domain
    name = domain.format_action(step.action)
    if step.step != index:
        return f"expected step number {index}, got {step.step}"
    if step.start != pose:
        return f"starts at {step.start}, but the robot is at {pose}"
    true = spec.schedule.active_faults(index, ticks, spec.seed)
    if spec.schedule.detection is Detection.NOW and step.known != true:
        return (
            f"records the known faults {domain.format_faults(step.known) or 'none'}, but with "
            f"detection 'now' the robot senses {domain.format_faults(true) or 'none'}"
        )
    if not domain.available(step.action, step.known):
        return f"{name} uses a known-faulty command ({domain.format_faults(step.known)})"
    if step.source is StepSource.FAILED_ATTEMPT:
        if domain.available(step.action, true):
            return f"a failed attempt of {name}, but no true fault forbids it"
        if step.end != step.start or step.duration != FAILED_ATTEMPT_TICKS:
            return "a failed attempt must stay put and last one tick"
        return None
    if not domain.available(step.action, true):
        return f"{name} is forbidden by the true faults {domain.format_faults(true)}"
    end, swept, duration = domain.step(pose, step.action)
    if not spec.maze.all_free(swept):
        return f"{name} at {pose} sweeps a wall or leaves the grid"
    if end != step.end:
        return f"{name} from {pose} ends at {end}, trace says {step.end}"
    if duration != step.duration:
        return f"{name} lasts {duration} ticks, trace says {step.duration}"
    return None


def _check_summary(trace: Trace, spec: MissionSpec, pose: Pose, ticks: Fraction) -> ReplayReport:
    count = len(trace.steps)
    summary = trace.summary
    if summary is None:
        return ReplayReport(True, count, partial=True)
    line = trace.summary_line
    checks = (
        (summary.get("steps") == count, f"summary says {summary.get('steps')} steps, the trace "
         f"has {count}"),
        (summary.get("final_pose") == str(pose), f"summary says final pose "
         f"{summary.get('final_pose')}, replay ends at {pose}"),
        ((summary.get("status") == "reached") == spec.at_goal(pose), f"summary status "
         f"{summary.get('status')!r} but the replay "
         f"{'ends' if spec.at_goal(pose) else 'does not end'} at the goal"),
        (summary.get("ticks") == str(ticks), f"summary says {summary.get('ticks')} ticks, "
         f"replay takes {ticks}"),
    )  # fmt: skip
    for holds, reason in checks:
        if not holds:
            return ReplayReport(False, count, None, line, reason)
    return ReplayReport(True, count)
