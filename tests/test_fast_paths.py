"""The speed-ups agree with the plain definitions they replace.

The mission loop runs on integer time units, move tables and a fault clock; the metrics read the
executor's tally; the kernels reuse scratch arrays across searches (generation stamps), grow
their heap and breadth-first queue on demand and share goal distances and poses between queries.
Each is checked here against the reference it stands for: ``Domain.step`` and
``FaultSchedule.active_faults`` step by step, the metrics recomputed from the steps, and the
pure-Python planner.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from fractions import Fraction

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.caching import clear_caches
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import (
    Clock,
    FaultClock,
    FaultEvent,
    FaultSchedule,
    Persistence,
)
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.moves import available_moves, move_table
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS, Outcome, Simulator
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyName, StrategyOptions
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.search import _kernels
from selfrepair.search.grid import grid_astar
from selfrepair.search.lattice import bfs_distances, plan
from selfrepair.search.problem import PlanningProblem, make_pose, pose_table
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze

STRATEGIES = (StrategyName.REPLAN, StrategyName.REPLACEMENT, StrategyName.LOOKAHEAD)
"""The strategies every mission test runs (the baselines have their own tests)."""

PROPERTY = settings(
    max_examples=int(os.environ.get("SELFREPAIR_EXAMPLES", "40")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
DOMAINS = (FOUR_WHEEL, THREE_ACTION)
needs_numba = NUMBA


def _maze(seed: int, width: int = 9, height: int = 7, density: float = 0.2) -> Maze:
    walls = np.random.default_rng(seed).random((height, width)) < density
    walls[1, 1] = False
    return Maze(walls)


@st.composite
def schedules(draw: st.DrawFn, domain: object) -> FaultSchedule:
    """Fault schedules mixing every persistence and both clocks."""
    faults = domain.faults  # type: ignore[attr-defined]
    events = []
    for _ in range(draw(st.integers(0, 3))):
        persistence = draw(st.sampled_from(list(Persistence)))
        events.append(
            FaultEvent(
                draw(st.sampled_from(faults)),
                at=draw(st.integers(0, 6)),
                clock=draw(st.sampled_from(list(Clock))),
                persistence=persistence,
                duration=draw(st.integers(1, 5))
                if persistence is Persistence.TRANSIENT
                else None,
                probability=draw(st.sampled_from([0.0, 0.4, 1.0]))
                if persistence is Persistence.INTERMITTENT
                else None,
            )
        )
    return FaultSchedule(tuple(events), draw(st.sampled_from(["now", "on-use"])))


@PROPERTY
@given(st.data(), st.sampled_from(DOMAINS), st.integers(0, 2**16))
def test_simulator_agrees_with_the_domain_step_by_step(
    data: st.DataObject, domain: object, seed: int
) -> None:
    maze = _maze(seed)
    schedule = data.draw(schedules(domain))
    start = Pose(1, 1, data.draw(st.sampled_from(list(Heading))))
    sim = Simulator(domain, maze, start, schedule, seed)  # type: ignore[arg-type]
    pose, step, ticks = start, 0, Fraction(0)
    for action in data.draw(st.lists(st.sampled_from(domain.actions), max_size=25)):  # type: ignore[attr-defined]
        true = schedule.active_faults(step, ticks, seed)
        assert sim.true_faults() == true and sim.ticks == ticks and sim.steps == step
        outcome = sim.execute(action)
        if not domain.available(action, true):  # type: ignore[attr-defined]
            assert outcome.status is Outcome.FAILED_ATTEMPT
            assert outcome.blocking == domain.blocking(action, true)  # type: ignore[attr-defined]
            assert outcome.duration == FAILED_ATTEMPT_TICKS
            step, ticks = step + 1, ticks + FAILED_ATTEMPT_TICKS
            continue
        end, swept, duration = domain.step(pose, action)  # type: ignore[attr-defined]
        if not maze.all_free(swept):
            assert outcome.status is Outcome.COLLISION and sim.pose == pose
            continue
        assert outcome.status is Outcome.MOVED
        assert (outcome.end, outcome.swept, outcome.duration) == (end, swept, duration)
        pose, step, ticks = end, step + 1, ticks + duration
        assert sim.pose == pose


@PROPERTY
@given(st.data(), st.integers(0, 2**16))
def test_fault_clock_equals_the_schedule(data: st.DataObject, seed: int) -> None:
    schedule = data.draw(schedules(FOUR_WHEEL))
    clock = FaultClock(schedule, seed, 3)
    units = 0
    for step in range(40):
        expected = schedule.active_faults(step, Fraction(units, 3), seed)
        assert clock.at(step, units) == expected
        units += data.draw(st.sampled_from([1, 2, 3, 4, 6, 12]))


def test_time_units_and_move_tables() -> None:
    assert FOUR_WHEEL.time_unit == 3  # durations are multiples of 1/3 tick
    table = move_table(FOUR_WHEEL, 20)
    for action in FOUR_WHEEL.actions:
        for heading in Heading:
            move = table.moves[action][heading]
            end, cells, duration = FOUR_WHEEL.step(Pose(5, 5, heading), action)
            assert (5 + move.dx, 5 + move.dy, move.heading) == (end.x, end.y, end.heading)
            assert move.cells == tuple((y - 5) * 20 + (x - 5) for x, y in cells)
            assert Fraction(move.units, table.unit) == duration == move.duration
    faults = frozenset(FOUR_WHEEL.fault_sets[14])
    available = available_moves(table, faults)
    assert set(available) == {a for a in FOUR_WHEEL.actions if FOUR_WHEEL.available(a, faults)}


routes_and_faults = st.tuples(
    st.integers(0, 2**16),
    st.sampled_from((frozenset(), *FOUR_WHEEL.fault_sets[::7])),
    st.sampled_from(sorted(STRATEGIES)),
    st.sampled_from(["now", "on-use"]),
    st.sampled_from([Fraction(0), Fraction(1), Fraction(1, 2)]),
)


@PROPERTY
@given(routes_and_faults)
def test_row_from_the_tally_equals_the_row_from_the_steps(case: tuple) -> None:
    seed, faults, strategy, detection, weight = case
    maze = generate_maze(13, 11, braid=0.3, seed=seed)
    free = maze.free_cells()
    spec = MissionSpec(
        maze,
        Pose(*free[0], Heading.E),
        free[-1],
        schedule=FaultSchedule.permanent(faults, detection=detection),
        strategy=strategy,
        options=StrategyOptions(recursion="guarded", window=2),
        clearance_weight=weight,
    )
    result = run_mission(spec)
    assert result.tally is not None
    fast, slow = mission_row(result), mission_row(dataclasses.replace(result, tally=None))
    assert fast == slow


@needs_numba
@PROPERTY
@given(st.integers(0, 2**16), st.sampled_from([Fraction(0), Fraction(2)]))
def test_kernels_agree_when_heap_queue_and_stamps_are_pushed_to_their_limits(
    seed: int, weight: Fraction
) -> None:
    maze = generate_maze(23, 19, braid=0.5, seed=seed)
    free = maze.free_cells()
    problem = PlanningProblem(maze, Pose(*free[0], Heading.N), free[-1], clearance_weight=weight)
    reference = plan(problem, backend="python")
    saved = _kernels._FIRST_HEAP, _kernels._FIRST_QUEUE, _kernels._LATTICE_MARK_MAX
    try:
        # tiny first heap and queue (they must grow), and stamps that run out every 2 searches
        _kernels._FIRST_HEAP, _kernels._FIRST_QUEUE, _kernels._LATTICE_MARK_MAX = 16, 4, 5
        _kernels._local.__dict__.clear()
        clear_caches()
        for _ in range(4):
            compiled = plan(problem, backend="numba")
            assert (compiled.actions, compiled.poses, compiled.cost, compiled.duration) == (
                reference.actions,
                reference.poses,
                reference.cost,
                reference.duration,
            )
        assert (bfs_distances(maze, free[-1], backend="numba") == bfs_distances(
            maze, free[-1], backend="python"
        )).all()
        path = grid_astar(maze, free[0], free[-1], backend="numba")
        assert path.path == grid_astar(maze, free[0], free[-1], backend="python").path
    finally:
        _kernels._FIRST_HEAP, _kernels._FIRST_QUEUE, _kernels._LATTICE_MARK_MAX = saved
        _kernels._local.__dict__.clear()
        clear_caches()


def test_goal_distances_are_shared_read_only_and_give_the_same_plans() -> None:
    clear_caches()
    maze = generate_maze(31, 21, braid=0.2, seed=3)
    free = maze.free_cells()
    problem = PlanningProblem(maze, Pose(*free[0], Heading.E), free[-1])
    cold = plan(problem, backend="python")
    warm = plan(problem, backend="python")
    other_start = plan(dataclasses.replace(problem, start=Pose(*free[5], Heading.S)))
    assert (cold.actions, cold.cost) == (warm.actions, warm.cost)
    assert other_start.status is cold.status
    assert bfs_distances(maze, free[-1]).flags.writeable  # the public copy stays writable


def test_make_pose_and_the_pose_table() -> None:
    made = make_pose(3, 4, Heading.W)
    assert made == Pose(3, 4, Heading.W) and hash(made) == hash(Pose(3, 4, Heading.W))
    assert str(made) == "3,4,W" and type(made) is Pose
    maze = Maze(np.zeros((5, 6), dtype=bool))
    table = pose_table(maze)
    assert table is not None and len(table) == 4 * 7 * 8
    big = Maze(np.zeros((300, 300), dtype=bool))
    assert pose_table(big) is None  # too large: poses are made per step instead


@needs_numba
def test_the_kernels_give_poses_from_the_shared_pose_table() -> None:
    problem = PlanningProblem(Maze(np.zeros((5, 6), dtype=bool)), Pose(0, 0, Heading.E), (5, 4))
    first, again = plan(problem, backend="numba"), plan(problem, backend="numba")
    assert first.poses and all(a is b for a, b in zip(first.poses, again.poses, strict=True))


@needs_numba
def test_kernel_load_is_reported_apart_from_the_search() -> None:
    code = (
        "from selfrepair.search.lattice import plan, PlanningProblem\n"
        "from selfrepair.search.grid import grid_astar\n"
        "from selfrepair.world.bundled import load_bundled, bundled_routes\n"
        "maze = load_bundled('narrow-short'); route = bundled_routes('narrow-short')[0]\n"
        "p = PlanningProblem(maze, route.start, route.goal)\n"
        "a, b = plan(p, backend='numba'), plan(p, backend='numba')\n"
        "g = grid_astar(maze, route.start.cell, route.goal, backend='numba')\n"
        "print(a.kernel_load_ns, b.kernel_load_ns, g.kernel_load_ns, a.wall_time_ns)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    first, second, grid, wall = (int(v) for v in out.stdout.split())
    assert first > 0 and second == 0  # the first call of a process loads the kernels
    assert grid > 0  # the grid kernel is loaded on its own first call
    assert 0 < wall < first  # the search's own time, without the load


def test_cold_runs_keep_the_simulators_move_tables_and_empty_the_planners_caches() -> None:
    from selfrepair.cli.experiments import resolve_experiment
    from selfrepair.experiment.config import load_config
    from selfrepair.experiment.missions import expand
    from selfrepair.experiment.timing import execute_mission

    mission = expand(load_config(resolve_experiment("paper")))[0]
    kept = move_table(FOUR_WHEEL, 40)
    maze = Maze(np.zeros((5, 6), dtype=bool))
    poses = pose_table(maze)
    execute_mission(mission)
    assert move_table(FOUR_WHEEL, 40) is kept  # simulation bookkeeping survives the cold run
    assert pose_table(maze) is not poses  # a planner cache is emptied for it


def test_cold_runs_keep_what_every_mission_prefills_before_timing() -> None:
    from selfrepair.caching import CacheKind, cache_stats
    from selfrepair.cli.experiments import resolve_experiment
    from selfrepair.experiment.config import load_config
    from selfrepair.experiment.missions import expand
    from selfrepair.experiment.timing import execute_mission

    prefilled = sorted(s.name for s in cache_stats() if s.kind is CacheKind.PREFILLED)

    def stats() -> dict[str, tuple[int, int]]:
        return {s.name: (s.size, s.hits) for s in cache_stats() if s.name in prefilled}

    missions = expand(load_config(resolve_experiment("paper")))
    mission = next(m for m in missions if dict(m.labels).get("strategy") == "replacement")
    execute_mission(mission)
    # the prefilled caches a replacement mission fills (diagnosis and detour caches stay empty)
    before = {name: value for name, value in stats().items() if value[0]}
    assert set(before) == {"table reach", "candidate geometry", "open-plane moves"}
    execute_mission(mission)  # its cold run empties the other caches, not these
    after = {name: value for name, value in stats().items() if name in before}
    # kept: the same entries (the geometry is only computed with the reach, so an emptied
    # geometry cache would stay empty), and the reach's hit count goes on (emptying resets it)
    assert {name: size for name, (size, _) in after.items()} == {
        name: size for name, (size, _) in before.items()
    }
    for kept in ("table reach", "open-plane moves"):  # looked up by every mission
        assert after[kept][1] > before[kept][1]
