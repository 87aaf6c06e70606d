"""The options that ``run`` and ``compare`` share, declared once.

:class:`MissionOptions` is the one list of the shared options: each field is typed with a Typer
option alias (or the ``MAZE`` argument) and has the option's default. :func:`mission_options`
gives a command all of them, and :func:`selfrepair.cli._spec.mission_spec` turns them into the
:class:`~selfrepair.execution.result.MissionSpec` (with its
:class:`~selfrepair.repair.strategies.StrategyOptions`), so an option added to the dataclass
(and used in ``mission_spec``) is an option of both commands. The JSON form of a mission's
metrics row is :mod:`selfrepair.cli._rowjson`.

Like the command modules, this module does not use ``from __future__ import annotations``:
Typer reads the field types as the parameter types of the commands.
"""

from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

from selfrepair.cli._app import (
    MaxCells,
    MaxLookupPatterns,
    MaxTableBytes,
    MaxTableCandidates,
    flag,
    option,
    option_group,
)
from selfrepair.cli._inputs import (
    Backend,
    ClearanceWeight,
    DomainOpt,
    Faults,
    Heuristic,
    MazeArg,
    Start,
)
from selfrepair.errors import InputError
from selfrepair.limits import (
    DEFAULT_CONFIDENCE,
    DEFAULT_FAULT_PRIOR,
    DEFAULT_MAX_FAULTS,
    DEFAULT_MAX_WAIT,
    DEFAULT_OBSERVER_RANGE,
    DEFAULT_SENSING_RANGE,
    MAX_CELLS,
    MAX_LOOKUP_PATTERNS,
    MAX_OBSERVERS,
    MAX_TABLE_BYTES,
    MAX_TABLE_CANDIDATES,
)

if TYPE_CHECKING:
    from collections.abc import Sequence


__all__ = ["MissionOptions", "check_choice", "mission_options"]

Goal = Annotated[str, option("--goal", "X,Y", "Goal cell.")]
At = Annotated[int, option("--at", "N", "When the faults start (a step or a tick).")]
ClockOpt = Annotated[str, option("--clock", "step|tick", "What --at and --transient count.")]
Detect = Annotated[
    str,
    option(
        "--detect",
        "now|on-use|hidden",
        "Faults are known when they start (now), when a command fails (on-use), or never "
        "(hidden: the robot moves as its faults make it and diagnoses them from what it observes; "
        "see docs/diagnosis.md).",
    ),
]
FaultBehaviourOpt = Annotated[
    str | None,
    option(
        "--fault-behaviour",
        "MODEL",
        "Faults hidden: what a forbidden command really does, a model of the robot (the "
        "four-wheel robot: stall, runaway-backward, reverse). Default: the robot's first.",
        show_default=False,
    ),
]
Noise = Annotated[
    float,
    option(
        "--noise",
        "P",
        "Faults hidden: odometry error rate, the chance that a pose reading names a wrong "
        "cell or heading (0 to below 0.5).",
    ),
]
BumpSwitch = Annotated[
    bool,
    flag("--bumps/--no-bumps", "Faults hidden: the robot senses when a motion stops at a wall."),
]
ObserversOpt = Annotated[
    int,
    option(
        "--observers",
        "N",
        f"Faults hidden: N teammates (0 to {MAX_OBSERVERS}) follow the robot, observer i "
        "where it was i commands before, and tell it what they see of each motion in range; "
        "active diagnosis plans its probes counting their readings (docs/diagnosis.md).",
    ),
]
ObserverRange = Annotated[
    int,
    option(
        "--observer-range",
        "CELLS",
        "Faults hidden: how far an observer sees (Chebyshev cells, 0 to 64).",
    ),
]
ObserverNoise = Annotated[
    float | None,
    option(
        "--observer-noise",
        "P",
        "Faults hidden: the observers' odometry error rate (0 to below 0.5). Default: --noise.",
        show_default=False,
    ),
]
ObserverViewOpt = Annotated[
    str,
    option(
        "--observer-view",
        "VIEW",
        "Faults hidden: what an observer sees of each motion in range: pose (the robot's "
        "pose after it) or wheels (the pose and which wheels turn which way, each wheel misread "
        "at --observer-noise; a robot with actuators, docs/diagnosis.md).",
    ),
]
MaxFaults = Annotated[
    int, option("--max-faults", "K", "Diagnosis: hypotheses of up to K faults.", min=0)
]
FaultPrior = Annotated[
    float, option("--fault-prior", "Q", "Diagnosis: prior probability of each fault (0 to 1).")
]
Confidence = Annotated[
    float,
    option(
        "--confidence",
        "E",
        "Diagnosis: a class is isolated, and the classes assumed cover what is possible, "
        "at posterior mass 1 - E.",
    ),
]
Transient = Annotated[
    int | None, option("--transient", "N", "Faults last N steps (or ticks), then heal.")
]
Intermittent = Annotated[
    float | None,
    option("--intermittent", "P", "Faults are active at each step with probability P."),
]
Events = Annotated[
    str,
    option(
        "--events",
        "EVENTS",
        "World events, ';'-separated: X,Y@T (cell blocked from tick T), X,Y@T..U (blocked "
        "from T, free from U), -X,Y@T (free from T).",
    ),
]
SensingOpt = Annotated[
    str,
    option(
        "--sensing",
        "MODE",
        "How the robot learns of blocked cells: range (sees cells within --sensing-range) "
        "or bump (only by bumping).",
    ),
]
SensingRange = Annotated[
    int, option("--sensing-range", "R", "Chebyshev cells the robot sees around it.", min=0)
]
TableOpt = Annotated[
    str | None,
    option(
        "--table",
        "TABLE",
        "Replacement table: bundled name (handwritten, generated-agnostic, "
        "generated-indexed, three-action) or a table file. Default: the robot's own (handwritten "
        "for four-wheel, the bundled three-action table), else one generated from the robot "
        "model.",
        show_default=False,
    ),
]
Recursion = Annotated[
    str, option("--recursion", "MODE", "Recursion in replacements: flat, guarded or layered.")
]
MaxDepth = Annotated[int, option("--max-depth", "N", "Depth bound of guarded recursion.")]
Window = Annotated[int, option("--window", "K", "Lookahead: actions after the faulty one.")]
MaxWait = Annotated[
    int,
    option(
        "--max-wait",
        "N",
        "Steps the robot may wait in place, in all, when no plan exists under the faults "
        "it knows (they may clear; detection now only); 0 gives up at once.",
        min=0,
    ),
]
LpgTimeLimit = Annotated[
    float,
    option(
        "--lpg-time-limit",
        "SECONDS",
        "lpg-adapt: wall-clock limit of each LPG-adapt call (a time-out falls back to A*).",
        min=0.001,
    ),
]
Rewrite = Annotated[
    bool,
    flag(
        "--rewrite",
        "Replacement: once a fault is known, substitute every faulty action of the rest of "
        "the plan that has a valid replacement (whole-plan rewriting); in a changing world, "
        "every later blocked window that has a detour too.",
    ),
]
PlanWithFaults = Annotated[
    bool, flag("--plan-with-faults", "Make the initial plan knowing the faults sensed at step 0.")
]
Seed = Annotated[int, option("--seed", "S", "Seed of intermittent faults.", min=0)]
WarmUp = Annotated[
    bool,
    flag(
        "--warm-up/--no-warm-up",
        "Run the mission once untimed first, so latencies leave out one-off costs "
        "(loading tables, first allocations).",
    ),
]


