"""The team viewer: one self-contained HTML page that replays a team mission on one timeline.

:func:`team_payload` turns a parsed team trace (:mod:`selfrepair.team.traceformat`) that
re-simulates into the page's data: the maze, every robot (colour, equipment), the tasks, and one
frame per instant at which something happens (a move or act starts or ends, a fault starts or
clears, a world event blocks or frees a cell, an incident, a repair), each with every robot's
pose, the cells it holds (its move's footprint while moving, its cell while resting: what the
reservations gave it), what it carries and what it is doing, where every item lies, which team
faults are active and which cells are blocked then (by world events, computed from the header's
schedule, and by blocked team faults: the page greys them out, as the mission page does). The
timeline has
one lane per robot (its moves coloured by source, its acts, incidents and repairs) and one per
team fault. Every pose and footprint comes from the robot model; the page's script only draws.
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.experiment.figstyle import SOURCE_COLOURS
from selfrepair.experiment.viewpage import check_viewable, pose_json, wall_runs, write_page
from selfrepair.geometry import Cell, Pose
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.team.model import ActionKind, TeamFaultKind
from selfrepair.team.replay import replay_team
from selfrepair.team.traceformat import TeamTrace
from selfrepair.team.traceread import read_team_trace

__all__ = [
    "TEAM_VIEWER_FORMAT",
    "TEAM_VIEWER_VERSION",
    "team_payload",
    "view_team_results",
    "view_team_trace",
]

TEAM_VIEWER_FORMAT = "selfrepair-team-viewer"
TEAM_VIEWER_VERSION = 1

ROBOT_COLOURS = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#D55E00", "#F0E442")
"""Robot colours, by the robot's place in the scenario (Okabe-Ito, colour-blind safe)."""

MOVE_COLOURS = {str(source): colour for source, colour in SOURCE_COLOURS.items()}
"""Move colours on the timeline by step source: the figures' and the mission page's."""


def _tick(units: int, scale: int) -> str:
    return str(Fraction(units, scale))


def _instants(trace: TeamTrace) -> list[int]:
    """Every unit at which something happens, in order, from 0."""
    times = {0}
    for m in trace.moves:
        times.update((m.start, m.end))
    for a in trace.acts:
        times.update((a.start, a.end))
    times.update(f.at for f in trace.faults)
    times.update(int(o["at"]) for o in trace.other if isinstance(o.get("at"), int))
    end = max(times)
    changes = (e.at * trace.scale for e in trace.scenario.world.events)
    times.update(u for u in changes if u <= end)  # a cell greys out (or clears) at its time
    return sorted(times)


