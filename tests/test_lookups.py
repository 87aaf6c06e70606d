"""Compiled replacement look-ups give the reference search's answers; whole-plan rewriting
executes the same steps as per-encounter replacement and meets fewer faulty actions."""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from selfrepair.caching import cache_stats, clear_caches
from selfrepair.errors import ProblemError
from selfrepair.execution.context import mission_context
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.result import MissionSpec, MissionStatus
from selfrepair.execution.trace import parse_trace, replay, trace_lines
from selfrepair.geometry import Heading, Pose
from selfrepair.repair import lookup_maps, lookups
from selfrepair.repair import neighbourhood as codes
from selfrepair.repair.lookups import (
    MAX_FAULT_LOOKUPS,
    action_index,
    compiled_replacement,
    fault_lookups,
    lookup_memory,
    neighbourhood,
    occupancy_rows,
)
from selfrepair.repair.replacement import (
    DEFERRING,
    RecursionMode,
    find_replacement,
    flat_replacement,
    table_reach,
)
from selfrepair.repair.strategies import (
    Repair,
    RepairRequest,
    RepairSource,
    RepairStatus,
    ReplacementRepairer,
    StrategyName,
    StrategyOptions,
    get_strategy,
)
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.tables.fileformat import bundled_table
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze

TABLES = ("handwritten", "generated-agnostic", "generated-indexed")
FAULT_SETS = (frozenset(), *FOUR_WHEEL.fault_sets)
PROPERTY = settings(
    max_examples=int(os.environ.get("SELFREPAIR_EXAMPLES", "60")),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)


@st.composite
def situations(draw: st.DrawFn) -> tuple[Maze, Pose, Any, frozenset[Any]]:
    """A random maze (any size, any wall density) and a pose anywhere on it, a wall included,
    an action and a fault set of zero to three faults."""
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    width, height = draw(st.integers(1, 9)), draw(st.integers(1, 9))
    walls = rng.random((height, width)) < draw(st.sampled_from([0.0, 0.2, 0.4, 0.7]))
    pose = Pose(
        draw(st.integers(0, width - 1)),
        draw(st.integers(0, height - 1)),
        draw(st.sampled_from(list(Heading))),
    )
    action = draw(st.sampled_from(four_wheel.ACTIONS))
    faults = draw(
        st.sampled_from(FAULT_SETS)
        | st.sets(st.sampled_from(FOUR_WHEEL.faults), max_size=3).map(frozenset)
    )
    return Maze(walls), pose, action, faults


@st.composite
def mazes_and_faulty_actions(draw: st.DrawFn) -> tuple[Maze, Any, frozenset[Any]]:
    """A random maze, a fault set of zero to three faults, and an action, faulty under those
    faults when there is one (a table's answer matters for those)."""
    maze, _, action, faults = draw(situations())
    faulty = [a for a in four_wheel.ACTIONS if not FOUR_WHEEL.available(a, faults)]
    if faulty and draw(st.integers(0, 4)):
        action = draw(st.sampled_from(faulty))
    return maze, action, faults


