"""The mission options that ``run`` and ``compare`` share, the spec they build, and the JSON
form of a mission's metrics row."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Annotated, Any

import typer

from selfrepair.cli._app import exact_json, number_json
from selfrepair.cli._inputs import find_input, parse_weight
from selfrepair.errors import InputError
from selfrepair.limits import MAX_LOOKUP_PATTERNS

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    from selfrepair.execution.faults import FaultSchedule
    from selfrepair.execution.result import MissionSpec
    from selfrepair.robots.domain import Domain

__all__ = ["check_choice", "domain_named", "mission_spec", "row_json"]

Goal = Annotated[str, typer.Option("--goal", metavar="X,Y", help="Goal cell.")]
At = Annotated[
    int, typer.Option("--at", metavar="N", help="When the faults start (a step or a tick).")
]
ClockOpt = Annotated[
    str, typer.Option("--clock", metavar="step|tick", help="What --at and --transient count.")
]
Detect = Annotated[
    str,
    typer.Option(
        "--detect",
        metavar="now|on-use",
        help="Faults are known when they start (now) or when a command fails (on-use).",
    ),
]
Transient = Annotated[
    int | None,
    typer.Option("--transient", metavar="N", help="Faults last N steps (or ticks), then heal."),
]
Intermittent = Annotated[
    float | None,
    typer.Option(
        "--intermittent", metavar="P", help="Faults are active at each step with probability P."
    ),
]
TableOpt = Annotated[
    str,
    typer.Option(
        "--table",
        metavar="TABLE",
        help="Replacement table: bundled name (handwritten, generated-agnostic, "
        "generated-indexed) or a table file.",
    ),
]
Recursion = Annotated[
    str,
    typer.Option(
        "--recursion", metavar="MODE", help="Recursion in replacements: flat, guarded or layered."
    ),
]
MaxDepth = Annotated[
    int, typer.Option("--max-depth", metavar="N", help="Depth bound of guarded recursion.")
]
Window = Annotated[
    int, typer.Option("--window", metavar="K", help="Lookahead: actions after the faulty one.")
]
LpgTimeLimit = Annotated[
    float,
    typer.Option(
        "--lpg-time-limit",
        metavar="SECONDS",
        min=0.001,
        help="lpg-adapt: wall-clock limit of each LPG-adapt call (a time-out falls back to A*).",
    ),
]
Rewrite = Annotated[
    bool,
    typer.Option(
        "--rewrite",
        help="Replacement: once a fault is known, substitute every faulty action of the rest of "
        "the plan that has a valid replacement (whole-plan rewriting).",
    ),
]
PlanWithFaults = Annotated[
    bool,
    typer.Option(
        "--plan-with-faults", help="Make the initial plan knowing the faults sensed at step 0."
    ),
]
Seed = Annotated[
    int, typer.Option("--seed", metavar="S", help="Seed of intermittent faults.", min=0)
]
DomainOpt = Annotated[
    str, typer.Option("--domain", metavar="NAME", help="The robot: a registered domain name.")
]
WarmUp = Annotated[
    bool,
    typer.Option(
        "--warm-up/--no-warm-up",
        help="Run the mission once untimed first, so latencies leave out one-off costs "
        "(loading tables, first allocations).",
    ),
]


def domain_named(name: str) -> Domain[Any, Any]:
    """The registered domain ``name`` (bad names are an error on ``--domain``)."""
    from selfrepair.robots.registry import get_domain

    try:
        return get_domain(name)
    except InputError as exc:
        raise InputError(exc.reason, source="--domain") from None


def check_choice(value: str, choices: Sequence[str], option: str) -> None:
    """An :class:`InputError` on ``option`` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise InputError(f"expected one of {', '.join(choices)}, got {value!r}", source=option)


def build_schedule(
    domain: Domain[Any, Any],
    faults: str,
    at: int,
    clock: str,
    detect: str,
    transient: int | None,
    intermittent: float | None,
) -> FaultSchedule:
    """The fault schedule the options describe (one persistence for every fault)."""
    from selfrepair.execution.faults import (
        Clock,
        Detection,
        FaultEvent,
        FaultSchedule,
        Persistence,
        canonical_order,
    )

    try:
        parsed = canonical_order(domain.parse_faults(faults))
    except InputError as exc:
        raise InputError(exc.reason, source="--faults") from None
    if transient is not None and intermittent is not None:
        raise InputError(
            "expected at most one of --transient and --intermittent", source="--transient"
        )
    persistence = (
        Persistence.TRANSIENT
        if transient is not None
        else Persistence.INTERMITTENT
        if intermittent is not None
        else Persistence.PERMANENT
    )
    events = tuple(
        FaultEvent(
            f,
            at=at,
            clock=Clock(clock),
            persistence=persistence,
            duration=transient,
            probability=intermittent,
        )
        for f in parsed
    )
    return FaultSchedule(events, Detection(detect))


