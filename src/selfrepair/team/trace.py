"""Team traces (JSON Lines) and their re-simulation.

A team trace has one JSON object per line, like a single-robot trace
(:mod:`selfrepair.execution.trace`) but for several robots:

1. a header (``"type": "header"``, ``"format": "selfrepair-team-trace"``, ``"version"``): the
   robot ``domain``, ``scale`` (time units per tick), the maze (name and rows), the robots
   (name, start pose, gripper), the tasks, the team faults, the options and the initial team
   plan (each robot's actions as text);
2. event lines in time order (times in units): ``fault`` (fault ``index`` became ``active`` or
   cleared), ``incident`` (robot, action, kind, load), ``repair`` (what the team strategy did:
   outcome, source, candidate, helper, pre-emption, disturbed robots, messages, plans, latency,
   the actions inserted per robot, items given up), ``own-repair`` (a robot's own single-robot
   repair), ``act`` (a pick, drop or handover with the cells its robots stood on) and ``move``
   (one primitive action of one robot: ``robot``, ``start``, ``end``, ``action``, ``from``,
   ``to`` as ``[x, y, "N"]``, ``source``);
3. the summary (``"type": "summary"``): the row of :func:`selfrepair.team.metrics.team_row`.

:func:`replay_team` re-simulates a parsed trace from its header alone and reports the first
thing that does not hold: a robot that *teleports* (a move that does not start where the
robot's previous move ended, or overlaps it in time), a move the robot model does not produce
(wrong end pose or duration), a move through a wall or a blocked cell, a move its true faults
forbid, a pick, drop or handover whose conditions do not hold, a *conflict* (two robots holding
the same cell at the same time: a moving robot holds its action's footprint, a resting one its
cell), or a summary that does not match.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.errors import TraceError
from selfrepair.execution.faults import Detection, FaultEvent, Persistence
from selfrepair.execution.result import StepSource
from selfrepair.execution.trace import TraceFields
from selfrepair.geometry import Cell, Pose
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.repair.replacement import RecursionMode
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import get_domain
from selfrepair.team.metrics import team_row
from selfrepair.team.model import (
    ActionKind,
    RobotSpec,
    Task,
    TeamAction,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    Trigger,
    parse_team_action,
    time_scale,
)
from selfrepair.team.result import MoveRecord, TeamOptions, TeamResult
from selfrepair.team.spacetime import units
from selfrepair.textio import read_text
from selfrepair.world.maze import format_maze, parse_maze

__all__ = [
    "TEAM_TRACE_FORMAT",
    "TEAM_TRACE_VERSION",
    "TeamReplayReport",
    "TeamTrace",
    "is_team_trace",
    "read_team_trace",
    "replay_team",
    "team_trace_lines",
    "write_team_trace",
]

TEAM_TRACE_FORMAT = "selfrepair-team-trace"
TEAM_TRACE_VERSION = 1


def _pose(pose: Pose) -> list[Any]:
    return [pose.x, pose.y, pose.heading.name]


def _cell(cell: Cell) -> list[int]:
    return [cell[0], cell[1]]


# --- writing --------------------------------------------------------------------------------------


def header_json(result: TeamResult) -> dict[str, Any]:
    """The header line's object for ``result``."""
    scenario, options = result.scenario, result.options
    return {
        "type": "header",
        "format": TEAM_TRACE_FORMAT,
        "version": TEAM_TRACE_VERSION,
        "scenario": scenario.name,
        "domain": scenario.domain.name,
        "scale": result.scale,
        "maze": {"name": scenario.maze.name, "rows": format_maze(scenario.maze).splitlines()},
        "robots": [
            {"name": r.name, "start": _pose(r.start), "gripper": r.gripper} for r in scenario.robots
        ],
        "tasks": [
            {"item": t.item, "pickup": _cell(t.pickup), "dropoff": _cell(t.dropoff)}
            for t in scenario.tasks
        ],
        "faults": [
            {
                "kind": f.kind.value,
                "robot": f.robot,
                "cells": [_cell(c) for c in f.cells],
                "wheel_faults": f.wheel_faults,
                "at": f.at,
                "trigger": f.trigger.value,
                "persistence": f.persistence.value,
                "duration": f.duration,
                "probability": f.probability,
            }
            for f in scenario.faults
        ],
        "detection": scenario.detection.value,
        "options": {
            "strategy": str(options.strategy),
            "table": str(options.table),
            "robot_strategy": options.robot_strategy,
            "robot_table": options.robot_table,
            "recursion": str(options.recursion),
            "max_depth": options.max_depth,
            "backend": options.backend,
            "max_ticks": options.max_ticks,
            "max_wait_ticks": options.max_wait_ticks,
            "spacetime_expansions": options.spacetime_expansions,
            "seed": options.seed,
        },
        "initial_plan": {name: [str(a) for a in actions] for name, actions in result.initial_plan},
    }


