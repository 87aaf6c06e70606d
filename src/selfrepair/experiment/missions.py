"""Expand an :class:`ExperimentConfig` into missions, each with a stable key and an explicit seed.

A :class:`Mission` carries the *canonical configuration* of one run as a JSON string with sorted
keys: maze identity (bundled name, file path plus content hash, or generator options), route,
fault set, fault timing and detection, strategy and its options, clearance weight and radius,
replicate and seed. The mission key is the SHA-256 of that string, so the same mission gets the
same key in every run and on every machine, and changing anything about a mission (including the
content of a maze or table file) gives it a new key. Files enter the key by name and content
hash, not by absolute path (:func:`portable`), so moving a checkout keeps every key. That is
what makes a sweep resumable.

The seed of a mission derives from the experiment's base seed and the mission's *situation*
(maze, route, faults, timing, detection, replicate) but not from its strategy: every strategy
meets the same random events (e.g. intermittent faults), so comparisons are paired.

The paper's 12 fault sets (:data:`PAPER_FAULT_SETS`) are explained in ``docs/experiments.md``.

Limits (:mod:`selfrepair.limits`) are checked by :func:`expand` before the work they guard: the
number of missions is counted from the configuration (:func:`count_missions`) before any mission
is built, maze files against ``max_cells`` before they are hashed and read, and table files are
loaded once with the default table limits, so a bad table stops the experiment before its sweep.
"""

from __future__ import annotations

import hashlib
import json
from collections import Counter
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import Any

from selfrepair.errors import ConfigError, LimitError
from selfrepair.execution.faults import FaultEvent, FaultSchedule, canonical_order
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.config import (
    ExperimentConfig,
    LookaheadStrategy,
    LpgAdaptStrategy,
    MazeConfig,
    ReplacementStrategy,
    ReplanStrategy,
    StrategyConfig,
)
from selfrepair.experiment.faultsteps import random_fault_step
from selfrepair.geometry import parse_cell, parse_pose
from selfrepair.limits import MAX_CELLS, MAX_MISSIONS, check_limit, maze_file_bytes
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import OPTIMAL, parse_objective
from selfrepair.robots.domain import Domain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.registry import get_domain, load_plugin
from selfrepair.world.maze import Maze
from selfrepair.world.routes import Route, random_routes

__all__ = [
    "BUNDLED_TABLES",
    "PAPER_FAULT_SETS",
    "REWRITE_LABEL",
    "SCHEMA",
    "Mission",
    "biting_fault_sets",
    "count_missions",
    "expand",
    "fault_profile",
    "maze_label",
    "maze_of",
    "portable",
    "random_routes",
    "to_spec",
    "variant_label",
]

SCHEMA = 1
"""Version of the canonical mission configuration; part of every key."""

PAPER_FAULT_SETS: tuple[str, ...] = (
    # chosen by biting_fault_sets (the rule in docs/experiments.md): each disables at least one
    # action of the initial plan of every one of the 16 bundled routes; singles first, then
    # doubles that spread the faults over wheels and modes
    "FL:F",
    "RL:F",
    "FR:B,RL:S",
    "RR:B,RR:F",
    "FL:S,FL:F",
    "FR:S,FR:F",
    "RL:B,RL:S",
    "FL:F,RR:B",
    "RL:S,RR:B",
    "FR:B,FR:F",
    "FL:F,RR:S",
    "FL:B,RL:S",
)
"""The reference experiment's 12 fault sets; see :func:`biting_fault_sets` and
docs/experiments.md (a test checks that the rule gives exactly these)."""


def biting_fault_sets(
    domain: Domain[Any, Any], plans: Iterable[Sequence[Any]], count: int
) -> tuple[str, ...]:
    """The rule behind :data:`PAPER_FAULT_SETS`: among ``domain.fault_sets``, those that disable
    at least one action of **every** plan of ``plans`` (so every mission meets a faulty action
    unless a repair steers round it), at most ``count`` of them, smallest sets first, then greedily
    the set whose wheels and modes (the two halves of ``W:M``) were used least by the sets chosen
    so far, ties to the earlier in ``domain.fault_sets``."""
    plans = [tuple(p) for p in plans]
    biting = [
        faults
        for faults in domain.fault_sets
        if all(any(not domain.available(a, faults) for a in p) for p in plans)
    ]
    used: Counter[str] = Counter()

    def halves(faults: frozenset[Any]) -> list[str]:
        return [part for f in faults for part in domain.format_faults((f,)).split(":")]

    chosen: list[str] = []
    while biting and len(chosen) < count:
        best = min(biting, key=lambda fs: (len(fs), sum(used[h] for h in halves(fs))))
        biting.remove(best)
        used.update(halves(best))
        chosen.append(domain.format_faults(best))
    return tuple(chosen)


