"""Expand an :class:`ExperimentConfig` into missions, each with a stable key and an explicit seed.

The missions of an experiment are one cross product (:func:`selfrepair.experiment.axes.cross`)
over its factor axes: (maze, route), fault set, fault time, detection, noise, observers,
replicate, world setting, (strategy variant, clearance weight) and simulator, the last varying
fastest; :func:`count_missions` multiplies the same axes, with the routes and variants counted
from the configuration. Keys and seeds are made as described in
:mod:`selfrepair.experiment.keys`; fault sets come from :mod:`selfrepair.experiment.faultsets`,
mazes and routes from :mod:`selfrepair.experiment.mazes`, strategy variants from
:mod:`selfrepair.experiment.variants`.

Limits (:mod:`selfrepair.limits`) are checked by :func:`expand` before the work they guard: the
number of missions is counted from the configuration (:func:`count_missions`) before any mission
is built, maze files against ``max_cells`` before they are hashed and read, and table files are
loaded once with the default table limits, so a bad table stops the experiment before its sweep.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

from selfrepair.diagnosis import (
    DEFAULT_CONFIDENCE,
    DEFAULT_FAULT_PRIOR,
    DEFAULT_MAX_FAULTS,
    ObservationModel,
)
from selfrepair.diagnosis.cooperative import Observer, ObserverView, observer_team
from selfrepair.errors import ConfigError
from selfrepair.execution.faults import Detection, FaultEvent, FaultSchedule, canonical_order
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.axes import Axis, Factor, Tally, cross, describe, total
from selfrepair.experiment.faultsets import fault_profile
from selfrepair.experiment.faultsteps import random_fault_step
from selfrepair.experiment.keys import (
    SCHEMA,
    Mission,
    canonical_json,
    derive_seed,
    keyed_mission,
    plugin_identities,
    portable,
)
from selfrepair.experiment.mazes import (
    entry_label,
    maze_identity,
    maze_label,
    maze_of,
    route_count,
    routes_of,
)
from selfrepair.experiment.schema import ExperimentConfig
from selfrepair.experiment.variants import (
    maze_filter,
    objective_label,
    short_table,
    variant_count,
    variant_label,
    variants_of,
)
from selfrepair.experiment.worlds import mission_world
from selfrepair.geometry import parse_cell, parse_pose
from selfrepair.limits import MAX_CELLS, MAX_MISSIONS, check_limit
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import OPTIMAL, parse_objective
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.registry import get_domain, load_plugin
from selfrepair.world.events import WorldSchedule
from selfrepair.world.routes import Route

__all__ = ["count_missions", "expand", "to_spec"]


def count_missions(config: ExperimentConfig) -> int:
    """How many missions ``config`` asks for, by arithmetic, before any is built.

    The product of routes (summed over the mazes), fault sets, fault times, detections, repeats
    and strategy variants (tables x recursion modes x windows, each times its clearance weights);
    a strategy limited to some mazes (``mazes``) counts the routes of those only. Duplicates are
    not subtracted, so :func:`expand` may give fewer. Bundled maze names must be valid
    (:func:`expand` checks them first).
    """
    return total(_count_factors(config, _situation_axes(config, get_domain(config.domain))))


def _situation_axes(config: ExperimentConfig, domain: SomeDomain) -> tuple[Axis, ...]:
    """The axes between the route and the strategy variant: what happens to the robot (fault
    set, fault time, detection, noise, observers), the replicate and the world setting."""
    faults = config.faults
    return (
        Axis("faults", fault_profile(faults.sets, domain), "fault sets"),
        Axis("fault_at", (RANDOM,) if faults.at_random else faults.at, "fault times"),
        Axis("detection", tuple(faults.detection), "detections"),
        Axis("noise", tuple(faults.noise), "noise rates"),
        Axis("observers", tuple(faults.observers), "observer counts"),
        Axis("replicate", tuple(range(config.repeats)), "repeats"),
        Axis("world", _worlds(config), "world settings"),
    )


def _count_factors(config: ExperimentConfig, situation: Sequence[Axis]) -> tuple[Factor, ...]:
    """The factors of :func:`expand`'s cross product, with the routes and strategy variants
    counted from the configuration (no maze file read): routes x ``situation`` x variants x
    simulators, or, when a strategy is limited to some mazes, the variants times their routes
    as one factor."""
    routes: dict[str, int] = {}
    for entry in config.mazes:
        label = entry_label(entry)
        routes[label] = routes.get(label, 0) + route_count(entry)
    all_routes = sum(routes.values())
    variants = runs = 0
    for strategy in config.strategies:
        count = variant_count(strategy, config)
        variants += count
        mazes = strategy.mazes
        runs += count * (all_routes if mazes is None else sum(routes.get(m, 0) for m in mazes))
    simulators = Axis("simulator", _simulators(config), "simulators")
    if any(s.mazes is not None for s in config.strategies):
        joint = Tally("strategy variants and weights x their routes", runs)
        return (joint, *situation, simulators)
    variant = Tally("strategy variants and weights", variants)
    return (Tally("routes", all_routes), *situation, variant, simulators)


def expand(
    config: ExperimentConfig,
    *,
    max_missions: int | None = MAX_MISSIONS,
    max_cells: int | None = MAX_CELLS,
) -> tuple[Mission, ...]:
    """Every mission of ``config``, in a deterministic order, with keys and seeds.

    Duplicate missions (the same canonical configuration reached twice) appear once. Raises
    :class:`~selfrepair.errors.LimitError` before building any mission when
    :func:`count_missions` exceeds ``max_missions``, or when a maze has more than ``max_cells``
    cells, and :class:`~selfrepair.errors.ConfigError` when the experiment has no mission.
    """
    identities = [
        maze_identity(entry, config.base_dir, config.source, index, max_cells)
        for index, entry in enumerate(config.mazes)
    ]
    domain = get_domain(config.domain)
    situation_axes = _situation_axes(config, domain)
    factors = _count_factors(config, situation_axes)
    check_limit(
        total(factors),
        max_missions,
        name="max_missions",
        what="missions",
        detail=describe(factors),
        source=config.source,
    )
    labels = [maze_label(identity) for identity in identities]
    variants = tuple(
        (variant, weight, maze_filter(strategy, index, labels, config.source))
        for index, strategy in enumerate(config.strategies)
        for variant, weights in variants_of(strategy, config)
        for weight in weights
    )
    plugins = plugin_identities(config)
    routes = tuple(
        (label, identity, route)
        for index, (entry, identity, label) in enumerate(
            zip(config.mazes, identities, labels, strict=True)
        )
        for route in routes_of(entry, identity, config.seed, config.source, index, max_cells)
    )
    fault_sets = next(axis.values for axis in situation_axes if axis.name == "faults")
    fault_count = {text: len(domain.parse_faults(str(text))) for text in fault_sets}  # robot's word
    axes = (
        Axis("route", routes, "routes"),
        *situation_axes,
        Axis("variant", variants, "strategy variants and weights"),
        Axis("simulator", _simulators(config), "simulators"),
    )
    missions: dict[str, Mission] = {}
    for point in cross(axes):
        label, identity, route = point["route"]
        variant, weight, only = point["variant"]
        if only is not None and label not in only:
            continue
        situation: dict[str, Any] = {
            "schema": SCHEMA,
            "maze": identity,
            "route": route.name,
            "start": str(route.start),
            "goal": f"{route.goal[0]},{route.goal[1]}",
            "faults": point["faults"],
            "fault_at": _fault_step(config, identity, route, point, domain),
            **({"fault_at_random": True} if config.faults.at_random else {}),
            "fault_clock": config.faults.clock,
            "persistence": config.faults.persistence,
            "fault_duration": config.faults.duration,
            "fault_probability": config.faults.probability,
            "detection": point["detection"],
            "replicate": point["replicate"],
        }
        if point["world"] is not None:  # absent without a [world] section: older keys stay valid
            situation["world"] = point["world"]
        if point["detection"] == Detection.HIDDEN:  # absent otherwise, so older keys stay valid
            situation["behaviour"] = config.faults.behaviour
            situation["noise"] = point["noise"]
            situation["bump_switch"] = config.faults.bump_switch
            if point["observers"]:  # absent when alone, so older keys stay valid
                situation["observers"] = {
                    "count": point["observers"],
                    "range": config.faults.observer_range,
                    "noise": point["noise"]
                    if config.faults.observer_noise is None
                    else config.faults.observer_noise,
                }
                if config.faults.observer_view is not ObserverView.POSE:  # older keys: pose
                    situation["observers"]["view"] = config.faults.observer_view.value
        if domain is not FOUR_WHEEL:  # absent for the four-wheel robot, so older keys stay valid
            situation["domain"] = domain.name
        if plugins:
            situation["plugins"] = plugins
        seed = derive_seed(config.seed, portable(situation))
        count = fault_count[point["faults"]]
        mission = _mission(
            config, situation, seed, variant, weight, label, count, point["simulator"]
        )
        missions.setdefault(mission.key, mission)
    if not missions:
        raise ConfigError(
            "expected an experiment with at least one mission, got none", source=config.source
        )
    return tuple(missions.values())


def _mission(
    config: ExperimentConfig,
    situation: dict[str, Any],
    seed: int,
    variant: dict[str, Any],
    weight: str,
    label: str,
    fault_count: int,
    simulator: dict[str, Any] | None,
) -> Mission:
    """One mission: the situation with its variant, weight, seed and (with a ``[physics]``
    section) simulator, keyed and labelled (``fault_count``: the faults of its fault set, as
    the robot's domain reads the text)."""
    settings = {
        **situation,
        **variant,
        "clearance_weight": weight,
        "clearance_radius": config.planner.clearance_radius,
        "seed": seed,
    }
    if simulator is not None:  # absent without a [physics] section: older keys stay valid
        settings["simulator"] = simulator
    options = variant["options"]
    labels: tuple[tuple[str, str | int | None], ...] = (
        ("maze", label),
        ("route", situation["route"]),
        ("faults", situation["faults"]),
        ("fault_count", fault_count),
        ("fault_at", situation["fault_at"]),
        ("detection", situation["detection"]),
        ("replicate", situation["replicate"]),
        ("strategy", variant["strategy"]),
        ("variant", variant_label(variant["strategy"], options)),
        ("base_variant", variant_label(variant["strategy"], _without_objective(options))),
        ("table", short_table(options.get("table"))),
        ("recursion", options.get("recursion")),
        ("window", options.get("window")),
        ("before", options.get("before", 0) if "window" in options else None),
        ("rewrite", int(bool(options.get("rewrite"))) if "table" in options else None),
        ("clearance_weight", weight),
        ("objective", objective_label(options, weight)),
    )
    world = situation.get("world")
    if world is not None:
        labels += (("world_rate", str(world["rate"])), ("sensing", world["sensing"]))
    if simulator is not None:
        labels += (("simulator", simulator["name"]),)
    return keyed_mission(config.name, seed, settings, labels)


def _without_objective(options: dict[str, Any]) -> dict[str, Any]:
    """The variant's options but its planning objective: what a tolerant robot is compared on
    (column ``base_variant``; the same as ``variant`` for a robot planned without one)."""
    return {k: v for k, v in options.items() if k != "objective"}


def _worlds(config: ExperimentConfig) -> tuple[dict[str, Any] | None, ...]:
    """The world settings of the ``world`` axis: one per rate and sensing mode, or ``None``
    alone when the experiment's maze never changes."""
    world = config.world
    if world is None:
        return (None,)
    return tuple(
        {
            "rate": rate,
            "duration": world.duration,
            "distance": world.distance,
            "horizon": world.horizon,
            "sensing": str(sensing),
            "range": world.range,
            "max_wait": world.max_wait,
        }
        for rate in world.rates
        for sensing in world.sensing
    )


def _simulators(config: ExperimentConfig) -> tuple[dict[str, Any] | None, ...]:
    """The values of the ``simulator`` axis: one per simulator of the ``[physics]`` section
    (physics with its tracking), or ``None`` alone without one (the lattice simulator)."""
    physics = config.physics
    if physics is None:
        return (None,)
    return tuple(
        {"name": name, **({"tracked": physics.tracked} if name == "physics" else {})}
        for name in physics.simulators
    )


RANDOM = "random"
"""The ``fault_at`` axis value of ``at_random``: one step drawn per situation."""


def _fault_step(
    config: ExperimentConfig,
    identity: dict[str, Any],
    route: Route,
    point: dict[str, Any],
    domain: SomeDomain,
) -> int:
    """When the faults of one situation (``point``) appear: its ``fault_at``, or for
    :data:`RANDOM` one step drawn
    (seeded by the maze, route and fault set) from the route's optimal plan
    (:func:`~selfrepair.experiment.faultsteps.random_fault_step`), the same for every strategy
    and objective."""
    at, faults = point["fault_at"], point["faults"]
    if at != RANDOM:
        return int(at)
    where = portable({"maze": identity, "route": route.name, "faults": faults, "at": RANDOM})
    maze = maze_of(canonical_json(identity))
    return random_fault_step(maze, route, domain, derive_seed(config.seed, where))


def _observers(settings: dict[str, Any] | None) -> tuple[Observer, ...]:
    """The observing teammates of a mission's ``observers`` setting (none when absent), named
    ``t1``, ``t2``, ... as in :mod:`selfrepair.diagnosis.cooperative`, with the setting's
    ``view`` (absent: ``pose``)."""
    if not settings:
        return ()
    view = ObserverView(settings.get("view", ObserverView.POSE.value))
    return observer_team(
        int(settings["count"]), float(settings["noise"]), int(settings["range"]), view
    )


def to_spec(mission: Mission) -> MissionSpec:
    """The executor's :class:`~selfrepair.execution.result.MissionSpec` for ``mission``.

    Mazes and tables are loaded once per process (cached), so a worker pays for them once.
    """
    s = mission.settings
    for plugin in s.get("plugins", []):
        load_plugin(plugin["file"])  # a worker process loads the robot before it is looked up
    domain = get_domain(s.get("domain", FOUR_WHEEL.name))
    events = tuple(
        FaultEvent(
            fault,
            at=s["fault_at"],
            clock=s["fault_clock"],
            persistence=s["persistence"],
            duration=s["fault_duration"],
            probability=s["fault_probability"],
        )
        for fault in canonical_order(domain.parse_faults(s["faults"]))
    )
    options = s["options"]
    maze, start, goal = (
        maze_of(canonical_json(s["maze"])),
        parse_pose(s["start"]),
        parse_cell(s["goal"]),
    )
    world = s.get("world")
    return MissionSpec(
        maze=maze,
        start=start,
        goal=goal,
        schedule=FaultSchedule(events=events, detection=s["detection"]),
        world=WorldSchedule()
        if world is None
        else mission_world(world, maze, start, goal, domain, mission.seed),
        strategy=s["strategy"],
        options=StrategyOptions(
            table=options.get("table", "handwritten"),
            recursion=options.get("recursion", RecursionMode.FLAT),
            window=options.get("window", 3),
            before=options.get("before", 0),
            lpg_time_limit_s=options.get("lpg_time_limit_s", 5.0),
            lpg_seed=options.get("lpg_seed", 0),
            rewrite=options.get("rewrite", False),
            max_faults=options.get("max_faults", DEFAULT_MAX_FAULTS),
            fault_prior=options.get("fault_prior", DEFAULT_FAULT_PRIOR),
            confidence=options.get("confidence", DEFAULT_CONFIDENCE),
            **({} if world is None else {"max_wait": world["max_wait"]}),
        ),
        behaviour=s.get("behaviour"),
        observation=ObservationModel(s.get("noise", 0.0), s.get("bump_switch", True)),
        observers=_observers(s.get("observers")),
        objective=parse_objective(options.get("objective", OPTIMAL)),
        clearance_weight=Fraction(s["clearance_weight"]),
        clearance_radius=s["clearance_radius"],
        seed=mission.seed,
        backend=options.get("backend", "auto"),
        domain=domain,
    )