def team_trace_lines(result: TeamResult, baseline: Fraction | None = None) -> list[str]:
    """Every line of the trace of ``result`` (``baseline``: the fault-free makespan, for the
    summary row)."""
    domain = result.scenario.domain
    events: list[tuple[int, int, dict[str, Any]]] = []
    for f in result.faults:
        events.append(
            (f.at, 0, {"type": "fault", "at": f.at, "index": f.index, "active": f.active})
        )
    for i in result.incidents:
        events.append(
            (i.at, 1, {"type": "incident", "at": i.at, "robot": i.robot, "action": str(i.action),
                       "kind": i.kind.value, "load": i.load.value})
        )  # fmt: skip
    for r in result.repairs:
        events.append((r.at, 2, _repair_json(r)))
    for o in result.own_repairs:
        events.append(
            (o.at, 3, {"type": "own-repair", "at": o.at, "robot": o.robot, "pose": _pose(o.pose),
                       "action": domain.format_action(o.action), "status": o.status.value,
                       "source": o.source.value,
                       "actions": [domain.format_action(a) for a in o.actions],
                       "latency_ns": o.latency_ns})
        )  # fmt: skip
    for a in result.acts:
        events.append(
            (a.start, 4, {"type": "act", "start": a.start, "end": a.end, "action": str(a.action),
                          "cells": [_cell(c) for c in a.cells]})
        )  # fmt: skip
    for m in result.moves:
        events.append((m.start, 5, _move_json(domain, m)))
    events.sort(key=lambda e: (e[0], e[1]))
    lines = [json.dumps(header_json(result))]
    lines += [json.dumps(e[2]) for e in events]
    lines.append(json.dumps({"type": "summary", **team_row(result, baseline)}))
    return lines


def _repair_json(r: Any) -> dict[str, Any]:
    return {
        "type": "repair",
        "at": r.at,
        "robot": r.robot,
        "action": str(r.action),
        "kind": r.kind.value,
        "outcome": r.outcome.value,
        "source": r.source.value,
        "candidate": r.candidate,
        "helper": r.helper,
        "preempted": r.preempted,
        "preemption_ticks": r.preemption_ticks,
        "disturbed": list(r.disturbed),
        "messages": r.messages,
        "plans": r.plans,
        "expansions": r.expansions,
        "latency_ns": r.latency_ns,
        "cpu_ns": r.cpu_ns,
        "changes": {name: [str(a) for a in actions] for name, actions in r.changes},
        "lost": list(r.lost),
    }


def _move_json(domain: Domain[Any, Any], m: MoveRecord) -> dict[str, Any]:
    return {
        "type": "move",
        "robot": m.robot,
        "start": m.start,
        "end": m.end,
        "action": domain.format_action(m.action),
        "from": _pose(m.before),
        "to": _pose(m.after),
        "source": m.source.value,
    }


def write_team_trace(
    result: TeamResult, path: str | Path, baseline: Fraction | None = None
) -> None:
    """Write the trace of ``result`` to ``path``."""
    Path(path).write_text("\n".join(team_trace_lines(result, baseline)) + "\n", encoding="utf-8")


# --- reading --------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class TraceMove:
    """A ``move`` line, read back."""

    robot: str
    start: int
    end: int
    action: Any
    before: Pose
    after: Pose
    source: StepSource
    line: int


@dataclass(frozen=True, slots=True)
class TraceAct:
    """An ``act`` line, read back."""

    start: int
    end: int
    action: TeamAction
    cells: tuple[Cell, ...]
    line: int


@dataclass(frozen=True, slots=True)
class TraceFault:
    """A ``fault`` line, read back."""

    at: int
    index: int
    active: bool
    line: int


