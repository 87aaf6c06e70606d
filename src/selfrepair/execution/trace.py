"""Mission traces (JSON Lines) and their replay.

A trace has one JSON object per line:

1. a header (``"type": "header"``): format name and version, the maze (name and embedded rows, so
   the trace stands alone), start, goal, fault schedule, strategy and options, planner settings,
   seed, and the initial plan;
2. one line per executed step (``"type": "step"``): ``step``, ``action`` (wheel code), ``from``
   and ``to`` as ``[x, y, "N"]``, ``duration`` (exact, as text such as ``"2/3"``), ``source``
   (``plan``, ``replacement``, ``lookahead``, ``replan`` or ``failed-attempt``) and ``known``
   (the faults known when the command was given, as strings; a failed attempt's fault is known
   from the next step on);
3. one line per repair (``"type": "repair"``), written just before the step line it takes
   effect at (so a repair that ends the mission comes after the last step): ``step`` (the
   number of the next step when the repair was made), ``pose``, ``action`` (the faulty action,
   ``null`` for the replan made when the plan runs out away from the goal), ``status``
   (``repaired``, ``stuck`` or ``budget_exhausted``), ``source`` (``replacement``,
   ``lookahead`` or ``replan``), ``attempts`` (the strategies tried, in order), ``actions``
   (what was spliced in), ``consumed`` (queued actions dropped), ``candidate_index`` and
   ``depth`` (a table replacement's candidate position and nesting depth, else ``null``) and
   ``latency_ns``. Traces without repair lines (written before they existed) still parse;
4. the mission summary (``"type": "summary"``): the row of
   :meth:`selfrepair.execution.result.MissionResult.to_row`.

:func:`replay` re-simulates the steps with the robot model and the fault schedule and returns a
:class:`ReplayReport` naming the first step that does not hold; a malformed file raises
:class:`~selfrepair.errors.TraceError` naming the line.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.errors import InputError, TraceError
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import (
    SOURCES,
    MissionResult,
    MissionSpec,
    RepairRecord,
    TraceStep,
)
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots import four_wheel
from selfrepair.world.maze import Maze, format_maze, parse_maze

__all__ = [
    "TRACE_FORMAT",
    "TRACE_VERSION",
    "ReplayReport",
    "Trace",
    "TraceRepair",
    "read_trace",
    "replay",
    "spec_from_header",
    "trace_lines",
    "write_trace",
]

TRACE_FORMAT = "selfrepair-trace"
TRACE_VERSION = 1


def _pose_json(pose: Pose) -> list[Any]:
    return [pose.x, pose.y, pose.heading.name]


def header_json(spec: MissionSpec, initial_plan: Iterable[four_wheel.Action] = ()) -> dict[str, Any]:
    """The header line's object for ``spec``."""
    options = spec.options
    return {
        "type": "header",
        "format": TRACE_FORMAT,
        "version": TRACE_VERSION,
        "maze": {"name": spec.maze.name, "rows": format_maze(spec.maze).splitlines()},
        "start": _pose_json(spec.start),
        "goal": [spec.goal[0], spec.goal[1]],
        "goal_heading": None if spec.goal_heading is None else spec.goal_heading.name,
        "schedule": spec.schedule.to_json(),
        "strategy": spec.strategy,
        "options": {
            "table": options.table_label,
            "recursion": options.recursion,
            "max_depth": options.max_depth,
            "window": options.window,
            "lookahead_expansions": options.lookahead_expansions,
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
        "initial_plan": [a.code for a in initial_plan],
    }


def step_json(step: TraceStep) -> dict[str, Any]:
    """One step line's object."""
    return {
        "type": "step",
        "step": step.step,
        "action": step.action.code,
        "from": _pose_json(step.start),
        "to": _pose_json(step.end),
        "duration": str(step.duration),
        "source": step.source,
        "known": sorted(str(f) for f in step.known),
    }


def trace_lines(result: MissionResult) -> list[str]:
    """The trace of ``result``, one JSON text per line (no newlines inside)."""
    lines = [json.dumps(header_json(result.spec, result.initial_plan.actions))]
    lines.extend(json.dumps(obj) for obj in _step_and_repair_objects(result))
    lines.append(json.dumps({"type": "summary", **mission_row(result)}))
    return lines


def write_trace(result: MissionResult, path: str | Path) -> None:
    """Write the trace of ``result`` to ``path``."""
    Path(path).write_text("\n".join(trace_lines(result)) + "\n", encoding="utf-8")


# --- repair lines --------------------------------------------------------------------------------

REPAIR_STATUSES = ("repaired", "stuck", "budget_exhausted")
"""What a repair line's ``status`` may be (see :class:`selfrepair.repair.strategies.Repair`)."""

REPAIR_SOURCES = tuple(s for s in SOURCES if s not in ("plan", "failed-attempt"))
"""What a repair line's ``source`` may be: the step sources a strategy produces."""


@dataclass(frozen=True, slots=True)
class TraceRepair:
    """One repair line: a :class:`~selfrepair.execution.result.RepairRecord` as the trace keeps
    it (the fields are those of the line, see the module docstring)."""

    step: int
    pose: Pose
    action: four_wheel.Action | None
    status: str
    source: str
    attempts: tuple[str, ...]
    actions: tuple[four_wheel.Action, ...]
    consumed: int
    candidate_index: int | None
    depth: int | None
    latency_ns: int


def repair_json(record: RepairRecord) -> dict[str, Any]:
    """One repair line's object."""
    repair = record.repair
    return {
        "type": "repair",
        "step": record.step,
        "pose": _pose_json(record.pose),
        "action": None if record.action is None else record.action.code,
        "status": repair.status,
        "source": repair.source,
        "attempts": list(repair.attempts),
        "actions": [a.code for a in repair.actions],
        "consumed": repair.consumed,
        "candidate_index": repair.candidate_index,
        "depth": repair.depth,
        "latency_ns": record.latency_ns,
    }


def _step_and_repair_objects(result: MissionResult) -> list[dict[str, Any]]:
    """Step and repair objects in trace order: each repair just before the step it precedes,
    the repairs made after the last step at the end."""
    objects: list[dict[str, Any]] = []
    repairs = list(result.repairs)
    done = 0
    for step in result.steps:
        while done < len(repairs) and repairs[done].step <= step.step:
            objects.append(repair_json(repairs[done]))
            done += 1
        objects.append(step_json(step))
    objects.extend(repair_json(r) for r in repairs[done:])
    return objects


def _parse_repair(data: Mapping[str, Any], source: str, line: int, next_step: int) -> TraceRepair:
    """A repair line, type-checked; it must come just before step line ``next_step``."""
    missing = [k for k in _REPAIR_KEYS if k not in data]
    if missing:
        raise TraceError(f"expected a repair with key {missing[0]!r}", source=source, line=line)
    step = _count(data, "step", source, line)
    if step != next_step:
        raise TraceError(
            f"expected a repair for step {next_step} (the next step line), got step {step}",
            source=source,
            line=line,
        )
    action = data["action"]
    return TraceRepair(
        step=next_step,
        pose=_parse_pose(data["pose"], source, line, "'pose'"),
        action=None if action is None else _codes([action], "action", source, line)[0],
        status=_choice(data, "status", REPAIR_STATUSES, source, line),
        source=_choice(data, "source", REPAIR_SOURCES, source, line),
        attempts=_names(data["attempts"], source, line),
        actions=_codes(data["actions"], "actions", source, line),
        consumed=_count(data, "consumed", source, line),
        candidate_index=_optional_count(data, "candidate_index", source, line),
        depth=_optional_count(data, "depth", source, line),
        latency_ns=_count(data, "latency_ns", source, line),
    )


_REPAIR_KEYS = (
    "step",
    "pose",
    "action",
    "status",
    "source",
    "attempts",
    "actions",
    "consumed",
    "candidate_index",
    "depth",
    "latency_ns",
)


def _count(data: Mapping[str, Any], key: str, source: str, line: int) -> int:
    value = data[key]
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise TraceError(
            f"expected repair {key!r} to be an integer >= 0, got {value!r}",
            source=source,
            line=line,
        )
    return value


def _optional_count(data: Mapping[str, Any], key: str, source: str, line: int) -> int | None:
    return None if data[key] is None else _count(data, key, source, line)


def _choice(
    data: Mapping[str, Any], key: str, choices: tuple[str, ...], source: str, line: int
) -> str:
    value = data[key]
    if value not in choices:
        raise TraceError(
            f"expected repair {key!r} in {', '.join(choices)}, got {value!r}",
            source=source,
            line=line,
        )
    return str(value)


def _names(value: Any, source: str, line: int) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise TraceError(
            f"expected repair 'attempts' to be a list of strategy names, got {value!r}",
            source=source,
            line=line,
        )
    return tuple(value)


def _codes(value: Any, key: str, source: str, line: int) -> tuple[four_wheel.Action, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise TraceError(
            f"expected repair {key!r} as action codes, got {value!r}", source=source, line=line
        )
    try:
        return tuple(four_wheel.parse_action(v, source=source) for v in value)
    except InputError as exc:
        raise TraceError(f"bad repair {key!r}: {exc.reason}", source=source, line=line) from None


@dataclass(frozen=True, slots=True)
class Trace:
    """A parsed trace: the header object, the steps (with their line numbers), the summary, and
    the repairs (with their line numbers; empty for traces written before repair lines)."""

    source: str
    header: Mapping[str, Any]
    steps: tuple[TraceStep, ...]
    step_lines: tuple[int, ...]
    summary: Mapping[str, Any] | None
    repairs: tuple[TraceRepair, ...] = ()
    repair_lines: tuple[int, ...] = ()


def _parse_pose(value: Any, source: str, line: int, what: str) -> Pose:
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, int) for v in value[:2])
        or value[2] not in Heading.__members__
    ):
        raise TraceError(
            f'expected {what} as [x, y, "N|E|S|W"], got {value!r}', source=source, line=line
        )
    return Pose(value[0], value[1], Heading[value[2]])


