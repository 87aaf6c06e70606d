"""Writing mission traces (format in :mod:`selfrepair.execution.traceformat`): one JSON object
per line, the header first and the summary row last."""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any, TypeVar

from selfrepair.diagnosis.cooperative import Observer, ObserverView
from selfrepair.execution.faults import Detection
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionResult, MissionSpec, RepairRecord, TraceStep
from selfrepair.execution.traceformat import TRACE_FORMAT, TRACE_VERSION, header_start, pose_json
from selfrepair.execution.traceobserve import diagnosis_header, observation_fields
from selfrepair.robots.domain import Domain, SomeDomain
from selfrepair.world.maze import format_maze

__all__ = ["header_json", "repair_json", "step_json", "trace_lines", "write_trace"]

A = TypeVar("A")
F = TypeVar("F")


def header_json(spec: MissionSpec, initial_plan: Iterable[object] = ()) -> dict[str, Any]:
    """The header line's object for ``spec``."""
    options = spec.options
    domain = spec.domain
    return {
        **header_start(TRACE_FORMAT, TRACE_VERSION, domain.name),
        "maze": {"name": spec.maze.name, "rows": format_maze(spec.maze).splitlines()},
        "start": pose_json(spec.start),
        "goal": [spec.goal[0], spec.goal[1]],
        "goal_heading": None if spec.goal_heading is None else spec.goal_heading.name,
        "schedule": spec.schedule.to_json(domain),
        **({"world": spec.world.to_json()} if spec.world else {}),
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
        **_hidden_json(spec),
    }


def _hidden_json(spec: MissionSpec) -> dict[str, Any]:
    """Faults hidden (docs/diagnosis.md): the behaviour model, the observation model and the
    diagnosis options, under ``"hidden"`` (absent otherwise, so other traces are as before)."""
    if spec.schedule.detection is not Detection.HIDDEN:
        return {}
    options = spec.options
    return {
        "hidden": {
            "behaviour": spec.behaviour,
            "noise": spec.observation.noise,
            "bumps": spec.observation.bumps,
            "max_faults": options.max_faults,
            "fault_prior": options.fault_prior,
            "confidence": options.confidence,
            **diagnosis_header(spec),
            **({"observers": [_observer(o) for o in spec.observers]} if spec.observers else {}),
        }
    }


def _observer(observer: Observer) -> dict[str, Any]:
    """An observing teammate as the header keeps it."""
    sensing = observer.sensing
    view = {} if observer.view is ObserverView.POSE else {"view": observer.view.value}
    return {"name": observer.name, "noise": observer.noise, "range": sensing.cells,
            "metric": sensing.metric.value, **view}  # fmt: skip


def _fault_texts(domain: Domain[A, F], faults: Iterable[F]) -> list[str]:
    return sorted(domain.format_faults([f]) for f in faults)


def step_json(domain: SomeDomain, step: TraceStep) -> dict[str, Any]:
    """One step line's object."""
    return {
        "type": "step",
        "step": step.step,
        "action": domain.format_action(step.action),
        "from": pose_json(step.start),
        "to": pose_json(step.end),
        "duration": str(step.duration),
        "source": step.source.value,
        "known": _fault_texts(domain, step.known),
    }


def repair_json(domain: SomeDomain, record: RepairRecord) -> dict[str, Any]:
    """One repair line's object."""
    repair = record.repair
    return {
        "type": "repair",
        "step": record.step,
        "pose": pose_json(record.pose),
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
    observed = observation_fields(result)
    for step in result.steps:
        while repairs and repairs[0].step <= step.step:
            lines.append(json.dumps(repair_json(domain, repairs.pop(0))))
        line = step_json(domain, step)
        if step.step in observed:
            line.update(observed[step.step])
        lines.append(json.dumps(line))
    lines.extend(json.dumps(repair_json(domain, r)) for r in repairs)
    lines.append(json.dumps({"type": "summary", **mission_row(result)}))
    return lines


def write_trace(result: MissionResult, path: str | Path) -> None:
    """Write the trace of ``result`` to ``path``."""
    Path(path).write_text("\n".join(trace_lines(result)) + "\n", encoding="utf-8")