BUNDLED_TABLES = ("handwritten", "generated-agnostic", "generated-indexed")
"""Table names resolved from package data; anything else is a path to a table file."""


@dataclass(frozen=True, slots=True)
class Mission:
    """One run of the executor, as plain data.

    ``config`` is the canonical JSON (sorted keys, no spaces) that ``key`` hashes; ``labels`` are
    the readable dimension columns stored next to the metrics (maze, route, faults, variant, ...).
    """

    key: str
    experiment: str
    seed: int
    config: str
    labels: tuple[tuple[str, str | int | None], ...]

    @property
    def settings(self) -> dict[str, Any]:
        """The canonical configuration as a dict."""
        return dict(json.loads(self.config))


def canonical_json(data: Any) -> str:
    """Sorted-key, compact JSON: the exact text a mission key hashes."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def mission_key(config_json: str) -> str:
    """The stable key of a mission: the first 32 hex digits of SHA-256 of its canonical JSON."""
    return hashlib.sha256(config_json.encode("ascii")).hexdigest()[:32]


def derive_seed(base_seed: int, situation: dict[str, Any]) -> int:
    """A 32-bit seed from the base seed and a mission's situation (strategy-independent)."""
    digest = hashlib.sha256(f"{base_seed}|{canonical_json(situation)}".encode("ascii")).digest()
    return int.from_bytes(digest[:4], "big")


# --- faults ------------------------------------------------------------------------------------


def fault_profile(
    sets: str | tuple[str, ...], domain: Domain[Any, Any] = FOUR_WHEEL
) -> tuple[str, ...]:
    """The fault sets of a profile name or an explicit list, each in ``domain``'s canonical text.

    ``singles``, ``doubles`` and ``all`` come from ``domain.fault_sets``; ``paper`` is the
    four-wheel robot's 12 (:data:`PAPER_FAULT_SETS`)."""
    if isinstance(sets, tuple):
        return sets
    singles = tuple(domain.format_faults(f) for f in domain.fault_sets if len(f) == 1)
    doubles = tuple(domain.format_faults(f) for f in domain.fault_sets if len(f) == 2)
    if sets == "paper":
        if domain is not FOUR_WHEEL:
            raise ConfigError(
                f'the "paper" fault profile is for the four-wheel robot, not {domain.name!r}'
            )
        return tuple(domain.format_faults(domain.parse_faults(s)) for s in PAPER_FAULT_SETS)
    profiles = {"singles": singles, "doubles": doubles, "all": singles + doubles}
    return profiles[sets]


# --- mazes and routes --------------------------------------------------------------------------


def maze_identity(
    entry: MazeConfig, base_dir: Path, source: str, index: int, max_cells: int | None = MAX_CELLS
) -> dict[str, Any]:
    """What identifies a maze in a mission key (a file is identified by path and content hash).

    A maze file too big to hold ``max_cells`` cells is refused before it is hashed."""
    if entry.bundled is not None:
        from selfrepair.world.bundled import maze_names

        if entry.bundled not in maze_names():
            raise ConfigError(
                f"key 'mazes[{index}].bundled': expected one of {', '.join(maze_names())}, "
                f"got {entry.bundled!r}",
                source=source,
            )
        return {"bundled": entry.bundled}
    if entry.file is not None:
        path = (base_dir / entry.file).resolve()
        try:
            size = path.stat().st_size
            check_limit(
                size,
                maze_file_bytes(max_cells),
                name="max_cells",
                what="bytes in a maze file",
                source=str(path),
            )
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError as exc:
            raise ConfigError(
                f"key 'mazes[{index}].file': cannot read maze file {str(path)!r}: {exc.strerror}",
                source=source,
            ) from None
        return {"file": str(path), "sha256": digest}
    assert entry.generate is not None
    return {"generate": entry.generate.model_dump()}