def _parse_step(data: Mapping[str, Any], source: str, line: int) -> TraceStep:
    try:
        action = four_wheel.parse_action(str(data["action"]), source=source)
        known = frozenset(four_wheel.parse_fault(str(f), source=source) for f in data["known"])
        duration = Fraction(str(data["duration"]))
        number = int(data["step"])
        step_source = str(data["source"])
        start = _parse_pose(data["from"], source, line, "'from'")
        end = _parse_pose(data["to"], source, line, "'to'")
    except KeyError as exc:
        raise TraceError(
            f"expected a step with key {exc.args[0]!r}", source=source, line=line
        ) from None
    except (ValueError, TypeError, ZeroDivisionError) as exc:
        if isinstance(exc, TraceError):
            raise
        reason = exc.reason if isinstance(exc, InputError) else str(exc)
        raise TraceError(f"bad step field: {reason}", source=source, line=line) from None
    if step_source not in SOURCES:
        raise TraceError(
            f"expected source in {', '.join(SOURCES)}, got {step_source!r}",
            source=source,
            line=line,
        )
    return TraceStep(number, action, start, end, duration, step_source, known)


def parse_trace(text: str, source: str = "<trace>") -> Trace:
    """Parse trace text; structure errors raise :class:`TraceError` naming the line."""
    header: Mapping[str, Any] | None = None
    summary: Mapping[str, Any] | None = None
    steps: list[TraceStep] = []
    lines: list[int] = []
    repairs: list[TraceRepair] = []
    repair_lines: list[int] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        try:
            data = json.loads(raw)
        except json.JSONDecodeError as exc:
            raise TraceError(
                f"expected one JSON object per line: {exc.msg}",
                source=source,
                line=number,
                column=exc.colno,
            ) from None
        kind = data.get("type") if isinstance(data, dict) else None
        if header is None:
            if kind != "header" or data.get("format") != TRACE_FORMAT:
                raise TraceError(
                    f'expected a header line with "format": "{TRACE_FORMAT}"',
                    source=source,
                    line=number,
                )
            if data.get("version") != TRACE_VERSION:
                raise TraceError(
                    f"expected trace version {TRACE_VERSION}, got {data.get('version')!r}",
                    source=source,
                    line=number,
                )
            header = data
        elif summary is not None:
            raise TraceError("expected nothing after the summary line", source=source, line=number)
        elif kind == "step":
            steps.append(_parse_step(data, source, number))
            lines.append(number)
        elif kind == "repair":
            repairs.append(_parse_repair(data, source, number, next_step=len(steps)))
            repair_lines.append(number)
        elif kind == "summary":
            summary = data
        else:
            raise TraceError(
                f"expected a step, repair or summary line, got type {kind!r}",
                source=source,
                line=number,
            )
    if header is None:
        raise TraceError("expected a header line, got an empty file", source=source)
    return Trace(
        source, header, tuple(steps), tuple(lines), summary, tuple(repairs), tuple(repair_lines)
    )


