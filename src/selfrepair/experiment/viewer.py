"""The mission viewer: one self-contained HTML page that replays a mission step by step.

:func:`mission_payload` turns a parsed trace into a JSON-able payload: the maze as wall runs, the
initial plan and every executed step as drawable segments, the robot's pose and heading after
each step, the true faults (from the header's fault schedule) and the known faults (from the
step lines) at each step, the fault events, and every repair (from the trace's repair lines) with
where it came from (table candidate, lookahead window or replan), what it spliced in and its
latency, and with the faults hidden what the robot believed after each step
(:mod:`selfrepair.experiment.viewdiagnosis`). Every pose, heading vector, swept cell and fault
set comes from the library (the robot model, the schedule); the page's script only draws.

:func:`render_html` puts the payload, the page template, its CSS and its script (package data in
``selfrepair/data/viewer/``) into one HTML file that needs no server and no network: everything
is inline, and the page's content security policy forbids loading anything.

:func:`view_trace` and :func:`view_results` are what ``selfrepair view`` runs: the first reads a
trace file; the second re-runs a mission stored in a results database (as the report does, see
:func:`selfrepair.experiment.reportmission.rerun_mission`) to get its trace.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any, TypeVar

from selfrepair.errors import InputError, TraceError
from selfrepair.execution.faults import Detection, canonical_order
from selfrepair.execution.result import MissionSpec, StepSource, TraceStep
from selfrepair.execution.trace import Trace, TraceRepair, parse_trace, replay, spec_from_header
from selfrepair.experiment.figstyle import SOURCE_COLOURS
from selfrepair.experiment.viewdiagnosis import diagnosis_json
from selfrepair.experiment.viewpage import (
    check_viewable,
    pose_json,
    render_html,
    wall_runs,
    write_page,
)
from selfrepair.geometry import Cell, Pose, turn_corner
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.repair.strategies import RepairSource, StrategyName, uses_table
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "MAX_VIEW_STEPS",
    "VIEWER_FORMAT",
    "VIEWER_VERSION",
    "mission_payload",
    "render_html",
    "tolerance_json",
    "trace_from_results",
    "view_results",
    "view_trace",
    "wall_runs",
]

VIEWER_FORMAT = "selfrepair-viewer"
VIEWER_VERSION = 1

MAX_VIEW_STEPS = 50_000
"""Default bound on the steps of a viewed mission (about 400 bytes of page each); raise it with
``selfrepair view --max-steps``."""

REPAIR_SOURCE_NAMES = {
    "replacement": "table replacement",
    "lookahead": "lookahead window",
    "replan": "replan",
    "plan-repair": "plan repair (LPG-adapt)",
}


# --- payload ------------------------------------------------------------------------------------


def segment_json(domain: SomeDomain, start: Pose, action: object) -> dict[str, Any]:
    """What ``action`` does from ``start`` according to the robot's domain, for drawing: end
    pose, the kind of move (from the geometry: ``wait``, ``turn``, ``straight`` or ``arc``),
    footprint cells and, for an arc, the cell it passes first (the curve's corner)."""
    end, swept, _ = domain.step(start, action)
    kind, via = _shape(start, end, swept)
    return {
        "action": domain.format_action(action),
        "from": pose_json(start),
        "to": pose_json(end),
        "kind": kind,
        "swept": [list(c) for c in swept],
        "via": None if via is None else list(via),
    }


def _shape(start: Pose, end: Pose, swept: Sequence[Cell]) -> tuple[str, Cell | None]:
    """How a move looks: in place (``wait``/``turn``), without turning (``straight``), or moving
    and turning (``arc``, drawn through its corner, :func:`~selfrepair.geometry.turn_corner`,
    the one definition ``mission.png`` uses too, when the move sweeps it)."""
    if end.cell == start.cell:
        return ("wait" if end.heading == start.heading else "turn"), None
    if end.heading == start.heading:
        return "straight", None
    corner = turn_corner(start, end)
    return "arc", corner if corner is not None and corner in swept else None


def _faults(domain: SomeDomain, faults: Iterable[object]) -> list[str]:
    return sorted(domain.format_faults([f]) for f in faults)


def _frame_ticks(steps: Sequence[TraceStep]) -> list[Fraction]:
    """Elapsed ticks at the start of each step, and after the last one."""
    ticks = [Fraction(0)]
    for step in steps:
        ticks.append(ticks[-1] + step.duration)
    return ticks


def true_faults(spec: MissionSpec, ticks: Sequence[Fraction]) -> list[frozenset[object]]:
    """The true faults at the start of each step (and after the last): the schedule's."""
    return [spec.schedule.active_faults(k, t, spec.seed) for k, t in enumerate(ticks)]


def known_faults(
    spec: MissionSpec, steps: Sequence[TraceStep], true: Sequence[frozenset[object]]
) -> list[frozenset[object]]:
    """The faults known at the start of each step: those the step line records. After the last
    step: what the sensors report (detection ``now``), or the last step's known faults plus
    those a final failed attempt revealed (detection ``on-use``)."""
    known = [s.known for s in steps]
    n = len(steps)
    if spec.schedule.detection is Detection.NOW:
        known.append(true[n])
    elif not steps:
        known.append(frozenset())
    else:
        last = steps[-1]
        revealed: frozenset[object] = frozenset()
        if last.source is StepSource.FAILED_ATTEMPT:
            revealed = spec.domain.blocking(last.action, true[n - 1])
        known.append(last.known | revealed)
    return known


def fault_events(
    domain: SomeDomain, true: Sequence[frozenset[object]], known: Sequence[frozenset[object]]
) -> list[dict[str, Any]]:
    """When each fault appears, clears, becomes known or stops being known (frame numbers)."""
    events: list[dict[str, Any]] = []
    before_true: frozenset[object] = frozenset()
    before_known: frozenset[object] = frozenset()
    for frame, (now_true, now_known) in enumerate(zip(true, known, strict=True)):
        for kind, faults in (
            ("appears", now_true - before_true),
            ("clears", before_true - now_true),
            ("becomes known", now_known - before_known),
            ("no longer known", before_known - now_known),
        ):
            events.extend(
                {"frame": frame, "fault": f, "kind": kind} for f in _faults(domain, faults)
            )
        before_true, before_known = now_true, now_known
    return events


def _runs(flags: Sequence[bool]) -> list[list[int]]:
    """Maximal runs ``[first, stop)`` of true flags."""
    runs: list[list[int]] = []
    for index, flag in enumerate(flags):
        if flag and runs and runs[-1][1] == index:
            runs[-1][1] = index + 1
        elif flag:
            runs.append([index, index + 1])
    return runs


def fault_timeline(
    domain: SomeDomain, true: Sequence[frozenset[object]], known: Sequence[frozenset[object]]
) -> list[dict[str, Any]]:
    """Per fault that is ever true or known: the frame runs in which it is true and known."""
    every: frozenset[object] = frozenset().union(*true, *known)
    return [
        {
            "fault": domain.format_faults([f]),
            "active": _runs([f in t for t in true]),
            "known": _runs([f in k for k in known]),
        }
        for f in canonical_order(every)
    ]


def _how(repair: TraceRepair) -> str:
    """Where a repair came from, in words, with the strategies that found nothing before it."""
    if repair.source == RepairSource.REPLACEMENT:
        depth = f", nested depth {repair.depth}" if repair.depth else ""
        how = f"table candidate index {repair.candidate_index}{depth}"
    elif repair.source == RepairSource.LOOKAHEAD:
        plural = "" if repair.consumed == 1 else "s"
        how = f"lookahead window over the next {repair.consumed} queued action{plural}"
    elif repair.action is None:
        how = "replan (the plan ran out away from the goal)"
    else:
        how = "replan from scratch"
    before = [a for a in repair.attempts[:-1] if a != repair.source]
    return f"{how} (after {' then '.join(before)} found none)" if before else how


def _latency(ns: int) -> str:
    if ns >= 1_000_000:
        return f"{ns / 1_000_000:.2f} ms"
    return f"{ns / 1_000:.1f} µs"


def repair_json(
    domain: SomeDomain,
    index: int,
    repair: TraceRepair,
    steps: Sequence[TraceStep],
    known: frozenset[object],
) -> dict[str, Any]:
    """A repair for the page: its line's fields, the path its actions take from its pose, the
    executed steps that carried them out, and text saying where it came from."""
    path = []
    pose = repair.pose
    for action in repair.actions:
        path.append(segment_json(domain, pose, action))
        pose = domain.apply(pose, action)
    executed = []
    for step in steps[repair.step : repair.step + len(repair.actions)]:
        if step.source.value != repair.source.value:
            break
        executed.append(step.step)
    return {
        "index": index,
        "step": repair.step,
        "pose": pose_json(repair.pose),
        "action": None if repair.action is None else domain.format_action(repair.action),
        "status": repair.status.value,
        "source": repair.source.value,
        "source_name": REPAIR_SOURCE_NAMES.get(repair.source, repair.source),
        "how": _how(repair),
        "attempts": list(repair.attempts),
        "actions": [domain.format_action(a) for a in repair.actions],
        "consumed": repair.consumed,
        "candidate_index": repair.candidate_index,
        "depth": repair.depth,
        "latency_ns": repair.latency_ns,
        "latency": _latency(repair.latency_ns),
        "known": _faults(domain, known),
        "path": path,
        "executed": executed,
    }


def _step_json(domain: SomeDomain, step: TraceStep, ticks: Fraction) -> dict[str, Any]:
    if step.source is StepSource.FAILED_ATTEMPT:
        segment = {
            "action": domain.format_action(step.action),
            "from": pose_json(step.start),
            "to": pose_json(step.end),
            "kind": "failed",
            "swept": [list(step.start.cell)],
            "via": None,
        }
    else:
        segment = segment_json(domain, step.start, step.action)
    return {
        **segment,
        "step": step.step,
        "source": step.source.value,
        "duration": str(step.duration),
        "tick": str(ticks),
    }


T = TypeVar("T")


def _finite(value: T) -> T | str:
    """``value`` with a non-finite float (which a hand-edited trace may hold) as text: the page's
    JSON has no NaN or Infinity."""
    return str(value) if isinstance(value, float) and not math.isfinite(value) else value


def _title(spec: MissionSpec, status: str) -> str:
    strategy = str(spec.strategy)
    if uses_table(strategy):
        strategy += f" [{spec.options.table_label}, {spec.options.recursion.value}]"
    goal = f"{spec.goal[0]},{spec.goal[1]}"
    return f"{spec.maze.name or 'maze'}: {spec.start} to {goal}, {strategy}: {status}"


def tolerance_json(spec: MissionSpec, actions: Sequence[object], k: int) -> dict[str, Any] | None:
    """The tolerance of the initial plan ``actions`` for every set of 1 to ``k`` faults
    (:meth:`~selfrepair.repair.tolerance.PlanTolerance.to_json`: per step, the fault sets
    uncovered from there), what the page draws as a heat strip along the route; ``None`` for
    ``k`` 0, an empty plan or a strategy other than ``replacement`` (tolerance is a property of
    a plan for the replacement strategy)."""
    if k < 1 or not actions or spec.strategy != StrategyName.REPLACEMENT:
        return None
    from selfrepair.execution.tolerance import actions_tolerance
    from selfrepair.repair.tolerance import fault_model

    found = actions_tolerance(spec, fault_model(spec.domain, k), actions)
    return found.to_json(spec.domain)


def mission_payload(
    trace: Trace,
    *,
    origin: Mapping[str, Any] | None = None,
    max_steps: int = MAX_VIEW_STEPS,
    tolerance: int = 1,
) -> dict[str, Any]:
    """The viewer's data for ``trace`` (see the module docstring). The trace must replay (the
    page draws only what the robot model says happened); ``max_steps`` bounds its steps.
    ``tolerance``: the ``k`` of the initial plan's tolerance shown (:func:`tolerance_json`; 0
    for none)."""
    check_viewable(
        "the trace",
        len(trace.steps),
        "steps",
        max_steps=max_steps,
        source=trace.source,
        replay=lambda: replay(trace),
    )
    spec = spec_from_header(trace.header, trace.source)
    steps = trace.steps
    ticks = _frame_ticks(steps)
    true = true_faults(spec, ticks)
    known = known_faults(spec, steps, true)
    plan: list[dict[str, Any]] = []
    pose = spec.start
    domain = spec.domain
    initial = []
    for code in trace.header.get("initial_plan", []):
        try:
            action = domain.parse_action(str(code))
        except InputError as exc:
            raise TraceError(f"initial plan: {exc.reason}", source=trace.source, line=1) from None
        plan.append(segment_json(domain, pose, action))
        initial.append(action)
        pose = domain.apply(pose, action)
    summary = {k: _finite(v) for k, v in (trace.summary or {}).items()}
    status = str(summary.get("status", "unfinished"))
    return {
        "format": VIEWER_FORMAT,
        "version": VIEWER_VERSION,
        "title": _title(spec, status),
        "origin": dict(origin or {"kind": "trace", "source": trace.source}),
        "maze": {
            "name": spec.maze.name,
            "width": spec.maze.width,
            "height": spec.maze.height,
            "walls": wall_runs(spec.maze),
        },
        "start": pose_json(spec.start),
        "goal": list(spec.goal),
        "goal_heading": None if spec.goal_heading is None else spec.goal_heading.name,
        "strategy": spec.strategy,
        "options": {
            "table": spec.options.table_label,
            "recursion": spec.options.recursion.value,
            "max_depth": spec.options.max_depth,
            "window": spec.options.window,
        },
        "schedule": spec.schedule.describe(),
        "world": spec.world.describe(),
        "detection": spec.schedule.detection.value,
        "colours": {str(source): colour for source, colour in SOURCE_COLOURS.items()},
        "plan": plan,
        "tolerance": tolerance_json(spec, initial, tolerance),
        "diagnosis": diagnosis_json(trace),
        "steps": [_step_json(domain, s, t) for s, t in zip(steps, ticks, strict=False)],
        "frames": [
            {
                "pose": pose_json(steps[k - 1].end if k else spec.start),
                "tick": str(ticks[k]),
                "true": _faults(domain, true[k]),
                "known": _faults(domain, known[k]),
                "blocked": [list(c) for c in sorted(spec.world.blocked_at(ticks[k]))],
            }
            for k in range(len(steps) + 1)
        ],
        "fault_events": fault_events(domain, true, known),
        "fault_timeline": fault_timeline(domain, true, known),
        "repairs": [
            repair_json(domain, i, r, steps, known[r.step]) for i, r in enumerate(trace.repairs)
        ],
        "has_repair_lines": bool(trace.repairs)
        or not any(s.source in REPAIR_SOURCE_NAMES for s in steps),
        "status": status,
        "summary": summary,
    }


# --- entry points -------------------------------------------------------------------------------


def view_trace(
    trace: str | Path,
    out: str | Path,
    *,
    max_steps: int = MAX_VIEW_STEPS,
    max_trace_bytes: int | None = MAX_TRACE_BYTES,
    tolerance: int = 1,
) -> Path:
    """Write the viewer page of the trace file ``trace`` to ``out``; returns ``out``: the mission
    page, or the team page (:mod:`selfrepair.experiment.teamview`) for a team trace. A trace file
    over ``max_trace_bytes`` is refused unread."""
    from selfrepair.execution.trace import read_trace
    from selfrepair.experiment.teamview import view_team_trace
    from selfrepair.team.traceread import is_team_trace

    if is_team_trace(trace):
        return view_team_trace(trace, out, max_steps=max_steps, max_trace_bytes=max_trace_bytes)
    parsed = read_trace(trace, max_trace_bytes=max_trace_bytes)
    return write_page(mission_payload(parsed, max_steps=max_steps, tolerance=tolerance), out)


def trace_from_results(db: str | Path, key_prefix: str) -> tuple[Trace, dict[str, Any]]:
    """Re-run the mission of ``db`` whose key starts with ``key_prefix`` and return its parsed
    trace and where it came from (database, full key, and whether the re-run agrees with the
    stored row on status and steps)."""
    from selfrepair.execution.trace import trace_lines
    from selfrepair.experiment.reportmission import pick_mission, rerun_mission
    from selfrepair.experiment.store import ResultStore

    if not key_prefix:
        raise InputError("expected a non-empty mission key or key prefix", source=str(db))
    with ResultStore(db, read_only=True) as store:
        rows = store.rows("WHERE substr(key, 1, ?) = ?", (len(key_prefix), key_prefix))
    row = pick_mission(rows, key_prefix, str(db))
    result = rerun_mission(row)
    key = str(row["key"])
    trace = parse_trace("\n".join(trace_lines(result)), source=f"{db} (mission {key[:12]})")
    stored = {"status": row.get("status"), "steps": row.get("steps")}
    again = {"status": result.status, "steps": len(result.steps)}
    origin = {
        "kind": "results",
        "source": str(db),
        "key": key,
        "experiment": row.get("experiment"),
        "agrees": stored == again,
        "stored": stored,
    }
    return trace, origin


def view_results(
    db: str | Path,
    key_prefix: str,
    out: str | Path,
    *,
    max_steps: int = MAX_VIEW_STEPS,
    tolerance: int = 1,
) -> Path:
    """Write the viewer page of the stored mission ``key_prefix`` of ``db`` to ``out``: the
    team page for a mission of a team experiment (run again from its stored configuration)."""
    from selfrepair.experiment.reportmission import pick_mission
    from selfrepair.experiment.store import ResultStore
    from selfrepair.experiment.teams import is_team_rows

    if not key_prefix:
        raise InputError("expected a non-empty mission key or key prefix", source=str(db))
    with ResultStore(db, read_only=True) as store:
        rows = store.rows("WHERE substr(key, 1, ?) = ?", (len(key_prefix), key_prefix))
    if is_team_rows(rows):
        from selfrepair.experiment.teamview import view_team_results

        return view_team_results(pick_mission(rows, key_prefix, str(db)), db, out, max_steps)
    trace, origin = trace_from_results(db, key_prefix)
    payload = mission_payload(trace, origin=origin, max_steps=max_steps, tolerance=tolerance)
    return write_page(payload, out)
