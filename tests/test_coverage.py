"""Coverage and optimality reports, checked against searches written independently here."""

from __future__ import annotations

import functools
import heapq
import itertools
import json
import pathlib
from fractions import Fraction
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.coverage import (
    compose,
    coverage_report,
    effect,
    free_space_rows,
    inverse,
    optimal_replacements,
    reachable,
    wall_coverage,
)
from selfrepair.repair.replacement import find_replacement
from selfrepair.robots import four_wheel
from selfrepair.robots.domain import Domain, run_open
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.tables.fileformat import bundled_table
from selfrepair.world.maze import parse_maze

ORIGIN = Pose(0, 0, Heading.N)


# --- the group of rigid moves agrees with the robot model -------------------------------------


@given(
    start=st.builds(Pose, st.integers(-5, 5), st.integers(-5, 5), st.sampled_from(list(Heading))),
    first=st.lists(st.sampled_from(four_wheel.ACTIONS), max_size=5),
    second=st.lists(st.sampled_from(four_wheel.ACTIONS), max_size=5),
)
def test_compose_and_inverse_match_the_model(
    start: Pose, first: list[four_wheel.Action], second: list[four_wheel.Action]
) -> None:
    mid = run_open(FOUR_WHEEL, start, first)
    end = run_open(FOUR_WHEEL, mid, second)
    a, b = effect(start, mid), effect(mid, end)
    assert compose(a, b) == effect(start, end)
    assert compose(a, inverse(a)) == (0, 0, 0) == compose(inverse(a), a)
    # effects do not depend on where the sequence starts
    assert effect(ORIGIN, run_open(FOUR_WHEEL, ORIGIN, first)) == a


# --- reachability, against breadth-first search in a box ---------------------------------------


_STEP_CACHE: dict[tuple[Pose, four_wheel.Action], Pose] = {}


def _step(pose: Pose, action: four_wheel.Action) -> Pose:
    nxt = _STEP_CACHE.get((pose, action))
    if nxt is None:
        nxt = _STEP_CACHE[(pose, action)] = four_wheel.step(pose, action)[0]
    return nxt


def _box_reachable(moves: list[four_wheel.Action], radius: int) -> set[Pose]:
    """Every pose that a non-empty sequence of ``moves`` staying within the box reaches."""
    seen: set[Pose] = set()
    queue = []
    for m in moves:
        nxt = _step(ORIGIN, m)
        if nxt not in seen:
            seen.add(nxt)
            queue.append(nxt)
    while queue:
        pose = queue.pop()
        for m in moves:
            nxt = _step(pose, m)
            if max(abs(nxt.x), abs(nxt.y)) <= radius and nxt not in seen:
                seen.add(nxt)
                queue.append(nxt)
    return seen


def test_reachable_matches_box_search_for_every_motion_subset() -> None:
    fastest = four_wheel.fastest_by_motion()
    motions = list(four_wheel.MOTIONS)
    targets = [four_wheel.step(ORIGIN, fastest[m])[0] for m in motions]
    for size in range(len(motions) + 1):
        for subset in itertools.combinations(motions, size):
            moves = [fastest[m] for m in subset]
            gens = [effect(ORIGIN, four_wheel.step(ORIGIN, a)[0]) for a in moves]
            found = _box_reachable(moves, 4)
            for target in targets:
                assert reachable(gens, effect(ORIGIN, target)) == (target in found), (
                    [m.name for m in subset],
                    target,
                )


def test_reachable_special_cases() -> None:
    fwd, back, turn = (1, 0, 0), (-1, 0, 0), (0, 0, 1)
    assert reachable([fwd], (3, 0, 0))
    assert not reachable([fwd], (-1, 0, 0))
    assert not reachable([fwd], (0, 0, 0))  # no non-empty sequence returns home
    assert reachable([fwd, back], (0, 0, 0))
    assert not reachable([fwd, back], (0, 1, 0))
    assert not reachable([turn], (1, 0, 0))
    assert reachable([turn, fwd], (-7, 3, 2))
    assert reachable([(0, 0, 0)], (0, 0, 0))  # a wait replaces a wait
    assert not reachable([], (0, 0, 0))
    # translations along two axes without inverses: a pointed cone
    assert reachable([(1, 0, 0), (0, 1, 0)], (2, 3, 0))
    assert not reachable([(1, 0, 0), (0, 1, 0)], (2, -1, 0))
    assert reachable([(1, 0, 0), (0, 1, 0), (-1, -1, 0)], (-4, 2, 0))  # cone is the plane


# --- exact optimum, against an independent search over the 81 raw actions ----------------------


