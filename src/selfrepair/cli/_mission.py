"""The options that ``run`` and ``compare`` share, declared once, the spec they build, and the
JSON form of a mission's metrics row.

:class:`MissionOptions` is the one list of the shared options: each field is typed with a Typer
option alias (or the ``MAZE`` argument) and has the option's default. :func:`mission_options`
gives a command all of them, and :func:`mission_spec` turns them into the
:class:`~selfrepair.execution.result.MissionSpec` (with its
:class:`~selfrepair.repair.strategies.StrategyOptions`), so an option added to the dataclass
(and used in :func:`mission_spec`) is an option of both commands.

Like the command modules, this module does not use ``from __future__ import annotations``:
Typer reads the field types as the parameter types of the commands.
"""

import functools
import inspect
import json
from dataclasses import MISSING, dataclass, fields
from typing import TYPE_CHECKING, Annotated, Any

import typer

from selfrepair.cli._app import (
    MaxCells,
    MaxLookupPatterns,
    MaxTableBytes,
    MaxTableCandidates,
    exact_json,
    number_json,
)
from selfrepair.cli._inputs import (
    Backend,
    ClearanceWeight,
    DomainOpt,
    Faults,
    Heuristic,
    MazeArg,
    Start,
    domain_named,
    find_input,
    parse_weight,
)
from selfrepair.errors import InputError, ProblemError
from selfrepair.limits import (
    DEFAULT_MAX_WAIT,
    DEFAULT_SENSING_RANGE,
    MAX_CELLS,
    MAX_LOOKUP_PATTERNS,
    MAX_TABLE_BYTES,
    MAX_TABLE_CANDIDATES,
)

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence

    from selfrepair.diagnosis import ObservationModel
    from selfrepair.execution.faults import FaultSchedule
    from selfrepair.execution.result import MissionSpec
    from selfrepair.robots.domain import Domain