def read_trace(path: str | Path) -> Trace:
    """Read and parse a trace file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise TraceError(f"cannot read trace file: {exc.strerror}", source=str(path)) from None
    except UnicodeDecodeError:
        raise TraceError("expected a UTF-8 JSON Lines trace", source=str(path)) from None
    return parse_trace(text, source=str(path))


def spec_from_header(header: Mapping[str, Any], source: str = "<trace>") -> MissionSpec:
    """The mission spec a trace header describes (so the mission can be run again)."""
    try:
        maze_data = header["maze"]
        maze: Maze = parse_maze(
            "\n".join(maze_data["rows"]), source=source, name=str(maze_data.get("name", ""))
        )
        start = _parse_pose(header["start"], source, 1, "'start'")
        gx, gy = header["goal"]
        heading = header.get("goal_heading")
        options = header.get("options", {})
        planner = header.get("planner", {})
        return MissionSpec(
            maze=maze,
            start=start,
            goal=(int(gx), int(gy)),
            goal_heading=None if heading is None else Heading[heading],
            schedule=FaultSchedule.from_json(header.get("schedule", {}), source),
            strategy=str(header.get("strategy", "replacement")),
            options=StrategyOptions(
                table=str(options.get("table", "handwritten")),
                recursion=str(options.get("recursion", "flat")),
                max_depth=int(options.get("max_depth", 2)),
                window=int(options.get("window", 3)),
                lookahead_expansions=int(options.get("lookahead_expansions", 20_000)),
            ),
            clearance_weight=Fraction(str(planner.get("clearance_weight", "0"))),
            clearance_radius=int(planner.get("clearance_radius", 2)),
            seed=int(header.get("seed", 0)),
            heuristic=str(planner.get("heuristic", "grid-distance")),
            backend=str(planner.get("backend", "auto")),
            replan_max_expansions=planner.get("max_expansions"),
            initial_faults_known=bool(header.get("initial_faults_known", False)),
            max_steps=header.get("max_steps"),
        )
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        # AttributeError: a field that must be an object (options, planner, schedule) is not
        if isinstance(exc, InputError):
            raise
        raise TraceError(f"expected a complete header: {exc!r}", source=source, line=1) from None


@dataclass(frozen=True, slots=True)
class ReplayReport:
    """The outcome of a replay. ``ok`` when every step holds; otherwise ``first_bad_step`` (the
    step number, or ``None`` for a problem with the summary), its ``line`` and the ``reason``."""

    ok: bool
    steps_checked: int
    first_bad_step: int | None = None
    line: int | None = None
    reason: str = ""

    def __str__(self) -> str:
        if self.ok:
            return f"ok: {self.steps_checked} steps replay"
        where = "summary" if self.first_bad_step is None else f"step {self.first_bad_step}"
        return f"{where} (line {self.line}) does not hold: {self.reason}"


def replay(trace: Trace | str | Path) -> ReplayReport:
    """Re-simulate every step of ``trace`` and report the first one that does not hold.

    Every step must start where the previous one ended and use an action available under the
    faults it recorded as known; with detection ``now`` those must be the faults the sensors
    report at that step (the true ones). A moving step must also be allowed by the true faults
    of the schedule at that step, sweep only free cells, and end at the pose and after the
    duration that :func:`selfrepair.robots.four_wheel.step` gives. A failed attempt must use an action the
    true faults forbid, stay put and last one tick. The summary, when present, must agree on the
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
    if step.step != index:
        return f"expected step number {index}, got {step.step}"
    if step.start != pose:
        return f"starts at {step.start}, but the robot is at {pose}"
    true = spec.schedule.active_faults(index, ticks, spec.seed)
    if spec.schedule.detection == "now" and step.known != true:
        return (
            f"records the known faults {four_wheel.format_faults(step.known) or 'none'}, but with "
            f"detection 'now' the robot senses {four_wheel.format_faults(true) or 'none'}"
        )
    if not four_wheel.available(step.action, step.known):
        return f"{step.action} uses a known-faulty command ({four_wheel.format_faults(step.known)})"
    if step.source == "failed-attempt":
        if four_wheel.available(step.action, true):
            return f"a failed attempt of {step.action}, but no true fault forbids it"
        if step.end != step.start or step.duration != FAILED_ATTEMPT_TICKS:
            return "a failed attempt must stay put and last one tick"
        return None
    if not four_wheel.available(step.action, true):
        return f"{step.action} is forbidden by the true faults {four_wheel.format_faults(true)}"
    end, swept, duration = four_wheel.step(pose, step.action)
    if not spec.maze.all_free(swept):
        return f"{step.action} at {pose} sweeps a wall or leaves the grid"
    if end != step.end:
        return f"{step.action} from {pose} ends at {end}, trace says {step.end}"
    if duration != step.duration:
        return f"{step.action} lasts {duration} ticks, trace says {step.duration}"
    return None