@functools.cache
def _independent_optimum(
    faults: frozenset[four_wheel.Fault], objective: str
) -> dict[str, Fraction]:
    """Uniform-cost search over raw actions inside a 7x7 box; costs in exact fractions."""
    moves = [a for a in four_wheel.ACTIONS if four_wheel.available(a, faults)]

    def cost(a: four_wheel.Action) -> Fraction:
        return a.duration if objective == "duration" else Fraction(1)

    best: dict[Pose, Fraction] = {}
    heap = [(cost(a), i, four_wheel.step(ORIGIN, a)[0]) for i, a in enumerate(moves)]
    heapq.heapify(heap)
    counter = itertools.count(len(heap))
    while heap:
        c, _, pose = heapq.heappop(heap)
        if pose in best:
            continue
        best[pose] = c
        for a in moves:
            nxt = _step(pose, a)
            if max(abs(nxt.x), abs(nxt.y)) <= 3 and nxt not in best:
                heapq.heappush(heap, (c + cost(a), next(counter), nxt))
    return {
        a.code: best[four_wheel.step(ORIGIN, a)[0]]
        for a in four_wheel.ACTIONS
        if not four_wheel.available(a, faults)
    }


@pytest.mark.parametrize(
    "faults", list(FOUR_WHEEL.fault_sets[:12]) + list(FOUR_WHEEL.fault_sets[12::13])
)
@pytest.mark.parametrize("objective", ["duration", "length"])
def test_optimum_matches_independent_search(
    faults: frozenset[four_wheel.Fault], objective: str
) -> None:
    found = {a.code: c for a, c in optimal_replacements(FOUR_WHEEL, faults, objective).items()}
    assert found == _independent_optimum(faults, objective)


def test_three_action_optimum() -> None:
    assert optimal_replacements(THREE_ACTION, frozenset({"R"})) == {"R": Fraction(3)}
    assert optimal_replacements(THREE_ACTION, frozenset({"F"})) == {"F": None}
    assert optimal_replacements(THREE_ACTION, frozenset({"L", "R"})) == {"L": None, "R": None}
    assert optimal_replacements(THREE_ACTION, frozenset({"F", "L"})) == {
        "F": None,
        "L": Fraction(3),
    }


# --- free-space coverage, against a direct count ---------------------------------------------


def _independent_rows(
    table_name: str, fault_sets: list[frozenset[four_wheel.Fault]]
) -> list[tuple[int, int, int]]:
    """(disabled, covered, optimal) per fault set: first candidate whose actions are all
    available (flat), its duration against the independent optimum."""
    table = bundled_table(table_name)
    rows = []
    for faults in fault_sets:
        optimum = _independent_optimum(faults, "duration")
        covered = optimal = 0
        for code, best in optimum.items():
            action = four_wheel.parse_action(code)
            usable = [
                c
                for c in table.candidates(action, faults)
                if action not in c and all(four_wheel.available(b, faults) for b in c)
            ]
            if usable:
                covered += 1
                optimal += sum(b.duration for b in usable[0]) == best
        rows.append((len(optimum), covered, optimal))
    return rows


@pytest.mark.parametrize("table_name", ["handwritten", "generated-agnostic", "generated-indexed"])
def test_free_space_rows_match_a_direct_count(table_name: str) -> None:
    fault_sets = list(FOUR_WHEEL.fault_sets[:12]) + list(FOUR_WHEEL.fault_sets[12::11])
    rows = free_space_rows(bundled_table(table_name), fault_sets)
    assert [(r.disabled, r.covered, r.optimal) for r in rows] == _independent_rows(
        table_name, fault_sets
    )
    assert all(r.replaceable == r.disabled for r in rows)  # every four-wheel action is


def test_three_action_handwritten_rows() -> None:
    rows = free_space_rows(bundled_table("three-action"), THREE_ACTION.fault_sets)
    got = {r.faults: (r.disabled, r.replaceable, r.covered, r.optimal) for r in rows}
    assert got == {
        "F": (1, 0, 0, 0),
        "L": (1, 1, 1, 1),
        "R": (1, 1, 1, 1),
        "F,L": (2, 1, 1, 1),
        "F,R": (2, 1, 1, 1),
        "L,R": (2, 0, 0, 0),
    }


def test_generated_indexed_meets_the_targets() -> None:
    totals = coverage_report(bundled_table("generated-indexed")).totals()
    assert totals["fault_sets"] == 78
    assert totals["covered"] == totals["replaceable"] == 3402
    assert totals["optimal"] == 3402
    assert totals["max_excess"] == 0


