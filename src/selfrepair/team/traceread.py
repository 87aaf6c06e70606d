"""Reading team traces: JSON Lines into a type-checked
:class:`~selfrepair.team.traceformat.TeamTrace` (format in :mod:`selfrepair.team.traceformat`);
every problem is a :class:`~selfrepair.errors.TraceError` naming the file and line."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from selfrepair.errors import InputError, TraceError
from selfrepair.execution.faults import Detection, Persistence
from selfrepair.execution.result import StepSource
from selfrepair.execution.traceformat import TraceFields
from selfrepair.execution.traceread import read_trace_text
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.repair.replacement import RecursionMode
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.registry import PluginFile, get_domain, load_recorded_plugin
from selfrepair.team.model import (
    RobotSpec,
    Task,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    Trigger,
    parse_team_action,
)
from selfrepair.team.result import TeamOptions
from selfrepair.team.traceformat import (
    TEAM_TRACE_FORMAT,
    TEAM_TRACE_VERSIONS,
    TeamTrace,
    TraceAct,
    TraceFault,
    TraceMove,
)
from selfrepair.world.events import WorldSchedule
from selfrepair.world.maze import parse_maze

__all__ = ["is_team_trace", "parse_team_trace", "read_team_trace"]


def is_team_trace(path: str | Path) -> bool:
    """Whether the first line of ``path`` is a team trace header."""
    try:
        with Path(path).open(encoding="utf-8") as handle:
            first = handle.readline()
        data = json.loads(first)
    except (OSError, ValueError, UnicodeDecodeError):
        return False
    return isinstance(data, dict) and data.get("format") == TEAM_TRACE_FORMAT


def read_team_trace(
    path: str | Path, *, partial: bool = False, max_trace_bytes: int | None = MAX_TRACE_BYTES
) -> TeamTrace:
    """Read and type-check a team trace; a trace without its summary is refused unless
    ``partial`` (it was cut short), a file over ``max_trace_bytes`` before it is read."""
    file = Path(path)
    text = read_trace_text(file, "team trace", max_trace_bytes)
    return parse_team_trace(text, source=str(file), partial=partial)


def parse_team_trace(text: str, *, source: str = "<trace>", partial: bool = False) -> TeamTrace:
    """Parse team trace ``text`` (see :func:`read_team_trace`)."""
    lines = [(n, line) for n, line in enumerate(text.splitlines(), start=1) if line.strip()]
    if not lines:
        raise TraceError("expected a team trace, got an empty file", source=source)
    objects = []
    for n, line in lines:
        try:
            data = json.loads(line)
        except json.JSONDecodeError as exc:
            raise TraceError(f"expected a JSON object: {exc.msg}", source=source, line=n) from None
        if not isinstance(data, dict):
            raise TraceError("expected a JSON object", source=source, line=n)
        objects.append(TraceFields(data, source, n))
    scenario, options, scale = _header(objects[0])
    domain = scenario.domain
    moves, acts, faults, other, other_lines = [], [], [], [], []
    summary: Mapping[str, Any] | None = None
    for f in objects[1:]:
        kind = f.data.get("type")
        if summary is not None:
            raise f.fail("expected nothing after the summary line")
        if kind == "move":
            moves.append(_move(f, domain))
        elif kind == "act":
            acts.append(
                TraceAct(f.integer("start", minimum=0), f.integer("end", minimum=0),
                         f.parsed("team action", parse_team_action, f.text("action")),
                         f.cells("cells"), f.line)
            )  # fmt: skip
        elif kind == "fault":
            active = f.get("active")
            if not isinstance(active, bool):
                raise f.fail(f"expected 'active' true or false, got {active!r}")
            index = f.integer("index", minimum=0)
            if index >= len(scenario.faults):
                raise f.fail(f"expected a fault index below {len(scenario.faults)}, got {index}")
            faults.append(TraceFault(f.integer("at", minimum=0), index, active, f.line))
        elif kind in ("incident", "repair", "own-repair"):
            other.append(f.data)
            other_lines.append(f.line)
        elif kind == "summary":
            summary = f.data
        else:
            raise f.fail(
                f"expected a move, act, fault, incident, repair or summary line, got {kind!r}"
            )
    if summary is None and not partial:
        raise TraceError(
            f"the trace is truncated after {len(moves)} moves (no summary line)", source=source
        )
    return TeamTrace(
        source, scenario, options, scale, objects[0].data, tuple(moves), tuple(acts),
        tuple(faults), tuple(other), summary, tuple(other_lines),
    )  # fmt: skip


def _move(f: TraceFields, domain: SomeDomain) -> TraceMove:
    source = f.text("source")
    if source not in {s.value for s in StepSource}:
        raise f.fail(
            f"expected 'source' in {', '.join(s.value for s in StepSource)}, got {source!r}"
        )
    return TraceMove(
        f.text("robot"), f.integer("start", minimum=0), f.integer("end", minimum=0),
        f.parsed("action", domain.parse_action, f.text("action")),
        f.pose("from"), f.pose("to"), StepSource(source), f.line,
    )  # fmt: skip


def _header(f: TraceFields) -> tuple[TeamScenario, TeamOptions, int]:
    if f.data.get("type") != "header" or f.data.get("format") != TEAM_TRACE_FORMAT:
        raise f.fail(f'expected a header line with "format": "{TEAM_TRACE_FORMAT}"')
    if f.data.get("version") not in TEAM_TRACE_VERSIONS:
        versions = " or ".join(str(v) for v in TEAM_TRACE_VERSIONS)
        raise f.fail(f"expected team trace version {versions}, got {f.data.get('version')!r}")
    name = f.text("domain")
    plugin = f.data.get("plugin")  # the plug-in file of a plug-in robot, else absent
    if plugin is not None:
        if not (
            isinstance(plugin, dict)
            and isinstance(plugin.get("path"), str)
            and isinstance(plugin.get("sha256"), str)
        ):
            raise f.fail(f'expected plugin {{"path": ..., "sha256": ...}}, got {plugin!r}')
        try:
            load_recorded_plugin(name, PluginFile(plugin["path"], plugin["sha256"]), "team trace")
        except InputError as exc:
            raise f.fail(exc.reason) from None
    domain = f.parsed("domain", get_domain, name)
    maze_data = f.get("maze")
    if not isinstance(maze_data, dict) or not isinstance(maze_data.get("rows"), list):
        raise f.fail("expected 'maze' with 'rows'")
    maze = f.parsed(
        "maze", lambda t: parse_maze(t, source=f.source, name=str(maze_data.get("name", ""))),
        "\n".join(str(r) for r in maze_data["rows"]),
    )  # fmt: skip
    robots = []
    for r in _list(f, "robots"):
        line = TraceFields(r, f.source, f.line)
        robots.append(
            RobotSpec(line.text("name"), line.pose("start"), bool(r.get("gripper", True)))
        )
    tasks = []
    for t in _list(f, "tasks"):
        line = TraceFields(t, f.source, f.line)
        tasks.append(
            Task(line.text("item"), line.cell(line.get("pickup")), line.cell(line.get("dropoff")))
        )
    faults = [_fault(TraceFields(d, f.source, f.line)) for d in _list(f, "faults")]
    options = _options(f)
    try:
        detection = Detection(f.data.get("detection", "now"))
    except ValueError:
        raise f.fail(
            f"expected 'detection' now or on-use, got {f.data.get('detection')!r}"
        ) from None
    world_data = f.data.get("world", {})
    if not isinstance(world_data, dict):
        raise f.fail(f"expected 'world' to be an object, got {world_data!r}")
    scenario = TeamScenario(
        maze, tuple(robots), tuple(tasks), tuple(faults), domain,
        str(f.data.get("scenario", "")), f.source, detection=detection,
        world=WorldSchedule.from_json(world_data, f.source),
    )  # fmt: skip
    scale = f.integer("scale", minimum=1)
    if scale != domain.time_unit:
        raise f.fail(f"expected 'scale' {domain.time_unit} for domain {domain.name}, got {scale}")
    return scenario, options, scale


def _fault(f: TraceFields) -> TeamFault:
    d = f.data
    try:
        return TeamFault(
            TeamFaultKind(d["kind"]),
            str(d.get("robot", "")),
            tuple(f.cell(c) for c in d.get("cells", [])),
            str(d.get("wheel_faults", "")),
            int(d.get("at", 0)),
            Trigger(d.get("trigger", "tick")),
            Persistence(d.get("persistence", "permanent")),
            d.get("duration"),
            None if d.get("probability") is None else float(d["probability"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, TraceError):
            raise
        raise f.fail(f"bad fault {dict(d)!r}: {exc}") from None


def _options(f: TraceFields) -> TeamOptions:
    o = f.get("options")
    if not isinstance(o, dict):
        raise f.fail("expected 'options' to be an object")
    try:
        return TeamOptions(
            o["strategy"],
            o["table"],
            o["robot_strategy"],
            o["robot_table"],
            RecursionMode(o["recursion"]),
            int(o["max_depth"]),
            str(o["backend"]),
            o["max_ticks"],
            int(o["max_wait_ticks"]),
            int(o["spacetime_expansions"]),
            int(o["seed"]),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise f.fail(f"bad options: {exc}") from None


def _list(f: TraceFields, key: str) -> list[dict[str, Any]]:
    value = f.get(key)
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise f.fail(f"expected {key!r} to be a list of objects")
    return value
