"""The timing policy of experiment missions: one cold run, then warm runs, medians per repair.

:func:`execute_mission` is the mission function :func:`selfrepair.experiment.runner.run_missions`
uses by default. Its cold run empties the caches of the kinds in :data:`COLD_CLEARS`
(:class:`~selfrepair.caching.CacheKind`), never caches named one by one, so a cache added later
is cleared or kept by what it holds.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import replace

from selfrepair.caching import CacheKind, clear_caches
from selfrepair.errors import ProblemError
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.store import Value
from selfrepair.stats import lower_median

__all__ = ["COLD_CLEARS", "DUPLICATE_COLUMNS", "PHYSICS_COLUMNS", "execute_mission"]


DUPLICATE_COLUMNS = frozenset(
    (
        "maze",
        "strategy",
        "table",
        "recursion",
        "window",
        "faults",
        "detection",
        "seed",
        "clearance_weight",
    )
)
"""Executor row columns left out because the mission's own label columns already hold them
(in the experiment's naming; the exact values are in the ``config`` JSON)."""


COLD_CLEARS = frozenset({CacheKind.PLAN, CacheKind.REPAIR, CacheKind.RECORD})
"""The cache kinds a cold run empties: what a plan or a repair derives, which a first repair in
a fresh process would have to compute. Kept: parsed inputs (tables, mazes) and the reference
optimum, filled before any clock starts; the simulator's move tables, which no plan or repair
reads; and what every mission prefills before its clocks start (a table's reach, its candidates'
geometry, the robot's open-plane moves). Clearing those would only slow the sweep down."""


def execute_mission(
    mission: Mission, *, repeats: int = 1, footing: str = "auto"
) -> Mapping[str, Value]:
    """The real mission function: run the executor on ``missions.to_spec(mission)``.

    The row is :meth:`MissionResult.to_row` (columns in docs/replacement.md) without the
    :data:`DUPLICATE_COLUMNS`, plus ``repair_sources`` (JSON list, the source of each repair in
    the order of ``repair_latencies_ns``), ``plan_ticks_before`` (duration of the initial,
    fault-free plan), ``extra_ticks`` (ticks taken minus that, for reached missions),
    ``maze_free_cells``, ``optimum_ticks``/``ticks_over_optimum`` (against the fault-free optimum
    at clearance weight 0 on the same route, the same reference for every variant) and the
    timing columns below.

    Timing, with one cache policy for every strategy (docs/experiments.md): the mission first
    runs **cold**, after every derived-data cache of the process is emptied
    (:func:`~selfrepair.caching.clear_caches` of the kinds in :data:`COLD_CLEARS`; loaded inputs,
    the compiled planner kernels, the simulator's move tables, which no plan or repair reads, and
    the tables' candidate geometry, which every mission computes before its clocks start, stay),
    so its first repair
    pays what a first repair in a fresh process pays: ``cold_first_repair_ns``,
    ``cold_repair_compute_ns``, ``cold_initial_planning_ns``. Then it runs ``repeats`` more times
    **warm** (caches as the runs before left them); every other
    timing column is the median over those warm runs, repair by repair (results are
    deterministic, so the repairs line up). ``timing_repeats`` records ``repeats``. ``footing``
    chooses the mission loop (:attr:`~selfrepair.execution.result.MissionSpec.footing`; the row's
    ``footing`` column says which ran).
    """
    from selfrepair.execution.executor import run_mission
    from selfrepair.execution.metrics import optimum_ticks
    from selfrepair.experiment.missions import to_spec

    if repeats < 1:
        raise ProblemError(f"repeats must be at least 1, got {repeats}")
    spec = to_spec(mission)
    if footing != spec.footing:  # the mission loop (not part of the mission's key)
        spec = replace(spec, footing=footing)
    simulator = mission.settings.get("simulator")
    clear_caches(COLD_CLEARS)
    physics: dict[str, Value] = {}
    if simulator is not None and simulator["name"] == "physics":
        cold, physics = _physics_run(spec, simulator["tracked"])
        warm, repeats = [cold], 1  # MuJoCo's seconds would swamp warm repair timings
    else:
        cold = run_mission(spec)
        warm = [run_mission(spec) for _ in range(repeats)]
        if simulator is not None:
            physics = dict.fromkeys(PHYSICS_COLUMNS)
    result = _median_timings(warm)
    row = {
        k: v
        for k, v in mission_row(result, optimum=optimum_ticks(spec)).items()
        if k not in DUPLICATE_COLUMNS
    }
    plan_ticks = result.initial_plan.duration
    row["repair_sources"] = json.dumps(
        [r.repair.source if r.repair.status == "repaired" else "failed" for r in result.repairs]
    )
    row["plan_ticks_before"] = float(plan_ticks)
    row["extra_ticks"] = float(result.ticks - plan_ticks) if result.reached else None
    row["maze_free_cells"] = int((~result.spec.maze.walls).sum())
    cold_latencies = [r.latency_ns for r in cold.repairs]
    row["first_repair_ns"] = result.repairs[0].latency_ns if result.repairs else None
    row["cold_first_repair_ns"] = cold_latencies[0] if cold_latencies else None
    row["cold_repair_compute_ns"] = sum(cold_latencies)
    row["cold_initial_planning_ns"] = cold.initial_planning_ns
    row["timing_repeats"] = repeats
    row.update(physics)
    return row


PHYSICS_COLUMNS = (
    "wall_contacts",
    "physics_final_error",
    "physics_seconds",
    "physics_max_position_error",
    "physics_max_heading_error",
    "deviations",
)
"""The columns a mission of an experiment with a ``[physics]`` section adds (empty on the
lattice simulator's rows): :class:`~selfrepair.physics.mission.PhysicsOutcome`'s wall contacts
(10 ms control updates touching a wall), final pose error (cells), seconds simulated, largest
position (cells) and heading (degrees) error of a move against the lattice, and deviations."""


def _physics_run(spec: MissionSpec, tracked: bool) -> tuple[MissionResult, dict[str, Value]]:
    """``spec`` run in MuJoCo (:func:`~selfrepair.physics.mission.run_physics_mission`): the
    lattice result and the :data:`PHYSICS_COLUMNS`."""
    from selfrepair.physics.mission import run_physics_mission

    done = run_physics_mission(spec, tracked=tracked)
    o = done.outcome
    values: tuple[Value, ...] = (
        o.wall_contacts,
        round(o.final_error, 4),
        round(o.seconds, 3),
        round(o.max_position_error, 4),
        round(o.max_heading_error, 2),
        o.deviations,
    )
    return done.result, dict(zip(PHYSICS_COLUMNS, values, strict=True))


def _median_timings(runs: Sequence[MissionResult]) -> MissionResult:
    """The first run with each timing replaced by its (lower) median over ``runs``: the initial
    planning time, and each repair's latency position by position."""
    first = runs[0]
    if len(runs) == 1:
        return first
    counts = {len(r.repairs) for r in runs}
    planning = lower_median([r.initial_planning_ns for r in runs])
    if counts != {len(first.repairs)}:  # never expected: missions are deterministic
        return replace(first, initial_planning_ns=planning)
    repairs = tuple(
        record._replace(latency_ns=lower_median([r.repairs[i].latency_ns for r in runs]))
        for i, record in enumerate(first.repairs)
    )
    return replace(first, repairs=repairs, initial_planning_ns=planning)