__all__ = [
    "MissionOptions",
    "check_choice",
    "mission_options",
    "mission_spec",
    "row_json",
    "table_note",
]

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
        metavar="now|on-use|hidden",
        help="Faults are known when they start (now), when a command fails (on-use), or never "
        "(hidden: the robot moves as its faults make it and diagnoses them from what it observes; "
        "see docs/diagnosis.md).",
    ),
]
FaultBehaviourOpt = Annotated[
    str | None,
    typer.Option(
        "--fault-behaviour",
        metavar="MODEL",
        help="Faults hidden: what a forbidden command really does, a model of the robot (the "
        "four-wheel robot: stall, runaway-backward, reverse). Default: the robot's first.",
        show_default=False,
    ),
]
Noise = Annotated[
    float,
    typer.Option(
        "--noise",
        metavar="P",
        help="Faults hidden: odometry error rate, the chance that a pose reading names a wrong "
        "cell or heading (0 to below 0.5).",
    ),
]
BumpSwitch = Annotated[
    bool,
    typer.Option(
        "--bumps/--no-bumps",
        help="Faults hidden: the robot senses when a motion stops at a wall.",
    ),
]
MaxFaults = Annotated[
    int,
    typer.Option(
        "--max-faults", metavar="K", min=0, help="Diagnosis: hypotheses of up to K faults."
    ),
]
FaultPrior = Annotated[
    float,
    typer.Option(
        "--fault-prior", metavar="Q", help="Diagnosis: prior probability of each fault (0 to 1)."
    ),
]
Confidence = Annotated[
    float,
    typer.Option(
        "--confidence",
        metavar="E",
        help="Diagnosis: a class is isolated, and the classes assumed cover what is possible, "
        "at posterior mass 1 - E.",
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
Events = Annotated[
    str,
    typer.Option(
        "--events",
        metavar="EVENTS",
        help="World events, ';'-separated: X,Y@T (cell blocked from tick T), X,Y@T..U (blocked "
        "from T, free from U), -X,Y@T (free from T).",
    ),
]
SensingOpt = Annotated[
    str,
    typer.Option(
        "--sensing",
        metavar="MODE",
        help="How the robot learns of blocked cells: range (sees cells within --sensing-range) "
        "or bump (only by bumping).",
    ),
]
SensingRange = Annotated[
    int,
    typer.Option(
        "--sensing-range", metavar="R", min=0, help="Chebyshev cells the robot sees around it."
    ),
]
TableOpt = Annotated[
    str | None,
    typer.Option(
        "--table",
        metavar="TABLE",
        help="Replacement table: bundled name (handwritten, generated-agnostic, "
        "generated-indexed, three-action) or a table file. Default: the robot's own (handwritten "
        "for four-wheel, the bundled three-action table), else one generated from the robot "
        "model.",
        show_default=False,
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
MaxWait = Annotated[
    int,
    typer.Option(
        "--max-wait",
        metavar="N",
        min=0,
        help="Steps the robot may wait in place, in all, when no plan exists under the faults "
        "it knows (they may clear; detection now only); 0 gives up at once.",
    ),
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
        "the plan that has a valid replacement (whole-plan rewriting); in a changing world, "
        "every later blocked window that has a detour too.",
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
WarmUp = Annotated[
    bool,
    typer.Option(
        "--warm-up/--no-warm-up",
        help="Run the mission once untimed first, so latencies leave out one-off costs "
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
    max_faults: MaxFaults = 2
    fault_prior: FaultPrior = 0.05
    confidence: Confidence = 0.01
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


def mission_options(command: "Callable[..., int]") -> "Callable[..., int]":
    """``command`` with every field of :class:`MissionOptions` as a parameter of its own (Typer
    reads them from the signature), in place of its parameter ``mission``, which it is then
    called with: the fields' values gathered in one :class:`MissionOptions`.

    Use it below ``@app.command()``; the command's other parameters keep their place around
    the mission options."""
    own = inspect.signature(command).parameters
    names = tuple(f.name for f in fields(MissionOptions))
    if "mission" not in own or set(names) & set(own):
        raise ProblemError(
            f"{command.__name__}: expected a parameter 'mission' and none named as a field of "
            "MissionOptions"
        )
    keyword = inspect.Parameter.KEYWORD_ONLY
    shared = [
        inspect.Parameter(
            f.name,
            keyword,
            annotation=f.type,
            default=inspect.Parameter.empty if f.default is MISSING else f.default,
        )
        for f in fields(MissionOptions)
    ]
    params: list[inspect.Parameter] = []
    for param in own.values():
        params.extend(shared if param.name == "mission" else [param.replace(kind=keyword)])

    @functools.wraps(command)
    def with_mission_options(**values: Any) -> int:
        mission = MissionOptions(**{name: values.pop(name) for name in names})
        return command(mission=mission, **values)

    with_mission_options.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
        params, return_annotation=int
    )
    with_mission_options.__annotations__ = {p.name: p.annotation for p in params}
    with_mission_options.__annotations__["return"] = int
    return with_mission_options


def check_choice(value: str, choices: "Sequence[str]", option: str) -> None:
    """An :class:`InputError` on ``option`` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise InputError(f"expected one of {', '.join(choices)}, got {value!r}", source=option)


def build_schedule(
    domain: "Domain[Any, Any]",
    faults: str,
    at: int,
    clock: str,
    detect: str,
    transient: int | None,
    intermittent: float | None,
) -> "FaultSchedule":
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
    mission: MissionOptions, strategy: str, strategies: "Sequence[str]" = ()
) -> "MissionSpec":
    """The mission the options describe, with ``strategy``; every option is checked here, so
    bad input is exit 2 before anything runs (``strategies``: every strategy that will run). The
    table is loaded here, within the limits given, and the mission gets the loaded table, so
    those limits are the ones that hold (a bad table file is exit 2 even when no repair needs
    it)."""
    from selfrepair.execution.faults import Clock, Detection
    from selfrepair.execution.result import MissionSpec
    from selfrepair.geometry import parse_cell, parse_pose
    from selfrepair.repair.replacement import RecursionMode
    from selfrepair.repair.strategies import StrategyOptions, strategy_names, uses_table
    from selfrepair.search.astar import BACKENDS
    from selfrepair.search.lattice import HEURISTICS
    from selfrepair.tables.fileformat import default_table, default_table_name, resolve_table
    from selfrepair.tables.model import SomeTable
    from selfrepair.world.bundled import resolve_maze
    from selfrepair.world.events import Sensing, WorldSchedule, parse_events

    m = mission
    domain = domain_named(m.domain_name)
    for name in (*strategies, strategy):
        check_choice(name, strategy_names(), "--strategies" if strategies else "--strategy")
    check_choice(m.recursion, tuple(RecursionMode), "--recursion")
    check_choice(m.detect, tuple(Detection), "--detect")
    check_choice(m.clock, tuple(Clock), "--clock")
    check_choice(m.heuristic, tuple(HEURISTICS), "--heuristic")
    check_choice(m.backend, BACKENDS, "--backend")
    loaded: str | SomeTable = default_table_name(domain) if m.table is None else m.table
    if not any(uses_table(name) for name in (*strategies, strategy)):
        pass
    elif m.table is None:
        loaded = default_table(domain)
    else:
        loaded = resolve_table(
            find_input(m.table),
            max_table_bytes=m.max_table_bytes,
            max_table_candidates=m.max_table_candidates,
        )
    schedule = build_schedule(
        domain, m.faults, m.at, m.clock, m.detect, m.transient, m.intermittent
    )
    check_choice(m.sensing, tuple(Sensing), "--sensing")
    world = WorldSchedule(parse_events(m.events), Sensing(m.sensing), m.sensing_range)
    observation = observation_options(domain, m)
    return MissionSpec(
        maze=resolve_maze(find_input(m.maze), max_cells=m.max_cells),
        start=parse_pose(m.start, source="--start"),
        goal=parse_cell(m.goal, source="--goal"),
        schedule=schedule,
        world=world,
        strategy=strategy,
        options=StrategyOptions(
            table=loaded,
            recursion=RecursionMode(m.recursion),
            max_depth=m.max_depth,
            window=m.window,
            lpg_time_limit_s=m.lpg_time_limit,
            rewrite=m.rewrite,
            max_lookup_patterns=m.max_lookup_patterns,
            max_wait=m.max_wait,
            max_faults=m.max_faults,
            fault_prior=m.fault_prior,
            confidence=m.confidence,
        ),
        behaviour=m.fault_behaviour,
        observation=observation,
        clearance_weight=parse_weight(m.clearance_weight),
        seed=m.seed,
        heuristic=m.heuristic,
        backend=m.backend,
        initial_faults_known=m.plan_with_faults,
        domain=domain,
    )


def observation_options(
    domain: "Domain[Any, Any]", m: MissionOptions
) -> "ObservationModel":
    """The observation model of the options, checked: ``--fault-behaviour`` names a model of the
    robot, ``--noise`` is a rate, both only with ``--detect hidden``; the diagnosis options are
    in range."""
    from selfrepair.diagnosis import ObservationModel
    from selfrepair.execution.faults import Detection

    hidden = m.detect == Detection.HIDDEN
    if m.fault_behaviour is not None:
        if not domain.behaviours:
            raise InputError(
                f"the {domain.name} robot has no fault-behaviour model (a forbidden command "
                "fails)",
                source="--fault-behaviour",
            )
        check_choice(m.fault_behaviour, domain.behaviour_names(), "--fault-behaviour")
    if (m.fault_behaviour is not None or m.noise) and not hidden:
        option = "--noise" if m.noise else "--fault-behaviour"
        raise InputError("expected --detect hidden (faults the robot is not told)", source=option)
    for inside, option, wanted, value in (
        (0.0 <= m.noise < 0.5, "--noise", "in [0, 0.5)", m.noise),
        (0.0 < m.fault_prior < 1.0, "--fault-prior", "in (0, 1)", m.fault_prior),
        (0.0 <= m.confidence < 1.0, "--confidence", "in [0, 1)", m.confidence),
    ):
        if not inside:
            raise InputError(f"expected a number {wanted}, got {value}", source=option)
    return ObservationModel(m.noise, m.bump_switch)


def table_note(mission: MissionOptions, spec: "MissionSpec") -> str | None:
    """One line saying which table the robot got by default (``None`` when ``--table`` named
    one, or when no strategy of the command uses a table)."""
    from selfrepair.tables.fileformat import GENERATED_DEFAULT, default_table_name
    from selfrepair.tables.model import ReplacementTable

    if mission.table is not None or not isinstance(spec.options.table, ReplacementTable):
        return None
    name = default_table_name(spec.domain)
    if name == GENERATED_DEFAULT:
        what = (
            f"generated from the {spec.domain.name} robot model (fault-agnostic, default "
            "options: selfrepair table generate --help)"
        )
    else:
        what = f"{name}, the {spec.domain.name} robot's bundled table"
    return f"table: {what}; --table names another"


_EXACT = ("ticks", "plan_cost_before", "plan_cost_after", "clearance_weight")
"""Columns that hold an exact number as text (``"31/3"``)."""
_EMBEDDED_JSON = ("fault_schedule", "repair_latencies_ns")
"""Columns that hold JSON text (for the results database)."""
_HISTOGRAMS = ("replacement_lengths", "replacement_depths")
"""Columns that hold a ``value:count,...`` histogram as text."""


def row_json(row: "Mapping[str, Any]") -> dict[str, Any]:
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