@dataclass(frozen=True, slots=True)
class TeamTrace:
    """A parsed team trace: the scenario and options rebuilt from the header, the scale, every
    event line (``other`` keeps incident, repair and own-repair lines as read) and the summary."""

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
    text = read_text(
        file,
        what="team trace",
        error=TraceError,
        max_bytes=max_trace_bytes,
        limit="max_trace_bytes",
    )
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
    moves, acts, faults, other = [], [], [], []
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
        tuple(faults), tuple(other), summary,
    )  # fmt: skip


def _move(f: TraceFields, domain: Domain[Any, Any]) -> TraceMove:
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
    if f.data.get("version") != TEAM_TRACE_VERSION:
        raise f.fail(
            f"expected team trace version {TEAM_TRACE_VERSION}, got {f.data.get('version')!r}"
        )
    domain = f.parsed("domain", get_domain, f.text("domain"))
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
    scenario = TeamScenario(
        maze, tuple(robots), tuple(tasks), tuple(faults), domain,
        str(f.data.get("scenario", "")), f.source, detection=detection,
    )  # fmt: skip
    scale = f.integer("scale", minimum=1)
    if scale != time_scale(domain):
        raise f.fail(f"expected 'scale' {time_scale(domain)} for domain {domain.name}, got {scale}")
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


# --- replay ---------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class TeamReplayReport:
    """What :func:`replay_team` found: ``ok``, the first problem (with its trace line) and how
    much was checked."""

    ok: bool
    problem: str
    line: int | None
    moves: int
    acts: int
    delivered: int

    def __str__(self) -> str:
        if self.ok:
            return (
                f"ok: {self.moves} moves and {self.acts} acts re-simulated, no conflict, no "
                f"teleport, {self.delivered} items delivered"
            )
        where = f"line {self.line}: " if self.line is not None else ""
        return f"{where}{self.problem}"


class _Problem(Exception):
    def __init__(self, what: str, line: int | None) -> None:
        super().__init__(what)
        self.what, self.line = what, line


def replay_team(trace: TeamTrace) -> TeamReplayReport:
    """Re-simulate ``trace`` (see the module docstring)."""
    delivered = 0
    try:
        active = _active_faults(trace)
        _check_moves(trace, active)
        delivered = _check_acts(trace, active)
        _check_conflicts(trace)
        _check_summary(trace, delivered)
    except _Problem as problem:
        return TeamReplayReport(
            False, problem.what, problem.line, len(trace.moves), len(trace.acts), delivered
        )
    return TeamReplayReport(True, "", None, len(trace.moves), len(trace.acts), delivered)


def _active_faults(trace: TeamTrace) -> list[tuple[int, int | None, TeamFault]]:
    """Each fault's active stretch ``[on, off)`` (``off`` None: for good), computed from the
    header - a tick, or the end of the robot's first pick in the acts, plus ``at`` - and
    checked against the trace's fault lines."""
    scale = trace.scale
    first_pick: dict[str, int] = {}
    for act in sorted(trace.acts, key=lambda a: a.start):
        if act.action.kind is ActionKind.PICK:
            first_pick.setdefault(act.action.robot, act.end)
    horizon = max([m.end for m in trace.moves] + [a.end for a in trace.acts] + [0])
    spans: list[tuple[int, int | None, TeamFault]] = []
    for index, fault in enumerate(trace.scenario.faults):
        if fault.trigger is Trigger.TICK:
            on: int | None = fault.at * scale
        else:
            picked = first_pick.get(fault.robot)
            on = None if picked is None else picked + fault.at * scale
        if on is None:
            continue
        off = None if fault.duration is None else on + fault.duration * scale
        lines = [f for f in trace.faults if f.index == index]
        expected = [(on, True)] + ([] if off is None else [(off, False)])
        got = [(f.at, f.active) for f in lines]
        if got != expected[: len(got)] or (on < horizon and not got):
            line = lines[0].line if lines else None
            raise _Problem(
                f"fault {index} ({fault.describe()}) is logged as {got}, not {expected}", line
            )
        spans.append((on, off, fault))
    return spans


def _faults_at(spans: list[tuple[int, int | None, TeamFault]], t: int) -> list[TeamFault]:
    return [f for on, off, f in spans if on <= t and (off is None or t < off)]


