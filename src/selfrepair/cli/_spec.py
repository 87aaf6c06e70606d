"""The mission the shared options of ``run`` and ``compare`` describe: every option checked and
turned into a :class:`~selfrepair.execution.result.MissionSpec` (with its fault schedule, its
:class:`~selfrepair.repair.strategies.StrategyOptions` and its observation model), and the line
that names the table a robot got by default. The options themselves are declared once in
:mod:`selfrepair.cli._mission`.

Like the command modules, this module does not use ``from __future__ import annotations``.
"""

from typing import TYPE_CHECKING

from selfrepair.cli._inputs import domain_named, find_input, parse_weight
from selfrepair.cli._mission import MissionOptions, check_choice
from selfrepair.errors import InputError

if TYPE_CHECKING:
    from collections.abc import Sequence

    from selfrepair.diagnosis import ObservationModel
    from selfrepair.diagnosis.cooperative import Observer
    from selfrepair.execution.faults import FaultSchedule
    from selfrepair.execution.result import MissionSpec
    from selfrepair.robots.domain import SomeDomain

__all__ = [
    "build_schedule",
    "mission_spec",
    "observation_options",
    "observer_options",
    "table_note",
]


def build_schedule(
    domain: "SomeDomain",
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
    observers = observer_options(m, domain)
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
        observers=observers,
        clearance_weight=parse_weight(m.clearance_weight),
        seed=m.seed,
        heuristic=m.heuristic,
        backend=m.backend,
        initial_faults_known=m.plan_with_faults,
        domain=domain,
    )


def observation_options(
    domain: "SomeDomain", m: MissionOptions
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
    _in_range(
        (0.0 <= m.noise < 0.5, "--noise", "in [0, 0.5)", m.noise),
        (0.0 < m.fault_prior < 1.0, "--fault-prior", "in (0, 1)", m.fault_prior),
        (0.0 <= m.confidence < 1.0, "--confidence", "in [0, 1)", m.confidence),
    )
    return ObservationModel(m.noise, m.bump_switch)


def observer_options(m: MissionOptions, domain: "SomeDomain") -> "tuple[Observer, ...]":
    """The observing teammates of the options, checked: ``--observers`` in range, and with
    ``--observer-range``, ``--observer-noise`` and ``--observer-view`` only with ``--detect
    hidden`` and at least one observer; ``--observer-view wheels`` only for a robot that
    declares actuators (``domain``)."""
    from selfrepair.diagnosis.cooperative import ObserverView, observer_team
    from selfrepair.execution.faults import Detection
    from selfrepair.limits import DEFAULT_OBSERVER_RANGE, MAX_OBSERVERS

    given = [
        (name, set_)
        for name, set_ in (
            ("--observers", m.observers != 0),
            ("--observer-range", m.observer_range != DEFAULT_OBSERVER_RANGE),
            ("--observer-noise", m.observer_noise is not None),
            ("--observer-view", m.observer_view != ObserverView.POSE.value),
        )
        if set_
    ]
    if given and m.detect != Detection.HIDDEN:
        raise InputError(
            "expected --detect hidden (teammates watch a robot whose faults are hidden)",
            source=given[0][0],
        )
    noise = m.noise if m.observer_noise is None else m.observer_noise
    _in_range(
        (0 <= m.observers <= MAX_OBSERVERS, "--observers", f"from 0 to {MAX_OBSERVERS}",
         m.observers),
        (0 <= m.observer_range <= 64, "--observer-range", "from 0 to 64", m.observer_range),
        (0.0 <= noise < 0.5, "--observer-noise", "in [0, 0.5)", noise),
    )  # fmt: skip
    check_choice(m.observer_view, tuple(v.value for v in ObserverView), "--observer-view")
    if given and not m.observers:
        raise InputError("expected --observers N of at least 1", source=given[0][0])
    view = ObserverView(m.observer_view)
    if view is ObserverView.WHEELS and domain.actuators is None:
        raise InputError(
            f"expected a robot with actuators a teammate can see; {domain.name!r} declares none "
            "(use --observer-view pose)",
            source="--observer-view",
        )
    return observer_team(m.observers, noise, m.observer_range, view)


def _in_range(*checks: tuple[bool, str, str, float]) -> None:
    """Raise the input error of the first ``(inside, option, wanted, value)`` check that is not
    ``inside`` (one message for every numeric option out of its range)."""
    for inside, option, wanted, value in checks:
        if not inside:
            raise InputError(f"expected a number {wanted}, got {value}", source=option)


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