def maze_label(identity: dict[str, Any]) -> str:
    """A short readable name for a maze identity (bundled name, file stem or generator spec)."""
    if "bundled" in identity:
        return str(identity["bundled"])
    if "file" in identity:
        return Path(identity["file"]).stem
    g = identity["generate"]
    braid = f"-b{g['braid']:g}" if g["braid"] else ""
    return f"gen{g['width']}x{g['height']}-c{g['corridor']}{braid}-s{g['seed']}"


def maze_of(identity_json: str, *, max_cells: int | None = None) -> Maze:
    """The maze of an identity (as canonical JSON, so results can be cached per process).

    ``max_cells`` is checked by :func:`expand`; it is off by default because the missions that
    workers load mazes for come from :func:`expand`, which has checked their mazes already.
    """
    return _maze_cached(identity_json, max_cells)


@lru_cache(maxsize=64)
def _maze_cached(identity_json: str, max_cells: int | None) -> Maze:
    identity = json.loads(identity_json)
    if "bundled" in identity:
        from selfrepair.world.bundled import load_bundled

        return load_bundled(identity["bundled"])
    if "file" in identity:
        from selfrepair.world.loading import load_maze

        return load_maze(identity["file"], max_cells=max_cells)
    from selfrepair.world.mazegen import generate_maze

    g = identity["generate"]
    return generate_maze(
        g["width"],
        g["height"],
        corridor=g["corridor"],
        braid=g["braid"],
        seed=g["seed"],
        name=maze_label(identity),
        max_cells=max_cells,
    )


def routes_of(
    entry: MazeConfig,
    identity: dict[str, Any],
    base_seed: int,
    source: str,
    index: int,
    max_cells: int | None = MAX_CELLS,
) -> tuple[Route, ...]:
    """The routes of one maze entry: bundled, random (seeded) or explicit (checked free)."""
    if entry.routes == "bundled":
        from selfrepair.world.bundled import bundled_routes

        assert entry.bundled is not None
        return bundled_routes(entry.bundled)
    maze = maze_of(canonical_json(identity), max_cells=max_cells)
    if isinstance(entry.routes, int):
        where = portable({"maze": identity})["maze"]  # seeded by content, not location
        return random_routes(maze, entry.routes, derive_seed(base_seed, {"routes": where}))
    routes = []
    for n, r in enumerate(entry.routes):
        route = Route(r.name or f"r{n + 1}", parse_pose(r.start), parse_cell(r.goal))
        for what, cell in (("start", route.start.cell), ("goal", route.goal)):
            if not maze.is_free(*cell):
                raise ConfigError(
                    f"key 'mazes[{index}].routes[{n}].{what}': expected a free cell of maze "
                    f"{maze_label(identity)!r}, got {cell[0]},{cell[1]}",
                    source=source,
                )
        routes.append(route)
    return tuple(routes)


# --- strategies --------------------------------------------------------------------------------


def strategy_variants(config: ExperimentConfig) -> Iterator[tuple[dict[str, Any], tuple[str, ...]]]:
    """Every (strategy settings, clearance weights) pair the config asks for."""
    for strategy in config.strategies:
        yield from _strategy_variants(strategy, config)


def _strategy_variants(
    strategy: StrategyConfig, config: ExperimentConfig
) -> Iterator[tuple[dict[str, Any], tuple[str, ...]]]:
    """The (strategy settings, clearance weights) pairs of one strategy entry."""
    weights = strategy.clearance_weights or config.planner.clearance_weights
    if isinstance(strategy, ReplacementStrategy):
        windows: tuple[tuple[int | None, int], ...] = (
            tuple((w, b) for w in strategy.window for b in strategy.before)
            if isinstance(strategy, LookaheadStrategy)
            else ((None, 0),)
        )
        for table in strategy.tables:
            for recursion in strategy.recursion:
                for window, before in windows:
                    for rewrite in strategy.rewrite:
                        for objective in strategy.objectives:
                            options: dict[str, Any] = {
                                **_table_identity(table, config),
                                "recursion": recursion,
                            }
                            if window is not None:
                                options["window"] = window
                            if before:  # absent when 0, so older mission keys stay valid
                                options["before"] = before
                            if rewrite:  # absent when false, so older mission keys stay valid
                                options["rewrite"] = True
                            if objective != OPTIMAL:  # absent when optimal, likewise
                                options["objective"] = objective
                            yield {"strategy": strategy.name, "options": options}, weights
    else:
        yield {"strategy": strategy.name, "options": _plain_options(strategy)}, weights


