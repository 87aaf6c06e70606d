"""Writing team traces: a :class:`~selfrepair.team.result.TeamResult` as JSON Lines (format in
:mod:`selfrepair.team.traceformat`)."""

from __future__ import annotations

import json
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.execution.traceformat import header_start
from selfrepair.robots.domain import SomeDomain
from selfrepair.team.metrics import team_row
from selfrepair.team.result import MoveRecord, TeamResult
from selfrepair.team.robottable import robot_table_label
from selfrepair.team.traceformat import (
    TEAM_TRACE_FORMAT,
    TEAM_TRACE_VERSION,
    cell_json,
    maze_digest,
    pose_json,
)
from selfrepair.world.maze import format_maze

__all__ = ["header_json", "team_trace_lines", "write_team_trace"]


def header_json(result: TeamResult) -> dict[str, Any]:
    """The header line's object for ``result``."""
    scenario, options = result.scenario, result.options
    rows = format_maze(scenario.maze).splitlines()
    return {
        **header_start(TEAM_TRACE_FORMAT, TEAM_TRACE_VERSION, scenario.domain.name),
        "scenario": scenario.name,
        "scenario_file": {"path": scenario.source, "sha256": scenario.digest},
        "scale": result.scale,
        "maze": {"name": scenario.maze.name, "rows": rows, "sha256": maze_digest(rows)},
        "robots": [
            {"name": r.name, "start": pose_json(r.start), "gripper": r.gripper}
            for r in scenario.robots
        ],
        "tasks": [
            {"item": t.item, "pickup": cell_json(t.pickup), "dropoff": cell_json(t.dropoff)}
            for t in scenario.tasks
        ],
        "faults": [
            {
                "kind": f.kind.value,
                "robot": f.robot,
                "cells": [cell_json(c) for c in f.cells],
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
        **({"world": scenario.world.to_json()} if scenario.world else {}),
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
        "robot_table": robot_table_label(scenario, options),
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
            (o.at, 3, {"type": "own-repair", "at": o.at, "robot": o.robot,
                       "pose": pose_json(o.pose), "action": domain.format_action(o.action),
                       "status": o.status.value, "source": o.source.value,
                       "actions": [domain.format_action(a) for a in o.actions],
                       "latency_ns": o.latency_ns})
        )  # fmt: skip
    for a in result.acts:
        events.append(
            (a.start, 4, {"type": "act", "start": a.start, "end": a.end, "action": str(a.action),
                          "cells": [cell_json(c) for c in a.cells]})
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


def _move_json(domain: SomeDomain, m: MoveRecord) -> dict[str, Any]:
    return {
        "type": "move",
        "robot": m.robot,
        "start": m.start,
        "end": m.end,
        "action": domain.format_action(m.action),
        "from": pose_json(m.before),
        "to": pose_json(m.after),
        "source": m.source.value,
    }


def write_team_trace(
    result: TeamResult, path: str | Path, baseline: Fraction | None = None
) -> None:
    """Write the trace of ``result`` to ``path``."""
    Path(path).write_text("\n".join(team_trace_lines(result, baseline)) + "\n", encoding="utf-8")