@dataclass(frozen=True, slots=True)
class MissionOptions:
    """The options of ``run`` and ``compare``, as given on the command line (checked by
    :func:`mission_spec`): the maze and route, the fault schedule, the strategy options, the
    planner, the warm-up run and the limits. The field order is the order of ``--help``."""

    maze: MazeArg
    start: Start
    goal: Goal
    faults: Faults = ""
    at: At = 0
    clock: ClockOpt = "step"
    detect: Detect = "now"
    fault_behaviour: FaultBehaviourOpt = None
    noise: Noise = 0.0
    bump_switch: BumpSwitch = True
    observers: ObserversOpt = 0
    observer_range: ObserverRange = DEFAULT_OBSERVER_RANGE
    observer_noise: ObserverNoise = None
    observer_view: ObserverViewOpt = "pose"
    max_faults: MaxFaults = DEFAULT_MAX_FAULTS
    fault_prior: FaultPrior = DEFAULT_FAULT_PRIOR
    confidence: Confidence = DEFAULT_CONFIDENCE
    transient: Transient = None
    intermittent: Intermittent = None
    events: Events = ""
    sensing: SensingOpt = "range"
    sensing_range: SensingRange = DEFAULT_SENSING_RANGE
    table: TableOpt = None
    recursion: Recursion = "flat"
    max_depth: MaxDepth = 2
    window: Window = 3
    max_wait: MaxWait = DEFAULT_MAX_WAIT
    lpg_time_limit: LpgTimeLimit = 5.0
    rewrite: Rewrite = False
    clearance_weight: ClearanceWeight = "0"
    heuristic: Heuristic = "grid-distance"
    backend: Backend = "auto"
    plan_with_faults: PlanWithFaults = False
    seed: Seed = 0
    warm_up: WarmUp = True
    domain_name: DomainOpt = "four-wheel"
    max_cells: MaxCells = MAX_CELLS
    max_table_bytes: MaxTableBytes = MAX_TABLE_BYTES
    max_table_candidates: MaxTableCandidates = MAX_TABLE_CANDIDATES
    max_lookup_patterns: MaxLookupPatterns = MAX_LOOKUP_PATTERNS


mission_options = option_group(MissionOptions, "mission")
"""``command`` with every field of :class:`MissionOptions` as a parameter of its own, in place of
its parameter ``mission``, which it is then called with (see
:func:`~selfrepair.cli._app.option_group`). Use it below ``@app.command()``."""


def check_choice(value: str, choices: "Sequence[str]", option: str) -> None:
    """An :class:`InputError` on ``option`` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise InputError(f"expected one of {', '.join(choices)}, got {value!r}", source=option)