def mission_spec(
    *,
    maze: str,
    start: str,
    goal: str,
    faults: str,
    at: int,
    clock: str,
    detect: str,
    transient: int | None,
    intermittent: float | None,
    strategy: str,
    table: str,
    recursion: str,
    max_depth: int,
    window: int,
    clearance_weight: str,
    heuristic: str,
    backend: str,
    plan_with_faults: bool,
    seed: int,
    domain_name: str,
    max_cells: int,
    max_table_bytes: int,
    max_table_candidates: int,
    strategies: Sequence[str] = (),
    lpg_time_limit: float = 5.0,
    rewrite: bool = False,
    max_lookup_patterns: int = MAX_LOOKUP_PATTERNS,
) -> MissionSpec:
    """The mission the options describe; every option is checked here, so bad input is exit 2
    before anything runs (``strategies``: every strategy that will run). The table is loaded
    here, within the limits given, and the mission gets the loaded table, so those limits are
    the ones that hold (a bad table file is exit 2 even when no repair needs it)."""
    from selfrepair.execution.faults import Clock, Detection
    from selfrepair.execution.result import MissionSpec
    from selfrepair.geometry import parse_cell, parse_pose
    from selfrepair.repair.replacement import RecursionMode
    from selfrepair.repair.strategies import StrategyOptions, strategy_names, uses_table
    from selfrepair.search.astar import BACKENDS
    from selfrepair.search.lattice import HEURISTICS
    from selfrepair.tables.fileformat import resolve_table
    from selfrepair.tables.model import ReplacementTable
    from selfrepair.world.bundled import resolve_maze

    domain = domain_named(domain_name)
    for name in (*strategies, strategy):
        check_choice(name, strategy_names(), "--strategies" if strategies else "--strategy")
    check_choice(recursion, tuple(RecursionMode), "--recursion")
    check_choice(detect, tuple(Detection), "--detect")
    check_choice(clock, tuple(Clock), "--clock")
    check_choice(heuristic, tuple(HEURISTICS), "--heuristic")
    check_choice(backend, BACKENDS, "--backend")
    loaded: str | ReplacementTable = table
    if any(uses_table(name) for name in (*strategies, strategy)):
        loaded = resolve_table(
            find_input(table),
            max_table_bytes=max_table_bytes,
            max_table_candidates=max_table_candidates,
        )
    return MissionSpec(
        maze=resolve_maze(find_input(maze), max_cells=max_cells),
        start=parse_pose(start, source="--start"),
        goal=parse_cell(goal, source="--goal"),
        schedule=build_schedule(domain, faults, at, clock, detect, transient, intermittent),
        strategy=strategy,
        options=StrategyOptions(
            table=loaded,
            recursion=RecursionMode(recursion),
            max_depth=max_depth,
            window=window,
            lpg_time_limit_s=lpg_time_limit,
            rewrite=rewrite,
            max_lookup_patterns=max_lookup_patterns,
        ),
        clearance_weight=parse_weight(clearance_weight),
        seed=seed,
        heuristic=heuristic,
        backend=backend,
        initial_faults_known=plan_with_faults,
        domain=domain,
    )


_EXACT = ("ticks", "plan_cost_before", "plan_cost_after", "clearance_weight")
"""Columns that hold an exact number as text (``"31/3"``)."""
_EMBEDDED_JSON = ("fault_schedule", "repair_latencies_ns")
"""Columns that hold JSON text (for the results database)."""
_HISTOGRAMS = ("replacement_lengths", "replacement_depths")
"""Columns that hold a ``value:count,...`` histogram as text."""


def row_json(row: Mapping[str, Any]) -> dict[str, Any]:
    """A mission's metrics row (``mission_row``) as JSON values: numbers are JSON numbers
    (``ticks`` and the other exact values with an exact ``_exact`` string twin, the ``_float``
    twins dropped; floats rounded), ``reached`` a boolean, and the embedded JSON and histogram
    texts as arrays and objects."""
    from fractions import Fraction

    out: dict[str, Any] = {}
    for key, value in row.items():
        if key.endswith("_float") and key.removesuffix("_float") in _EXACT:
            continue
        if key in _EXACT:
            exact = None if value is None else Fraction(str(value))
            out[key] = number_json(exact)
            out[f"{key}_exact"] = exact_json(exact)
        elif key in _EMBEDDED_JSON:
            out[key] = json.loads(str(value))
        elif key in _HISTOGRAMS:
            pairs = (item.split(":") for item in str(value or "").split(",") if item)
            out[key] = {length: int(count) for length, count in pairs}
        elif key == "reached":
            out[key] = bool(value)
        elif key.endswith("_ns") and isinstance(value, float):
            out[key] = round(value)
        elif isinstance(value, float):
            out[key] = number_json(value)
        else:
            out[key] = value
    return out