def _check_summary(trace: Trace, spec: MissionSpec, pose: Pose, ticks: Fraction) -> ReplayReport:
    count = len(trace.steps)
    summary = trace.summary
    if summary is None:
        return ReplayReport(True, count)
    line = max((*trace.step_lines[-1:], *trace.repair_lines[-1:]), default=1) + 1
    at_goal = pose.cell == spec.goal and (
        spec.goal_heading is None or pose.heading == spec.goal_heading
    )
    if summary.get("steps") != count:
        return ReplayReport(
            False,
            count,
            None,
            line,
            f"summary says {summary.get('steps')} steps, the trace has {count}",
        )
    if summary.get("final_pose") != str(pose):
        return ReplayReport(
            False,
            count,
            None,
            line,
            f"summary says final pose {summary.get('final_pose')}, replay ends at {pose}",
        )
    if (summary.get("status") == "reached") != at_goal:
        return ReplayReport(
            False,
            count,
            None,
            line,
            f"summary status {summary.get('status')!r} but the replay "
            f"{'ends' if at_goal else 'does not end'} at the goal",
        )
    if summary.get("ticks") != str(ticks):
        return ReplayReport(
            False,
            count,
            None,
            line,
            f"summary says {summary.get('ticks')} ticks, replay takes {ticks}",
        )
    return ReplayReport(True, count)