def _check_moves(trace: TeamTrace, spans: list[tuple[int, int | None, TeamFault]]) -> None:
    scenario, domain, scale = trace.scenario, trace.scenario.domain, trace.scale
    maze = scenario.maze
    names = {r.name for r in scenario.robots}
    last: dict[str, tuple[Pose, int]] = {r.name: (r.start, 0) for r in scenario.robots}
    steps = dict.fromkeys(names, 0)  # each robot's commands so far (its intermittent draws)
    for m in sorted(trace.moves, key=lambda m: (m.start, m.line)):
        if m.robot not in names:
            raise _Problem(f"move of unknown robot {m.robot!r}", m.line)
        pose, free_at = last[m.robot]
        if m.before != pose:
            raise _Problem(
                f"teleport: {m.robot} moves from {m.before} but stands at {pose}", m.line
            )
        if m.start < free_at:
            raise _Problem(
                f"{m.robot} starts a move at {m.start} before its last one ends ({free_at})", m.line
            )
        faults, blocked = _truth(trace, spans, m.robot, m.start, steps[m.robot])
        steps[m.robot] += 1
        name = domain.format_action(m.action)
        if m.source is StepSource.FAILED_ATTEMPT:
            if m.after != m.before or m.end - m.start != scale:
                raise _Problem(f"{m.robot}'s failed attempt moves or lasts not one tick", m.line)
            if domain.available(m.action, faults):
                raise _Problem(
                    f"{m.robot}'s {name} is logged as failed, but its true faults allow it", m.line
                )
            continue
        if domain.apply(m.before, m.action) != m.after:
            raise _Problem(f"{name} from {m.before} does not end at {m.after}", m.line)
        if m.end - m.start != units(domain, m.action, scale):
            raise _Problem(
                f"{name} takes {units(domain, m.action, scale)} units, not {m.end - m.start}",
                m.line,
            )
        cells = domain.footprint(m.before, m.action)
        if not maze.all_free(cells):
            raise _Problem(f"{m.robot}'s move sweeps a wall", m.line)
        if any(c in blocked for c in cells[1:]):
            raise _Problem(f"{m.robot}'s move sweeps a blocked cell", m.line)
        if not domain.available(m.action, faults):
            raise _Problem(f"{m.robot} moves with {name}, which its faults forbid", m.line)
        last[m.robot] = (m.after, m.end)


def _truth(
    trace: TeamTrace,
    spans: list[tuple[int, int | None, TeamFault]],
    robot: str,
    t: int,
    step: int,
) -> tuple[frozenset[Any], set[Cell]]:
    """The true domain faults of ``robot`` at ``t`` (its command number ``step``: an
    intermittent fault is drawn as :class:`~selfrepair.team.state.RobotFaultClock` draws it,
    from the options' seed) and the blocked cells."""
    domain = trace.scenario.domain
    faults: set[Any] = set()
    blocked: set[Cell] = set()
    for f in _faults_at(spans, t):
        if f.kind is TeamFaultKind.BLOCKED:
            blocked.update(f.cells)
            continue
        if f.robot != robot or f.kind not in (TeamFaultKind.IMMOBILISED, TeamFaultKind.WHEELS):
            continue
        if f.persistence is Persistence.INTERMITTENT:
            index = next(i for i, g in enumerate(trace.scenario.faults) if g is f)
            draw = FaultEvent(None, persistence=Persistence.INTERMITTENT, probability=f.probability)
            if not draw.active(index, step, Fraction(0), trace.options.seed):
                continue
        if f.kind is TeamFaultKind.IMMOBILISED:
            faults.update(domain.faults)
        else:
            faults |= domain.parse_faults(f.wheel_faults)
    return frozenset(faults), blocked