def _maze_filter(
    strategy: StrategyConfig, index: int, labels: list[str], source: str
) -> frozenset[str] | None:
    """The maze labels strategy ``index`` is limited to (``None``: all), each checked to name a
    maze of the experiment."""
    if strategy.mazes is None:
        return None
    for name in strategy.mazes:
        if name not in labels:
            raise ConfigError(
                f"key 'strategies[{index}].mazes': expected names of this experiment's mazes "
                f"({', '.join(dict.fromkeys(labels))}), got {name!r}",
                source=source,
            )
    return frozenset(strategy.mazes)


def _entry_label(entry: MazeConfig) -> str:
    """The label :func:`maze_label` gives a maze entry, without reading its file."""
    if entry.bundled is not None:
        return entry.bundled
    if entry.file is not None:
        return Path(entry.file).stem
    assert entry.generate is not None
    return maze_label({"generate": entry.generate.model_dump()})


def _plain_options(strategy: StrategyConfig) -> dict[str, Any]:
    """The options of a strategy without a table, as its missions record them (defaults left
    out, so that the keys of missions made before an option existed stay valid)."""
    if isinstance(strategy, ReplanStrategy) and strategy.backend != "auto":
        return {"backend": strategy.backend}
    if isinstance(strategy, LpgAdaptStrategy):
        return {"lpg_time_limit_s": strategy.time_limit, "lpg_seed": strategy.seed}
    return {}


def _table_identity(table: str, config: ExperimentConfig) -> dict[str, str]:
    """A bundled table by name; a table file by its absolute path (to load it) and the SHA-256
    of its content (so editing the file gives its missions new keys)."""
    if table in BUNDLED_TABLES:
        return {"table": table}
    path = (config.base_dir / table).resolve()
    if not path.is_file():
        raise ConfigError(
            f"key 'strategies[].tables': expected one of {', '.join(BUNDLED_TABLES)} or a "
            f"readable table file, got {table!r}",
            source=config.source,
        )
    _check_table(path)
    try:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as exc:
        raise ConfigError(
            f"key 'strategies[].tables': cannot read table file {table!r}: {exc.strerror}",
            source=config.source,
        ) from None
    return {"table": str(path), "table_sha256": digest}


def _check_table(path: Path) -> None:
    """Load a table file once, with the default limits, so that a bad or oversized table stops
    the experiment before its sweep (the workers load it again, with the same limits)."""
    from selfrepair.tables.fileformat import load_table

    try:
        load_table(path)
    except LimitError as exc:
        raise LimitError(
            exc.message,
            limit=exc.limit,
            note="experiment workers load tables with the default limits, not raised by flags",
            source=exc.source,
            line=exc.line,
        ) from None


def _plugin_identities(config: ExperimentConfig) -> list[dict[str, str]]:
    """Each plug-in file of ``config`` by absolute path (to load it in workers) and content hash
    (so editing the robot gives its missions new keys)."""
    out = []
    for plugin in config.plugins:
        path = (config.base_dir / plugin).resolve()
        out.append({"file": str(path), "sha256": load_plugin(path)})
    return out


def portable(settings: dict[str, Any]) -> dict[str, Any]:
    """``settings`` as the key and seed see them: files by name and content hash, not by their
    absolute path, so a checkout or data directory can move without changing any key."""
    out = dict(settings)
    maze = out.get("maze")
    if isinstance(maze, dict) and "file" in maze:
        out["maze"] = {**maze, "file": Path(maze["file"]).name}
    plugins = out.get("plugins")
    if isinstance(plugins, list):
        out["plugins"] = [{**p, "file": Path(p["file"]).name} for p in plugins]
    options = out.get("options")
    if isinstance(options, dict) and "table_sha256" in options:
        out["options"] = {**options, "table": Path(options["table"]).name}
    return out


REWRITE_LABEL = "rewrite"
"""The part of a variant label that marks whole-plan rewriting, e.g.
``replacement[handwritten,guarded,rewrite]``."""