def test_excess_is_relative_to_the_optimum() -> None:
    table = bundled_table("handwritten")
    faults = frozenset({four_wheel.parse_fault("FL:F")})
    (row,) = free_space_rows(table, [faults])
    optimum = optimal_replacements(FOUR_WHEEL, faults)
    excess = Fraction(0)
    for action, best in optimum.items():
        found = find_replacement(table, action, ORIGIN, faults, lambda c: True)
        if found is not None and best is not None:
            excess += sum((b.duration for b in found.actions), Fraction(0)) / best - 1
    assert row.excess_sum == excess


# --- next to walls, against a pose-by-pose check -----------------------------------------------

SMALL_MAZE = """\
#########
#...#...#
#.#...#.#
#.#.###.#
#...#...#
##.##.###
#.......#
#########
"""


@pytest.mark.parametrize(
    ("domain", "table_name", "picks"),
    [
        (FOUR_WHEEL, "handwritten", (0, 4, 11, 12, 40, 77)),
        (FOUR_WHEEL, "generated-agnostic", (0, 4, 11, 12, 40, 77)),
        (FOUR_WHEEL, "generated-indexed", (0, 4, 11, 12, 40, 77)),
        (THREE_ACTION, "three-action", (0, 1, 2, 3, 4, 5)),
    ],
)
def test_wall_coverage_matches_pose_by_pose(
    domain: Domain[Any, Any], table_name: str, picks: tuple[int, ...]
) -> None:
    maze = parse_maze(SMALL_MAZE, name="small")
    table = bundled_table(table_name)
    fault_sets = [domain.fault_sets[i] for i in picks]
    pairs = uncovered = 0
    for faults in fault_sets:
        replaceable = {a for a, c in optimal_replacements(domain, faults).items() if c is not None}
        for x, y in maze.free_cells():
            for heading in Heading:
                pose = Pose(x, y, heading)
                for action in replaceable:
                    if not maze.all_free(domain.footprint(pose, action)):
                        continue
                    pairs += 1
                    found = find_replacement(
                        table, action, pose, faults, maze.all_free, mode="flat"
                    )
                    uncovered += found is None
    row = wall_coverage(table, maze, fault_sets)
    assert (row.maze, row.pairs, row.uncovered) == ("small", pairs, uncovered)
    assert pairs > 0


# --- CLI -------------------------------------------------------------------------------------


def test_cli_coverage_json(tmp_path: pathlib.Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "report.json"
    code = main(["table", "coverage", "three-action", "--no-walls", "--json-out", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "covered by the table" in printed
    data = json.loads(out.read_text())
    assert data["totals"]["replaceable"] == 4  # L and R under {L}, {R}, {F,L}, {F,R}
    assert data["totals"]["covered"] == 4
    assert len(data["fault_sets"]) == 6
    assert len(data["pairs"]) == 9
    r_pair = next(p for p in data["pairs"] if p["faults"] == "R")
    assert r_pair == {
        "faults": "R",
        "action": "R",
        "optimum": "3",
        "cost": "3",
        "excess": "0",
        "candidate": 0,
        "depth": 0,
        "actions": ["L", "L", "L"],
    }
    f_pair = next(p for p in data["pairs"] if p["faults"] == "F")
    assert f_pair["optimum"] is None and f_pair["cost"] is None


def test_cli_coverage_per_fault_and_maze(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        [
            "table",
            "coverage",
            "generated-indexed",
            "--faults",
            "singles",
            "--maze",
            "narrow-short",
            "--per-fault",
            "--json",
        ]
    )
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert [w["maze"] for w in data["walls"]] == ["narrow-short"]
    assert data["walls"][0]["uncovered"] == 0
    assert data["totals"]["fault_sets"] == 12


def test_cli_coverage_bad_recursion(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["table", "coverage", "handwritten", "--recursion", "deep"]) == 2
    assert "--recursion" in capsys.readouterr().err


def test_generated_agnostic_covers_every_pair_in_free_space() -> None:
    totals = coverage_report(bundled_table("generated-agnostic")).totals()
    hand = coverage_report(bundled_table("handwritten")).totals()
    assert totals["covered"] == totals["replaceable"] == 3402
    assert hand["covered"] < totals["covered"]


def test_unknown_objective_in_a_table_header_is_a_table_error() -> None:
    from dataclasses import replace

    from selfrepair.errors import TableError
    from selfrepair.repair.coverage import coverage_report
    from selfrepair.tables.fileformat import bundled_table

    table = replace(bundled_table("handwritten"), parameters={"objective": "foo"})
    with pytest.raises(TableError, match="objective"):
        coverage_report(table, faults="singles")