def _frames(trace: TeamTrace, times: list[int]) -> list[dict[str, Any]]:
    """The state of the team at each instant (see the module docstring)."""
    scenario, domain = trace.scenario, trace.scenario.domain
    world = scenario.world
    moves = sorted(trace.moves, key=lambda m: (m.end, m.line))  # applied as they end
    acts = sorted(trace.acts, key=lambda a: (a.end, a.line))
    pose: dict[str, Pose] = {r.name: r.start for r in scenario.robots}
    floor: dict[str, Cell | None] = {t.item: t.pickup for t in scenario.tasks}
    carrier: dict[str, str] = {}
    delivered: set[str] = set()
    active: dict[int, bool] = {}
    faults = sorted(trace.faults, key=lambda f: (f.at, f.line))
    m_next = a_next = f_next = 0
    frames = []
    for t in times:
        while m_next < len(moves) and moves[m_next].end <= t:
            pose[moves[m_next].robot] = moves[m_next].after
            m_next += 1
        while a_next < len(acts) and acts[a_next].end <= t:
            act = acts[a_next].action
            if act.kind is ActionKind.PICK:
                floor[act.item], carrier[act.item] = None, act.robot
            elif act.kind is ActionKind.DROP:
                del carrier[act.item]
                floor[act.item] = acts[a_next].cells[0]
                if floor[act.item] == scenario.task(act.item).dropoff:
                    delivered.add(act.item)
            else:
                carrier[act.item] = act.taker
            a_next += 1
        while f_next < len(faults) and faults[f_next].at <= t:
            active[faults[f_next].index] = faults[f_next].active
            f_next += 1
        doing = {m.robot: m for m in moves[m_next:] if m.start <= t}  # under way at t
        acting = {r: a for a in trace.acts if a.start <= t < a.end for r in a.action.robots}
        robots = []
        for spec in scenario.robots:
            name = spec.name
            move = doing.get(name)
            held = domain.footprint(move.before, move.action) if move else (pose[name].cell,)
            what = domain.format_action(move.action) if move else None
            if name in acting:
                what = str(acting[name].action)
            robots.append({
                **pose_json(pose[name]),
                "name": name,
                "moving": move is not None,
                "held": [list(c) for c in held],
                "carrying": next((i for i, r in carrier.items() if r == name), None),
                "doing": what,
            })  # fmt: skip
        items = []
        for task in scenario.tasks:
            holder = carrier.get(task.item)
            cell = pose[holder].cell if holder else floor[task.item]
            assert cell is not None
            items.append({"item": task.item, "x": cell[0], "y": cell[1], "carrier": holder,
                          "delivered": task.item in delivered})  # fmt: skip
        on = sorted(i for i, now in active.items() if now)
        blocked = set(world.blocked_at(Fraction(t, trace.scale))) if world else set()
        for i in on:
            if scenario.faults[i].kind is TeamFaultKind.BLOCKED:
                blocked.update(scenario.faults[i].cells)
        frames.append({
            "at": t,
            "tick": _tick(t, trace.scale),
            "robots": robots,
            "items": items,
            "faults": on,
            "blocked": [list(c) for c in sorted(blocked)],
            "delivered": len(delivered),
        })  # fmt: skip
    return frames


def _frame_of(times: list[int], at: int) -> int:
    """The frame of unit ``at`` (the first instant at or after it)."""
    for index, t in enumerate(times):
        if t >= at:
            return index
    return len(times) - 1


def _events(trace: TeamTrace, times: list[int]) -> dict[str, list[dict[str, Any]]]:
    """Incidents, team repairs and own repairs as the page lists and marks them."""
    out: dict[str, list[dict[str, Any]]] = {"incident": [], "repair": [], "own-repair": []}
    for line, o in zip(trace.other_lines, trace.other, strict=False):
        at = int(o.get("at", 0))
        kind = str(o.get("type"))
        entry: dict[str, Any] = {"at": at, "tick": _tick(at, trace.scale),
                                 "frame": _frame_of(times, at), "line": line,
                                 "robot": str(o.get("robot", ""))}  # fmt: skip
        if kind == "incident":
            entry.update(action=o.get("action"), kind=o.get("kind"), load=o.get("load"))
        elif kind == "repair":
            latency = int(o.get("latency_ns", 0) or 0)
            entry.update(
                action=o.get("action"), kind=o.get("kind"), outcome=o.get("outcome"),
                source=o.get("source"), candidate=o.get("candidate") or "",
                helper=o.get("helper") or "", disturbed=list(o.get("disturbed") or []),
                latency=f"{latency / 1000:,.0f} µs", lost=list(o.get("lost") or []),
                changes={str(k): list(v) for k, v in dict(o.get("changes") or {}).items()},
            )  # fmt: skip
        else:
            entry.update(action=o.get("action"), status=o.get("status"), source=o.get("source"))
        out[kind].append(entry)
    return out


