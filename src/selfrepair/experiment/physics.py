"""The paper's missions on two footings: the lattice simulator and MuJoCo (``selfrepair physics
experiment``).

Each mission of the reference experiment's design (bundled mazes, their four routes, the 12 paper
fault sets, permanent from the first step and detected at once) runs per strategy twice: on the
lattice (:func:`~selfrepair.execution.executor.run_mission`) and in physics
(:func:`~selfrepair.physics.mission.run_physics_mission`, tracked unless asked otherwise). A row
holds both outcomes; :func:`footing_summary` gives, per strategy, how many of the missions the
lattice completes physics completes too, and how many of those without touching a wall.

``robot="four-wheel-confirmed"`` plans and repairs with only the actions physics confirms
(:func:`selfrepair.physics.identified.identified_domain` with ``confirmed_only``) and a table
generated for them; the lattice footing then simulates that robot too.
``robot="four-wheel-in-sequence"`` does the same with only the actions that also hold in sequence
(``in_sequence_only``).

The default is small enough for a 2-core machine (two mazes, 96 missions per strategy); the four
bundled mazes are one option away.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import InputError
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.faultsets import PAPER_FAULT_SETS
from selfrepair.experiment.keys import canonical_json
from selfrepair.physics.identified import CONFIRMED_NAME, IN_SEQUENCE_NAME, load_identified
from selfrepair.physics.mission import run_physics_mission
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.tables.fileformat import default_table
from selfrepair.tables.model import SomeTable
from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names

__all__ = [
    "DEFAULT_MAZES",
    "ROBOTS",
    "STRATEGIES",
    "FootingRow",
    "footing_summary",
    "physics_experiment",
    "physics_mission_spec",
    "stored_footing_rows",
]

DEFAULT_MAZES = ("narrow-short", "wide-short")
"""The mazes of the default run (the two short ones: a few minutes on two cores)."""

STRATEGIES: dict[str, tuple[str, StrategyOptions]] = {
    "replan": ("replan", StrategyOptions()),
    "replacement": ("replacement", StrategyOptions(recursion=RecursionMode.GUARDED)),
    "rewriting": (
        "replacement",
        StrategyOptions(recursion=RecursionMode.GUARDED, rewrite=True),
    ),
    "lookahead": ("lookahead", StrategyOptions(recursion=RecursionMode.GUARDED)),
}
"""The strategies compared, by label: the strategy and its options (the hand-written table,
guarded recursion; ``rewriting`` substitutes every faulty action of the plan at once)."""


@dataclass(frozen=True, slots=True)
class FootingRow:
    """One mission on both footings."""

    maze: str
    route: str
    faults: str
    strategy: str
    lattice_reached: bool
    physics_reached: bool
    wall_contacts: int
    final_error: float
    seconds: float
    repairs: int
    deviations: int


ROBOTS = ("four-wheel", CONFIRMED_NAME, IN_SEQUENCE_NAME)
"""The robot models a run may plan with: the lattice's four-wheel robot (hand-written table), the
one that commands only the 65 actions physics confirms from rest, or the one that commands only
the 40 that also hold in sequence (each of the identified ones with its generated fault-agnostic
table, made once per process)."""

_ROBOTS: BoundedCache[str, tuple[SomeDomain, SomeTable | None]] = BoundedCache(
    "physics experiment robot models", 3, kind=CacheKind.INPUT
)


def _make_robot(name: str) -> tuple[SomeDomain, SomeTable | None]:
    if name in (CONFIRMED_NAME, IN_SEQUENCE_NAME):
        domain = load_identified(
            name=name,
            confirmed_only=name == CONFIRMED_NAME,
            in_sequence_only=name == IN_SEQUENCE_NAME,
        )
        return domain, default_table(domain)  # generated: the identified robot ships none
    return FOUR_WHEEL, None


def _robot(name: str) -> tuple[SomeDomain, SomeTable | None]:
    """The domain and table of robot model ``name`` (made once per process and kept)."""
    return _ROBOTS.get(name, lambda: _make_robot(name))


def physics_mission_spec(
    maze: str, route: int, faults: str, label: str, robot: str
) -> MissionSpec:
    """The mission of ``experiment physics`` on bundled ``maze``'s route ``route`` under the
    permanent ``faults`` (the domain's text), with strategy ``label`` (a key of
    :data:`STRATEGIES`) and robot model ``robot`` (a key of :data:`ROBOTS`): the one place that
    builds it, for the experiment and for ``benchmarks/physics_contacts.py``."""
    strategy, options = STRATEGIES[label]
    domain, table = _robot(robot)
    if table is not None:
        options = replace(options, table=table)
    r = bundled_routes(maze)[route]
    schedule = FaultSchedule.permanent(domain.parse_faults(faults))
    return MissionSpec(
        load_bundled(maze), r.start, r.goal, schedule=schedule, strategy=strategy,
        options=options, domain=domain,
    )  # fmt: skip


def _run(job: tuple[str, int, str, str, bool, str]) -> FootingRow:
    maze, route, faults, label, tracked, robot = job
    spec = physics_mission_spec(maze, route, faults, label, robot)
    lattice = run_mission(spec)
    done = run_physics_mission(spec, tracked=tracked)
    o = done.outcome
    return FootingRow(
        maze, bundled_routes(maze)[route].name, faults, label, lattice.reached, o.reached,
        o.wall_contacts, o.final_error, o.seconds, o.repairs, o.deviations,
    )  # fmt: skip


def physics_experiment(
    mazes: Sequence[str] = DEFAULT_MAZES,
    strategies: Sequence[str] = tuple(STRATEGIES),
    fault_sets: Iterable[str] = PAPER_FAULT_SETS,
    *,
    tracked: bool = True,
    workers: int = 1,
    robot: str = "four-wheel",
) -> list[FootingRow]:
    """Every mission of the design on both footings, maze by maze, route by route, fault set by
    fault set, strategy by strategy (in that order, also with ``workers`` processes), planned
    and repaired with robot model ``robot`` (:data:`ROBOTS`)."""
    if robot not in ROBOTS:
        raise InputError(
            f"expected a robot model of {', '.join(ROBOTS)}, got {robot!r}", source="<robot>"
        )
    for name in mazes:
        if name not in maze_names():
            raise InputError(
                f"expected a bundled maze ({', '.join(maze_names())}), got {name!r}",
                source="<mazes>",
            )
    for label in strategies:
        if label not in STRATEGIES:
            raise InputError(
                f"expected a strategy of {', '.join(STRATEGIES)}, got {label!r}",
                source="<strategies>",
            )
    sets = tuple(fault_sets)
    jobs = [
        (maze, route, faults, label, tracked, robot)
        for maze in mazes
        for route in range(len(bundled_routes(maze)))
        for faults in sets
        for label in strategies
    ]
    if workers <= 1:
        return [_run(job) for job in jobs]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(_run, jobs, chunksize=4))


def stored_footing_rows(rows: Iterable[Mapping[str, Any]]) -> list[FootingRow]:
    """The missions of an experiment with a ``[physics]`` section (stored rows, each with a
    ``simulator`` column) paired across simulators: one :class:`FootingRow` per mission that ran
    on both, its ``strategy`` the row's ``variant``, in the order of the physics rows. A mission's
    pair is the row whose configuration is the same but for the simulator."""
    lattice: dict[str, Mapping[str, Any]] = {}
    physics: list[tuple[str, Mapping[str, Any]]] = []
    for row in rows:
        settings = json.loads(str(row["config"]))
        simulator = settings.pop("simulator", None)
        if simulator is None:
            continue
        pair = canonical_json(settings)
        if simulator["name"] == "physics":
            physics.append((pair, row))
        else:
            lattice[pair] = row
    out = []
    for pair, row in physics:
        other = lattice.get(pair)
        if other is None:
            continue
        out.append(
            FootingRow(
                maze=str(row["maze"]),
                route=str(row["route"]),
                faults=str(row["faults"]),
                strategy=str(row["variant"]),
                lattice_reached=bool(other["reached"]),
                physics_reached=bool(row["reached"]),
                wall_contacts=int(row["wall_contacts"]),
                final_error=float(row["physics_final_error"]),
                seconds=float(row["physics_seconds"]),
                repairs=int(row["faulty_encounters"]),
                deviations=int(row["deviations"]),
            )
        )
    return out


def footing_summary(rows: Iterable[FootingRow]) -> dict[str, dict[str, Any]]:
    """Per strategy (in the order met): missions, how many the lattice and physics complete, and
    of the lattice's, the share physics completes and the share it completes with no wall
    contact."""
    out: dict[str, dict[str, Any]] = {}
    for row in rows:
        s = out.setdefault(row.strategy, {
            "missions": 0, "lattice_reached": 0, "physics_reached": 0,
            "both_reached": 0, "both_reached_no_contact": 0, "missions_with_contact": 0,
        })  # fmt: skip
        s["missions"] += 1
        s["lattice_reached"] += row.lattice_reached
        s["physics_reached"] += row.physics_reached
        s["missions_with_contact"] += row.wall_contacts > 0
        if row.lattice_reached and row.physics_reached:
            s["both_reached"] += 1
            s["both_reached_no_contact"] += row.wall_contacts == 0
    for s in out.values():
        n = s["lattice_reached"]
        s["physics_share_of_lattice"] = round(s["both_reached"] / n, 4) if n else None
        s["no_contact_share_of_lattice"] = round(s["both_reached_no_contact"] / n, 4) if n else None
    return out