def _check_acts(trace: TeamTrace, spans: list[tuple[int, int | None, TeamFault]]) -> int:
    """Item logic of every act, in time order; returns the items delivered."""
    scenario = trace.scenario
    tasks = {t.item: t for t in scenario.tasks}
    floor: dict[str, Cell | None] = {t.item: t.pickup for t in scenario.tasks}
    holder: dict[str, str] = {}
    carrying: dict[str, str] = {}
    gripper = {r.name: r.gripper for r in scenario.robots}
    delivered = set()
    for a in sorted(trace.acts, key=lambda a: (a.start, a.line)):
        action = a.action
        if action.item not in tasks:
            raise _Problem(f"act on unknown item {action.item!r}", a.line)
        for robot, cell in zip(action.robots, a.cells, strict=False):
            if _pose_at(trace, robot, a.start).cell != cell or _moving(
                trace, robot, a.start, a.end
            ):
                raise _Problem(f"{robot} is not resting on {cell} during {action}", a.line)
        broken = {f.robot for f in _faults_at(spans, a.start) if f.kind is TeamFaultKind.GRIPPER}
        grips = {r for r, g in gripper.items() if g and r not in broken}
        item = action.item
        if action.kind is ActionKind.PICK:
            if action.robot not in grips or action.robot in carrying or floor[item] != a.cells[0]:
                raise _Problem(f"{action} cannot happen (gripper, load or item place)", a.line)
            floor[item], holder[item], carrying[action.robot] = None, action.robot, item
        elif action.kind is ActionKind.DROP:
            if action.robot not in grips or holder.get(item) != action.robot:
                raise _Problem(f"{action} cannot happen (gripper or load)", a.line)
            del holder[item], carrying[action.robot]
            floor[item] = a.cells[0]
            if a.cells[0] == tasks[item].dropoff:
                delivered.add(item)
        else:
            (gx, gy), (tx, ty) = a.cells
            if abs(gx - tx) + abs(gy - ty) != 1 or holder.get(item) != action.robot:
                raise _Problem(
                    f"{action} cannot happen (not adjacent, or the giver lacks the item)", a.line
                )
            if action.taker not in grips or action.taker in carrying:
                raise _Problem(f"{action} cannot happen (the taker cannot take it)", a.line)
            del carrying[action.robot]
            holder[item], carrying[action.taker] = action.taker, item
    return len(delivered)


def _pose_at(trace: TeamTrace, robot: str, t: int) -> Pose:
    pose = trace.scenario.robot(robot).start
    for m in trace.moves:  # in time order
        if m.robot == robot and m.end <= t:
            pose = m.after
    return pose


def _moving(trace: TeamTrace, robot: str, start: int, end: int) -> bool:
    return any(m.robot == robot and m.start < end and start < m.end for m in trace.moves)


def _check_conflicts(trace: TeamTrace) -> None:
    """No two robots hold one cell at the same time (moving: footprint; resting: cell)."""
    domain = trace.scenario.domain
    horizon = max([m.end for m in trace.moves] + [a.end for a in trace.acts] + [0]) + 1
    by_cell: dict[Cell, list[tuple[int, int, str, int]]] = {}
    for robot in trace.scenario.robots:
        moves = sorted((m for m in trace.moves if m.robot == robot.name), key=lambda m: m.start)
        pose, since, line = robot.start, 0, 1
        for m in moves:
            by_cell.setdefault(pose.cell, []).append((since, m.start, robot.name, line))
            held = (
                (m.before.cell,)
                if m.source is StepSource.FAILED_ATTEMPT
                else domain.footprint(m.before, m.action)
            )  # a failed attempt holds the robot's cell
            for cell in held:
                by_cell.setdefault(cell, []).append((m.start, m.end, robot.name, m.line))
            pose, since, line = m.after, m.end, m.line
        by_cell.setdefault(pose.cell, []).append((since, horizon, robot.name, line))
    first: tuple[int, str, int] | None = None
    for cell, spans in by_cell.items():
        spans.sort()
        for i, (s1, e1, r1, l1) in enumerate(spans):
            for s2, e2, r2, l2 in spans[i + 1 :]:
                if s2 >= e1:
                    break
                if r1 != r2 and s2 < e1 and s1 < e2:
                    at = max(s1, s2)
                    text = (
                        f"conflict: {r1} and {r2} both hold cell {cell[0]},{cell[1]} at unit {at}"
                    )
                    if first is None or at < first[0]:
                        first = (at, text, max(l1, l2))
    if first is not None:
        raise _Problem(first[1], first[2])


def _check_summary(trace: TeamTrace, delivered: int) -> None:
    summary = trace.summary
    if summary is None:
        return
    if summary.get("delivered") != delivered:
        raise _Problem(
            f"the summary says {summary.get('delivered')} items delivered, the acts deliver "
            f"{delivered}",
            None,
        )
    if summary.get("moves") != len(trace.moves) or summary.get("acts") != len(trace.acts):
        raise _Problem("the summary's move or act count does not match the trace", None)