@PROPERTY
@given(
    mazes_and_faulty_actions(),
    st.sampled_from(TABLES),
    st.sampled_from(list(RecursionMode)),
    st.integers(0, 3),
    st.sampled_from([0, 4, 12]),
    st.lists(st.sampled_from(four_wheel.ACTIONS), max_size=2).map(frozenset),
)
def test_compiled_look_ups_equal_the_reference_search(
    situation: tuple[Maze, Any, frozenset[Any]],
    name: str,
    mode: RecursionMode,
    max_depth: int,
    enumerate_bits: int,
    guard: frozenset[Any],
) -> None:
    """Every field equal (candidate, expansion, index, depth, examined, end, deferred), at every
    cell of the maze (walls included) and every heading, on the first (built) and the second
    (stored) look-up, with flat neighbourhoods enumerated in full or not at all, in every
    recursion mode (``primitive`` included), with a random guard set (actions an outer
    replacement is still replacing, as the deferring repairer passes) or none."""
    maze, action, faults = situation
    table = bundled_table(name)
    grid = maze.free_grid(table_reach(table))
    old = lookup_maps.ENUMERATE_BITS
    lookup_maps.ENUMERATE_BITS = enumerate_bits
    lookups._LOOKUPS.clear()
    try:
        for _ in range(2):
            for y in range(maze.height):
                for x in range(maze.width):
                    for heading in Heading:
                        pose = Pose(x, y, heading)
                        reference = find_replacement(
                            table,
                            action,
                            pose,
                            faults,
                            maze.all_free,
                            mode=mode,
                            max_depth=max_depth,
                            guard=guard,
                        )
                        got = compiled_replacement(
                            table,
                            action,
                            pose,
                            faults,
                            grid,
                            mode=mode,
                            max_depth=max_depth,
                            guard=guard,
                        )
                        assert got == reference, (pose, got, reference)
                        if mode is RecursionMode.FLAT and not guard:
                            assert flat_replacement(table, action, pose, faults, grid) == reference
    finally:
        lookup_maps.ENUMERATE_BITS = old


@PROPERTY
@given(situations(), st.sampled_from(TABLES), st.sampled_from(list(RecursionMode)), st.data())
def test_the_answer_depends_on_the_neighbourhood_only(
    situation: tuple[Maze, Pose, Any, frozenset[Any]],
    name: str,
    mode: RecursionMode,
    data: st.DataObject,
) -> None:
    """Redraw every cell outside the neighbourhood: the reference search answers the same."""
    maze, pose, action, faults = situation
    table = bundled_table(name)
    cells = neighbourhood(table, action, faults, pose.heading, mode=mode)
    inside = {(pose.x + x, pose.y + y) for x, y in cells}
    rng = np.random.default_rng(data.draw(st.integers(0, 2**31)))
    walls = maze.walls.copy()
    for y in range(maze.height):
        for x in range(maze.width):
            if (x, y) not in inside:
                walls[y, x] = rng.random() < 0.5
    other = Maze(walls)
    before = find_replacement(table, action, pose, faults, maze.all_free, mode=mode)
    after = find_replacement(table, action, pose, faults, other.all_free, mode=mode)
    assert before == after


def test_a_neighbourhood_cell_changes_the_answer() -> None:
    """The map follows a wall that appears inside the neighbourhood (the test can fail)."""
    table = bundled_table()
    action = four_wheel.parse_action("FFFF")
    faults = four_wheel.parse_faults("FL:F")
    open_maze = Maze(np.zeros((7, 7), dtype=bool))
    pose = Pose(3, 3, Heading.N)
    free = compiled_replacement(table, action, pose, faults, open_maze.free_grid(2))
    assert free is not None
    first_cell = sorted(neighbourhood(table, action, faults, Heading.N) - {(0, 0)})
    changed = False
    for x, y in first_cell:
        walls = np.zeros((7, 7), dtype=bool)
        walls[3 + y, 3 + x] = True
        maze = Maze(walls)
        got = compiled_replacement(table, action, pose, faults, maze.free_grid(2))
        assert got == find_replacement(table, action, pose, faults, maze.all_free)
        changed |= got != free
    assert changed


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**31), st.integers(1, 12), st.integers(1, 12), st.integers(0, 4))
def test_occupancy_codes_hold_the_free_cells_around_each_cell(
    seed: int, width: int, height: int, radius: int
) -> None:
    rng = np.random.default_rng(seed)
    maze = Maze(rng.random((height, width)) < 0.4)
    grid = maze.free_grid(1)
    rows = occupancy_rows(grid, radius)
    assert [len(row) for row in rows] == [width] * height
    side = 2 * radius + 1
    for y in range(height):
        for x in range(width):
            code = rows[y][x]
            for dy in range(-radius, radius + 1):
                for dx in range(-radius, radius + 1):
                    bit = (dy + radius) * side + dx + radius
                    assert bool(code >> bit & 1) == grid.is_free(x + dx, y + dy)