def variant_label(strategy: str, options: dict[str, Any]) -> str:
    """A short readable strategy variant, e.g. ``replacement[handwritten,guarded]``."""
    if not options:
        return strategy
    parts = []
    if "table" in options:
        table = str(options["table"])
        parts.append(table if table in BUNDLED_TABLES else Path(table).stem)
    if "recursion" in options:
        parts.append(str(options["recursion"]))
    if "window" in options:
        parts.append(f"k={options['window']}")
    if options.get("before"):
        parts.append(f"before={options['before']}")
    if "backend" in options:
        parts.append(str(options["backend"]))
    if "lpg_time_limit_s" in options:
        parts.append(f"{options['lpg_time_limit_s']:g}s")
    if options.get("lpg_seed"):
        parts.append(f"seed={options['lpg_seed']}")
    if options.get("rewrite"):
        parts.append(REWRITE_LABEL)
    if options.get("objective"):
        parts.append(str(options["objective"]))
    return f"{strategy}[{','.join(parts)}]"


def objective_label(options: dict[str, Any], weight: str) -> str:
    """The ``objective`` column: ``optimal``, ``clearance W``, ``tolerant k=K``, ``tolerant soft
    L k=K`` (with ``, clearance W`` when a tolerant objective also has a weight)."""
    clearance = "" if Fraction(weight) == 0 else f"clearance {weight}"
    tolerant = str(options.get("objective") or "")
    if not tolerant:
        return clearance or OPTIMAL
    return f"{tolerant}, {clearance}" if clearance else tolerant


# --- expansion ---------------------------------------------------------------------------------


def count_missions(config: ExperimentConfig) -> int:
    """How many missions ``config`` asks for, by arithmetic, before any is built.

    The product of routes (summed over the mazes), fault sets, fault times, detections, repeats
    and strategy variants (tables x recursion modes x windows, each times its clearance weights);
    a strategy limited to some mazes (``mazes``) counts the routes of those only. Duplicates are
    not subtracted, so :func:`expand` may give fewer. Bundled maze names must be valid
    (:func:`expand` checks them first).
    """
    return _mission_factors(config)[0]