def team_payload(
    trace: TeamTrace, *, origin: Mapping[str, Any] | None = None, max_steps: int
) -> dict[str, Any]:
    """The team page's data for ``trace`` (see the module docstring). The trace must replay;
    ``max_steps`` bounds its moves and acts."""
    check = check_viewable(
        "the team trace",
        len(trace.moves) + len(trace.acts),
        "moves and acts",
        max_steps=max_steps,
        source=trace.source,
        replay=lambda: replay_team(trace),
    )
    scenario, scale = trace.scenario, trace.scale
    times = _instants(trace)
    lanes = []
    for spec in scenario.robots:
        lanes.append({
            "robot": spec.name,
            "moves": [[m.start, m.end, m.source.value] for m in trace.moves
                      if m.robot == spec.name],
            "acts": [[a.start, a.end, str(a.action)] for a in trace.acts
                     if spec.name in a.action.robots],
        })  # fmt: skip
    fault_lanes = []
    for index, fault in enumerate(scenario.faults):
        spans: list[list[int | None]] = []
        for f in sorted((f for f in trace.faults if f.index == index), key=lambda f: f.at):
            if f.active:
                spans.append([f.at, None])
            elif spans:
                spans[-1][1] = f.at
        fault_lanes.append({"index": index, "text": fault.describe(), "spans": spans})
    summary = dict(trace.summary or {})
    options = trace.options
    status = str(summary.get("status", "unfinished"))
    return {
        "format": TEAM_VIEWER_FORMAT,
        "version": TEAM_VIEWER_VERSION,
        "title": f"{scenario.name or 'team'} on {scenario.maze.name or 'the maze'}: "
        f"{len(scenario.robots)} robots, {options.label}: {status}",
        "origin": dict(origin or {"kind": "trace", "source": trace.source}),
        "replay": str(check),
        "maze": {"name": scenario.maze.name, "width": scenario.maze.width,
                 "height": scenario.maze.height, "walls": wall_runs(scenario.maze)},
        "scale": scale,
        "robots": [{"name": r.name, "gripper": r.gripper, "start": pose_json(r.start),
                    "colour": ROBOT_COLOURS[i % len(ROBOT_COLOURS)]}
                   for i, r in enumerate(scenario.robots)],
        "tasks": [{"item": t.item, "pickup": list(t.pickup), "dropoff": list(t.dropoff)}
                  for t in scenario.tasks],
        "move_colours": MOVE_COLOURS,
        "frames": _frames(trace, times),
        "lanes": lanes,
        "fault_lanes": fault_lanes,
        "end": times[-1],
        **_events(trace, times),
        "status": status,
        "summary": {k: v for k, v in summary.items() if not isinstance(v, float) or v == v},
    }  # fmt: skip


def view_team_trace(
    trace: str | Path,
    out: str | Path,
    *,
    max_steps: int,
    max_trace_bytes: int | None = MAX_TRACE_BYTES,
) -> Path:
    """Write the team page of the team trace file ``trace`` to ``out``; returns ``out``."""
    parsed = read_team_trace(trace, max_trace_bytes=max_trace_bytes)
    return write_page(team_payload(parsed, max_steps=max_steps), out, page="team")


def view_team_results(
    row: Mapping[str, Any], db: str | Path, out: str | Path, max_steps: int
) -> Path:
    """Write the team page of the stored team mission ``row`` of ``db``, run again from its
    stored configuration, to ``out``; the page says whether the re-run agrees with the row."""
    from selfrepair.experiment.teams import rerun_team_mission
    from selfrepair.team.traceread import parse_team_trace
    from selfrepair.team.tracewrite import team_trace_lines

    result, baseline = rerun_team_mission(row)
    key = str(row["key"])
    trace = parse_team_trace(
        "\n".join(team_trace_lines(result, baseline)), source=f"{db} (mission {key[:12]})"
    )
    stored = {"delivered": row.get("delivered"), "makespan": row.get("makespan")}
    again = {"delivered": len(result.delivered), "makespan": float(result.makespan)}
    origin = {"kind": "results", "source": str(db), "key": key, "agrees": stored == again,
              "experiment": row.get("experiment"), "stored": stored}  # fmt: skip
    payload = team_payload(trace, origin=origin, max_steps=max_steps)
    return write_page(payload, out, page="team")