@pytest.mark.parametrize("radius", [1, 4])  # 4: 81 bits, codes past one 64-bit word
def test_occupancy_codes_do_not_depend_on_the_band_they_are_made_in(
    monkeypatch: pytest.MonkeyPatch, radius: int
) -> None:
    maze = Maze(np.random.default_rng(5).random((23, 9)) < 0.4)
    grid = maze.free_grid(2)
    whole = codes._rows(grid, radius)
    monkeypatch.setattr(codes, "BAND", 4)  # 23 rows: bands of 4, the last of 3
    assert codes._rows(grid, radius) == whole
    assert len({id(code) for row in whole for code in row}) == len({c for r in whole for c in r})


def test_pattern_budget_bounds_memory_and_keeps_answers(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(lookup_maps, "ENUMERATE_BITS", 0)
    lookups._LOOKUPS.clear()
    table = bundled_table("generated-agnostic")
    rng = np.random.default_rng(3)
    maze = Maze(rng.random((12, 12)) < 0.3)
    grid = maze.free_grid(table_reach(table))
    faults = four_wheel.parse_faults("FL:F")
    for x, y in maze.free_cells():
        for heading in Heading:
            pose = Pose(x, y, heading)
            for action in four_wheel.ACTIONS[:20]:
                got = compiled_replacement(
                    table, action, pose, faults, grid, mode="guarded", max_patterns=5
                )
                assert got == find_replacement(
                    table, action, pose, faults, maze.all_free, mode="guarded"
                )
    (memory,) = [m for m in lookup_memory() if m.table == table.source]
    assert memory.patterns == 5 and memory.bytes > 0
    assert memory.mode is RecursionMode.GUARDED and memory.max_depth == 2


def test_memory_report_and_cache_bound() -> None:
    clear_caches()
    table = bundled_table()
    maze = Maze(np.zeros((5, 5), dtype=bool))
    for faults in ("FL:F", "FR:B"):
        compiled_replacement(
            table,
            four_wheel.parse_action("FFFF"),
            Pose(2, 2, Heading.E),
            four_wheel.parse_faults(faults),
            maze.free_grid(2),
        )
    report = {m.faults: m for m in lookup_memory()}
    assert set(report) >= {"FL:F", "FR:B"}
    assert all(m.actions == 1 and m.patterns >= 1 and m.bytes > 0 for m in report.values())
    stats = {s.name: s for s in cache_stats()}
    assert stats["compiled replacement look-ups"].maxsize == MAX_FAULT_LOOKUPS


def test_equal_copies_of_actions_are_found_by_equality() -> None:
    index = action_index(FOUR_WHEEL)
    copy = four_wheel.Action("SFFF")
    original = four_wheel.parse_action("SFFF")
    assert copy == original and copy is not original
    assert index.of(copy) == index.of(original) == FOUR_WHEEL.actions.index(original)


def test_fault_lookups_check_their_arguments() -> None:
    from selfrepair.errors import ProblemError

    with pytest.raises(ProblemError, match="max_depth"):
        fault_lookups(bundled_table(), (), max_depth=-1, answer=lambda r: r)
    with pytest.raises(ProblemError, match="recursion mode"):
        fault_lookups(bundled_table(), (), mode="deep", answer=lambda r: r)
    with pytest.raises(ProblemError, match="radius"):
        occupancy_rows(Maze(np.zeros((2, 2), dtype=bool)).free_grid(1), -1)


# --- the strategy --------------------------------------------------------------------------------


def _context(maze: Maze, options: StrategyOptions, pose: Pose) -> Any:
    spec = MissionSpec(maze, pose, pose.cell, options=options)
    return mission_context(spec, options.resolved_table())


@PROPERTY
@given(mazes_and_faulty_actions(), st.sampled_from(TABLES), st.sampled_from(list(RecursionMode)))
def test_the_repairer_returns_the_reference_repair(
    situation: tuple[Maze, Any, frozenset[Any]], name: str, mode: RecursionMode
) -> None:
    """At every free cell and heading, built then stored: the repair the reference search gives
    (or the replan fallback when it finds nothing)."""
    maze, action, faults = situation
    free = maze.free_cells()
    if not free:
        return
    options = StrategyOptions(table=name, recursion=mode)
    context = _context(maze, options, Pose(*free[0], Heading.N))
    start = get_strategy(StrategyName.REPLACEMENT)
    repairer = start(context)
    for _ in range(2):
        for cell in free:
            for heading in Heading:
                pose = Pose(*cell, heading)
                if mode in DEFERRING:  # its state belongs to one mission's queue
                    repairer = start(context)
                repair = repairer.repair(RepairRequest(pose, (action,), faults))
                found = find_replacement(
                    context.table, action, pose, faults, maze.all_free, mode=mode
                )
                if found is None:
                    assert repair.source is RepairSource.REPLAN
                    assert repair.attempts == (StrategyName.REPLACEMENT, StrategyName.REPLAN)
                    continue
                assert repair == Repair(
                    RepairStatus.REPAIRED,
                    RepairSource.REPLACEMENT,
                    found.actions,
                    1,
                    candidate_length=len(found.actions),
                    depth=found.depth,
                    examined=found.examined,
                    attempts=(StrategyName.REPLACEMENT,),
                    candidate_index=found.position,
                )


def test_repairer_finds_equal_copies_of_actions() -> None:
    maze = Maze(np.zeros((5, 5), dtype=bool))
    faults = four_wheel.parse_faults("FL:F")
    pose = Pose(2, 2, Heading.E)
    repairer = ReplacementRepairer(_context(maze, StrategyOptions(), pose))
    by_copy = repairer.repair(RepairRequest(pose, (four_wheel.Action("FFFF"),), faults))
    by_self = repairer.repair(RepairRequest(pose, (four_wheel.parse_action("FFFF"),), faults))
    assert by_copy == by_self and by_copy.source is RepairSource.REPLACEMENT


@st.composite
def missions(draw: st.DrawFn) -> MissionSpec:
    """A generated maze, a random route, permanent faults from a random step, detected at once."""
    from selfrepair.world.routes import random_routes

    seed = draw(st.integers(0, 10_000))
    size = draw(st.sampled_from([9, 13, 17]))
    maze = generate_maze(size, size, braid=draw(st.sampled_from([0.0, 0.5])), seed=seed)
    (route,) = random_routes(maze, 1, seed)
    faults = draw(st.sampled_from(FOUR_WHEEL.fault_sets))
    return MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(faults, at=draw(st.sampled_from([0, 3]))),
        options=StrategyOptions(
            table=draw(st.sampled_from(TABLES)),
            recursion=draw(st.sampled_from(REWRITING_MODES)),
        ),
    )