def _mission_factors(config: ExperimentConfig) -> tuple[int, str]:
    """The mission count and how it came about, as text for a message."""
    routes: dict[str, int] = {}
    for entry in config.mazes:
        if entry.routes == "bundled":
            from selfrepair.world.bundled import bundled_routes

            assert entry.bundled is not None
            count = len(bundled_routes(entry.bundled))
        else:
            count = entry.routes if isinstance(entry.routes, int) else len(entry.routes)
        label = _entry_label(entry)
        routes[label] = routes.get(label, 0) + count
    all_routes = sum(routes.values())
    variants = runs = 0
    for strategy in config.strategies:
        weights = len(strategy.clearance_weights or config.planner.clearance_weights)
        if isinstance(strategy, ReplacementStrategy):
            windows = (
                len(strategy.window) * len(strategy.before)
                if isinstance(strategy, LookaheadStrategy)
                else 1
            )
            count = (
                len(strategy.tables)
                * len(strategy.recursion)
                * windows
                * len(strategy.rewrite)
                * len(strategy.objectives)
                * weights
            )
        else:
            count = weights
        variants += count
        mazes = strategy.mazes
        runs += count * (all_routes if mazes is None else sum(routes.get(m, 0) for m in mazes))
    faults = config.faults
    filtered = any(s.mazes is not None for s in config.strategies)
    factors = [
        (runs, "strategy variants and weights x their routes")
        if filtered
        else (all_routes, "routes"),
        (len(fault_profile(faults.sets, get_domain(config.domain))), "fault sets"),
        (1 if faults.at_random else len(faults.at), "fault times"),
        (len(faults.detection), "detections"),
        (config.repeats, "repeats"),
    ]
    if not filtered:
        factors.append((variants, "strategy variants and weights"))
    total = 1
    for count, _ in factors:
        total *= count
    return total, " x ".join(f"{what} {count:,}" for count, what in factors)


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
    total, factors = _mission_factors(config)
    check_limit(
        total,
        max_missions,
        name="max_missions",
        what="missions",
        detail=factors,
        source=config.source,
    )
    labels = [maze_label(identity) for identity in identities]
    variants = [
        (variant, weights, _maze_filter(strategy, index, labels, config.source))
        for index, strategy in enumerate(config.strategies)
        for variant, weights in _strategy_variants(strategy, config)
    ]
    plugins = _plugin_identities(config)
    domain = get_domain(config.domain)
    fault_sets = fault_profile(config.faults.sets, domain)
    missions: dict[str, Mission] = {}
    for index, (entry, identity) in enumerate(zip(config.mazes, identities, strict=True)):
        label = maze_label(identity)
        routes = routes_of(entry, identity, config.seed, config.source, index, max_cells)
        for route in routes:
            for faults in fault_sets:
                for at in _fault_steps(config, identity, route, faults, domain):
                    for detection in config.faults.detection:
                        for replicate in range(config.repeats):
                            situation: dict[str, Any] = {
                                "schema": SCHEMA,
                                "maze": identity,
                                "route": route.name,
                                "start": str(route.start),
                                "goal": f"{route.goal[0]},{route.goal[1]}",
                                "faults": faults,
                                "fault_at": at,
                                **({"fault_at_random": True} if config.faults.at_random else {}),
                                "fault_clock": config.faults.clock,
                                "persistence": config.faults.persistence,
                                "fault_duration": config.faults.duration,
                                "fault_probability": config.faults.probability,
                                "detection": detection,
                                "replicate": replicate,
                            }
                            if domain is not FOUR_WHEEL:  # absent for the four-wheel robot,
                                situation["domain"] = domain.name  # so older keys stay valid
                            if plugins:
                                situation["plugins"] = plugins
                            seed = derive_seed(config.seed, portable(situation))
                            for variant, weights, only in variants:
                                if only is not None and label not in only:
                                    continue
                                for weight in weights:
                                    mission = _mission(
                                        config, situation, seed, variant, weight, label
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
) -> Mission:
    settings = {
        **situation,
        **variant,
        "clearance_weight": weight,
        "clearance_radius": config.planner.clearance_radius,
        "seed": seed,
    }
    text = canonical_json(settings)
    key = mission_key(canonical_json(portable(settings)))
    options = variant["options"]
    labels: tuple[tuple[str, str | int | None], ...] = (
        ("maze", label),
        ("route", situation["route"]),
        ("faults", situation["faults"]),
        ("fault_count", len(situation["faults"].split(",")) if situation["faults"] else 0),
        ("fault_at", situation["fault_at"]),
        ("detection", situation["detection"]),
        ("replicate", situation["replicate"]),
        ("strategy", variant["strategy"]),
        ("variant", variant_label(variant["strategy"], options)),
        ("table", _short_table(options.get("table"))),
        ("recursion", options.get("recursion")),
        ("window", options.get("window")),
        ("clearance_weight", weight),
        ("objective", objective_label(options, weight)),
    )
    return Mission(key, config.name, seed, text, labels)


def _fault_steps(
    config: ExperimentConfig,
    identity: dict[str, Any],
    route: Route,
    faults: str,
    domain: Domain[Any, Any],
) -> tuple[int, ...]:
    """When the faults of one situation appear: each of ``faults.at``, or with ``at_random``
    one step drawn from the route's optimal plan (:func:`random_fault_step`)."""
    if not config.faults.at_random:
        return tuple(config.faults.at)
    where = portable({"maze": identity, "route": route.name, "faults": faults, "at": "random"})
    maze = maze_of(canonical_json(identity))
    return (random_fault_step(maze, route, domain, derive_seed(config.seed, where)),)


def _short_table(table: Any) -> str | None:
    if table is None:
        return None
    return table if table in BUNDLED_TABLES else Path(str(table)).stem


# --- executor specs ----------------------------------------------------------------------------


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
    return MissionSpec(
        maze=maze_of(canonical_json(s["maze"])),
        start=parse_pose(s["start"]),
        goal=parse_cell(s["goal"]),
        schedule=FaultSchedule(events=events, detection=s["detection"]),
        strategy=s["strategy"],
        options=StrategyOptions(
            table=options.get("table", "handwritten"),
            recursion=options.get("recursion", RecursionMode.FLAT),
            window=options.get("window", 3),
            before=options.get("before", 0),
            lpg_time_limit_s=options.get("lpg_time_limit_s", 5.0),
            lpg_seed=options.get("lpg_seed", 0),
            rewrite=options.get("rewrite", False),
        ),
        objective=parse_objective(options.get("objective", OPTIMAL)),
        clearance_weight=Fraction(s["clearance_weight"]),
        clearance_radius=s["clearance_radius"],
        seed=mission.seed,
        backend=options.get("backend", "auto"),
        domain=domain,
    )