REWRITING_MODES = [m for m in RecursionMode if m not in DEFERRING]
"""Rewriting is refused in deferring modes (their replacements may keep faulty actions)."""


@settings(max_examples=int(os.environ.get("SELFREPAIR_EXAMPLES", "40")), deadline=None)
@given(missions())
def test_rewriting_executes_the_same_steps_with_fewer_repairs(spec: MissionSpec) -> None:
    per_encounter = run_mission(spec)
    rewriting = run_mission(
        MissionSpec(
            spec.maze,
            spec.start,
            spec.goal,
            schedule=spec.schedule,
            options=StrategyOptions(
                table=spec.options.table, recursion=spec.options.recursion, rewrite=True
            ),
        )
    )
    assert rewriting.status == per_encounter.status
    assert [(s.start, s.action) for s in rewriting.steps] == [
        (s.start, s.action) for s in per_encounter.steps
    ]
    assert len(rewriting.repairs) <= len(per_encounter.repairs)
    assert sum(r.repair.replans for r in rewriting.repairs) == sum(
        r.repair.replans for r in per_encounter.repairs
    )
    faults = spec.schedule.all_faults()  # permanent and detected at once: known at any repair
    for record in rewriting.repairs:
        repair = record.repair
        assert all(spec.domain.available(a, faults) for a in repair.actions)
        if repair.source is RepairSource.REPLACEMENT:
            assert (repair.rewritten > 0) == (repair.consumed > 1)


def test_rewrite_substitutes_every_later_occurrence_at_once() -> None:
    """In a corridor, every forward move needs a replacement: one repair does them all."""
    maze = Maze(np.zeros((3, 12), dtype=bool))
    faults = four_wheel.parse_faults("FL:F")
    spec = MissionSpec(
        maze,
        Pose(0, 1, Heading.E),
        (11, 1),
        schedule=FaultSchedule.permanent(faults),
        options=StrategyOptions(recursion="guarded", rewrite=True),
    )
    result = run_mission(spec)
    assert result.status is MissionStatus.REACHED
    (repair,) = [r.repair for r in result.repairs]
    assert repair.rewritten >= 5 and repair.source is RepairSource.REPLACEMENT
    assert all(FOUR_WHEEL.available(s.action, faults) for s in result.steps)
    options = StrategyOptions(recursion="guarded")
    per_encounter = run_mission(
        MissionSpec(maze, spec.start, spec.goal, schedule=spec.schedule, options=options)
    )
    assert len(per_encounter.repairs) == repair.rewritten + 1
    parsed = parse_trace("\n".join(trace_lines(result)))
    assert replay(parsed).ok


@pytest.mark.parametrize("detection", [Detection.NOW, Detection.ON_USE])
def test_rewrite_rechecks_faults_that_become_known_later(detection: Detection) -> None:
    """Faults learned on use or appearing later trigger a new rewrite; the mission still holds."""
    from selfrepair.execution.faults import FaultEvent
    from selfrepair.world.routes import random_routes

    maze = generate_maze(21, 21, braid=0.3, seed=5)
    (route,) = random_routes(maze, 1, 7)
    (first,) = four_wheel.parse_faults("FL:F")
    (second,) = four_wheel.parse_faults("RR:B")
    schedule = FaultSchedule((FaultEvent(first, at=0), FaultEvent(second, at=6)), detection)
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=schedule,
        options=StrategyOptions(recursion="guarded", rewrite=True),
    )
    result = run_mission(spec)
    assert result.status is MissionStatus.REACHED
    assert replay(parse_trace("\n".join(trace_lines(result)))).ok


def test_max_lookup_patterns_caps_what_a_mission_stores() -> None:
    """The ``--max-lookup-patterns`` cap: nothing stored at 0, the same mission either way."""
    maze, start, goal = Maze(np.zeros((9, 9), dtype=bool)), Pose(1, 1, Heading.E), (7, 7)
    schedule = FaultSchedule.permanent(four_wheel.parse_faults("FL:F"), at=0)
    results = []
    for cap in (0, 4096):
        clear_caches()
        options = StrategyOptions(recursion="guarded", max_lookup_patterns=cap)
        spec = MissionSpec(maze, start, goal, schedule=schedule, options=options)
        results.append(run_mission(spec))
        (memory,) = [m for m in lookup_memory() if m.faults == "FL:F"]
        assert (memory.patterns == 0) == (cap == 0)
    assert [s.action for s in results[0].steps] == [s.action for s in results[1].steps]
    with pytest.raises(ProblemError, match="max_lookup_patterns"):
        StrategyOptions(max_lookup_patterns=-1)


def test_run_accepts_max_lookup_patterns(capsys: pytest.CaptureFixture[str]) -> None:
    from selfrepair.cli import main

    route = ["narrow-short", "--start", "1,1,E", "--goal", "13,13", "--faults", "FL:F", "--json"]
    assert main(["run", *route, "--max-lookup-patterns", "0"]) == 0
    capsys.readouterr()
    assert main(["run", *route, "--max-lookup-patterns", "-1"]) == 2
