"""Honest measurement: the mission-level metrics computed by hand on a small mission, the timing
runs, the statistics, the fault-set rule, the primitive/complex recursion mode, lookahead windows
before the faulty action, and the scale experiment's crossover."""

from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binomtest

from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.metrics import mission_row, motion_distance, optimum_ticks
from selfrepair.execution.result import MissionSpec
from selfrepair.experiment.faultsets import PAPER_FAULT_SETS, biting_fault_sets
from selfrepair.experiment.keys import Mission, canonical_json
from selfrepair.experiment.scale import crossover
from selfrepair.experiment.stats import sign_test
from selfrepair.experiment.timing import execute_mission
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.replacement import (
    RecursionMode,
    complex_actions,
    find_replacement,
    is_valid_replacement,
)
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.stats import bootstrap_interval
from selfrepair.tables.fileformat import bundled_table
from selfrepair.tables.model import ReplacementTable, TableEntry
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import parse_maze

A = FOUR_WHEEL.parse_action
F = FOUR_WHEEL.parse_faults
CORRIDOR = parse_maze("#######\n#.....#\n#######", name="corridor")
START = Pose(1, 1, Heading.E)


def _corridor(strategy: str, faults: str = "FL:F") -> MissionSpec:
    return MissionSpec(
        CORRIDOR,
        START,
        (5, 1),
        schedule=FaultSchedule.permanent(F(faults)),
        strategy=strategy,
        options=StrategyOptions(table="handwritten", recursion="flat"),
    )


# --- the mission-level metrics, by hand ---------------------------------------------------------


def test_new_metrics_by_hand_on_a_corridor() -> None:
    """Four cells east: the plan is FFFF x4 (1 tick each). With FL:F the hand-written table's
    first healthy forward candidate is SSFF (2 ticks, the same motion), so the robot drives
    SSFF x4 and never replans; the replanning robot replans once."""
    result = run_mission(_corridor("replacement"))
    assert [FOUR_WHEEL.format_action(s.action) for s in result.executed] == ["SSFF"] * 4
    optimum = optimum_ticks(result.spec)
    assert optimum == 4  # 4 x FFFF
    row = mission_row(result, optimum=optimum)
    assert row["completed_without_replan"] == 1
    assert row["ticks_over_optimum"] == 8 - 4
    assert row["optimum_ticks"] == 4.0
    assert row["plan_distance"] == 8  # 4 FFFF removed, 4 SSFF added
    assert row["plan_distance_motion"] == 0  # all of them "forward" from the same poses
    assert row["repair_compute_ns"] == sum(r.latency_ns for r in result.repairs)
    assert row["repair_compute_ns"] == row["compute_ns"] - row["initial_planning_ns"]

    replanned = run_mission(_corridor("replan"))
    row = mission_row(replanned, optimum=optimum_ticks(replanned.spec))
    assert row["completed_without_replan"] == 0 and row["replans"] == 1
    assert row["ticks_over_optimum"] == float(replanned.ticks - 4)
    assert mission_row(replanned)["ticks_over_optimum"] is None  # no reference given


def test_optimum_is_one_reference_for_every_weight() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    specs = [
        MissionSpec(maze, route.start, route.goal, clearance_weight=Fraction(w)) for w in (0, 2)
    ]
    w0 = plan(PlanningProblem(maze, route.start, route.goal))
    assert optimum_ticks(specs[0]) == optimum_ticks(specs[1]) == w0.duration


def test_motion_distance_counts_motions_not_wheel_codes() -> None:
    pose = Pose(1, 1, Heading.E)
    first = [(pose, A("FFFF")), (pose, A("FBFB"))]
    assert (
        motion_distance(
            FOUR_WHEEL.motion_class, first, [(pose, A("SSFF")), (pose, A("FBFB"))]
        ).total
        == 0
    )
    assert motion_distance(FOUR_WHEEL.motion_class, first, [(pose, A("BFBF"))]).total == 3


# --- timing: cold run, warm repeats -------------------------------------------------------------


def test_execute_mission_reports_cold_and_warm_timings() -> None:
    settings = {
        "schema": 1,
        "maze": {"bundled": "narrow-short"},
        "route": "r1",
        "start": str(bundled_routes("narrow-short")[0].start),
        "goal": "{},{}".format(*bundled_routes("narrow-short")[0].goal),
        "faults": "FL:F",
        "fault_at": 0,
        "fault_clock": "step",
        "persistence": "permanent",
        "fault_duration": None,
        "fault_probability": None,
        "detection": "now",
        "replicate": 0,
        "strategy": "replacement",
        "options": {"table": "handwritten", "recursion": "flat"},
        "clearance_weight": "0",
        "clearance_radius": 2,
        "seed": 1,
    }
    mission = Mission("k", "t", 1, canonical_json(settings), ())
    row = execute_mission(mission, repeats=3)
    assert row["timing_repeats"] == 3
    latencies = json.loads(str(row["repair_latencies_ns"]))
    assert row["first_repair_ns"] == latencies[0]
    assert row["repair_compute_ns"] == sum(latencies)
    assert isinstance(row["cold_first_repair_ns"], int) and row["cold_first_repair_ns"] > 0
    assert isinstance(row["cold_repair_compute_ns"], int)
    assert row["optimum_ticks"] == float(row["plan_ticks_before"])  # w=0: the initial plan
    # timings aside, the row is the same whatever the repeats
    again = execute_mission(mission, repeats=1)
    same = {k for k in row if not k.endswith("_ns") and k not in ("timing_repeats",)}
    assert {k: row[k] for k in same} == {k: again[k] for k in same}


# --- statistics ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("better", "worse"), [(28, 6), (5, 5), (84, 0), (3, 10), (1, 0)])
def test_sign_test_is_the_exact_binomial_tail(better: int, worse: int) -> None:
    expected = binomtest(better, better + worse, 0.5, alternative="greater").pvalue
    assert sign_test(better, worse) == pytest.approx(expected, rel=1e-12)
    assert sign_test(0, 0) == 1.0


def test_bootstrap_interval_is_reproducible_and_covers_the_estimate() -> None:
    values = list(np.random.default_rng(3).lognormal(size=200))
    first = bootstrap_interval(values)
    assert first is not None and first == bootstrap_interval(values)
    assert first.low <= first.estimate <= first.high and first.n == 200
    assert first.high - first.low < 0.5
    wide = bootstrap_interval(values[:10])
    assert wide is not None and wide.high - wide.low > first.high - first.low
    assert bootstrap_interval([]) is None
    one = bootstrap_interval([4.0, 4.0])
    assert one is not None and (one.low, one.estimate, one.high) == (4.0, 4.0, 4.0)


# --- fault sets that bite -----------------------------------------------------------------------


def test_paper_fault_sets_follow_the_documented_rule() -> None:
    plans = []
    for name in ("narrow-short", "wide-short", "narrow-long", "wide-long"):
        maze = load_bundled(name)
        for route in bundled_routes(name):
            plans.append(plan(PlanningProblem(maze, route.start, route.goal)).actions)
    assert len(plans) == 16
    assert biting_fault_sets(FOUR_WHEEL, plans, 12) == PAPER_FAULT_SETS
    for faults in PAPER_FAULT_SETS:  # each set disables an action of every initial plan
        assert all(any(not FOUR_WHEEL.available(a, F(faults)) for a in p) for p in plans)


# --- the primitive/complex recursion mode -------------------------------------------------------


def _table(*entries: tuple[str, list[str]]) -> ReplacementTable:
    return ReplacementTable(
        FOUR_WHEEL,
        "fault-agnostic",
        "hand",
        tuple(
            TableEntry(A(action), tuple(tuple(A(a) for a in c.split()) for c in candidates))
            for action, candidates in entries
        ),
    )


OPEN = parse_maze("\n".join(["." * 9] * 9)).free_grid(4).all_free
ORIGIN = Pose(4, 4, Heading.N)


def test_complex_actions_use_more_than_two_different_actions() -> None:
    table = _table(
        ("FFFF", ["SSFF", "FBFB FBFB BBBB FBFB FBFB"]),  # at most 2 different: primitive
        ("SFFF", ["FFSF", "BFBF FFFF FBFB FFFF BFBF"]),  # 3 different: complex
    )
    found = complex_actions(table, frozenset())
    assert A("SFFF") in found and A("FFFF") not in found
    assert A("BBBB") in found  # no candidate at all: not replaceable, so complex
    hand = complex_actions(bundled_table(), frozenset())
    assert {FOUR_WHEEL.format_action(a) for a in hand} == {
        "SFFF",
        "FFSF",
        "FSFF",
        "FFFS",
        "SBBB",
        "BBSB",
        "BSBB",
        "BBBS",
    }


# Two arcs (forward-left) that can each be replaced by a turn right, a turn left and the other
# arc, or by forward, turn left, forward. With FR:F both arcs are faulty; the turns FBFB and BSBS
# and the slow forward SSFF are healthy.
ARCS = _table(
    ("FFSF", ["FBFB BSBS SFFF", "SSFF BSBS SSFF"]),
    ("SFFF", ["FBFB BSBS FFSF", "SSFF BSBS SSFF"]),
)
NO_FR_F = F("FR:F")


def _names(actions: tuple[object, ...]) -> list[str]:
    return [FOUR_WHEEL.format_action(a) for a in actions]


def test_primitive_mode_defers_a_faulty_complex_action_unless_it_comes_first() -> None:
    hit = find_replacement(ARCS, A("FFSF"), ORIGIN, NO_FR_F, OPEN, mode="primitive")
    assert hit is not None
    assert _names(hit.actions) == ["FBFB", "BSBS", "SFFF"]
    assert hit.deferred == (2,)  # SFFF is complex, faulty and not first: left for later
    assert is_valid_replacement(
        FOUR_WHEEL, A("FFSF"), ORIGIN, hit.actions, NO_FR_F, OPEN, deferred=hit.deferred
    )
    assert not is_valid_replacement(FOUR_WHEEL, A("FFSF"), ORIGIN, hit.actions, NO_FR_F, OPEN)
    # guarded replaces SFFF at once (its first candidate uses FFSF, being replaced: skipped)
    guarded = find_replacement(ARCS, A("FFSF"), ORIGIN, NO_FR_F, OPEN, mode="guarded")
    assert guarded is not None and guarded.depth == 1 and guarded.deferred == ()
    assert _names(guarded.actions) == ["FBFB", "BSBS", "SSFF", "BSBS", "SSFF"]
    flat = find_replacement(ARCS, A("FFSF"), ORIGIN, NO_FR_F, OPEN, mode="flat")
    assert flat is not None and flat.position == 1
    # a complex action that comes first is checked: faulty, so the candidate is invalid
    first = _table(("FFSF", ["SFFF"]), ("SFFF", ["FBFB BSBS FFSF"]))
    assert find_replacement(first, A("FFSF"), ORIGIN, NO_FR_F, OPEN, mode="primitive") is None
    # an outer guard forbids reusing an action still being replaced
    guard = find_replacement(
        ARCS, A("FFSF"), ORIGIN, NO_FR_F, OPEN, mode="primitive", guard={A("SFFF")}
    )
    assert guard is not None and guard.position == 1


@pytest.mark.parametrize("table", ["handwritten", "generated-agnostic", "generated-indexed"])
def test_primitive_missions_reach_the_goal_and_never_execute_a_known_fault(table: str) -> None:
    maze = load_bundled("wide-short")
    for route in bundled_routes("wide-short"):
        for faults in PAPER_FAULT_SETS[:6]:
            spec = MissionSpec(
                maze,
                route.start,
                route.goal,
                schedule=FaultSchedule.permanent(F(faults)),
                strategy="replacement",
                options=StrategyOptions(table=table, recursion=RecursionMode.PRIMITIVE),
            )
            result = run_mission(spec)
            assert result.reached
            assert all(FOUR_WHEEL.available(s.action, F(faults)) for s in result.executed)


def test_deferred_action_is_replaced_when_reached_with_the_guard_carried_over() -> None:
    """The plan is one arc, FFSF. Its replacement turns right, turns left and keeps SFFF for
    later; when the robot reaches SFFF, FFSF is still being replaced, so SFFF's first candidate
    (which uses FFSF) is skipped and the second is taken. Without the guard carried over, the
    robot would turn right and left for ever."""
    maze = parse_maze("\n".join(["." * 15] * 15))
    start = Pose(7, 7, Heading.N)
    end = FOUR_WHEEL.apply(start, A("FFSF"))
    spec = MissionSpec(
        maze,
        start,
        end.cell,
        goal_heading=end.heading,
        schedule=FaultSchedule.permanent(NO_FR_F),
        strategy="replacement",
        options=StrategyOptions(table=ARCS, recursion=RecursionMode.PRIMITIVE),
    )
    result = run_mission(spec)
    assert _names(result.initial_plan.actions) == ["FFSF"]
    assert result.reached
    assert [FOUR_WHEEL.format_action(r.action) for r in result.repairs] == ["FFSF", "SFFF"]
    assert _names(tuple(s.action for s in result.executed)) == [
        "FBFB",
        "BSBS",
        "SSFF",
        "BSBS",
        "SSFF",
    ]


# --- lookahead windows before the faulty action -------------------------------------------------


def test_a_before_window_starts_ahead_of_the_faulty_action() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]

    def run(before: int):  # type: ignore[no-untyped-def]
        return run_mission(
            MissionSpec(
                maze,
                route.start,
                route.goal,
                schedule=FaultSchedule.permanent(F("FL:F")),
                strategy="lookahead",
                options=StrategyOptions(recursion="guarded", window=3, before=before),
            )
        )

    after, both = run(0), run(2)
    assert after.reached and both.reached
    assert all(r.repair.consumed == 4 for r in after.repairs)  # faulty + 3 after
    early = [r for r in both.repairs if r.repair.consumed == 6]  # 2 before + faulty + 3
    assert early, "no window reached back"
    for record in early:  # the faulty action was 2 actions ahead when the window was made
        assert FOUR_WHEEL.available(both.steps[record.step].action, F("FL:F"))
    assert both.ticks <= after.ticks
    for result in (after, both):
        assert all(FOUR_WHEEL.available(s.action, F("FL:F")) for s in result.executed)


def test_with_on_use_detection_a_window_cannot_reach_back() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    result = run_mission(
        MissionSpec(
            maze,
            route.start,
            route.goal,
            schedule=FaultSchedule.permanent(F("FL:F"), detection="on-use"),
            strategy="lookahead",
            options=StrategyOptions(recursion="guarded", window=3, before=2),
        )
    )
    assert result.reached
    # the first fault becomes known only when its action fails: that window cannot reach back;
    # once known, later actions it forbids are seen coming
    assert result.steps[result.repairs[0].step - 1].source == "failed-attempt"
    assert result.repairs[0].repair.consumed <= 4
    assert any(r.repair.consumed == 6 for r in result.repairs[1:])


# --- the scale experiment's crossover ----------------------------------------------------------


def _scale_rows(k: float, slope: float) -> list[dict[str, object]]:
    """Pairs whose ratio is exactly ``k * side**slope`` (with noise that cancels in the fit)."""
    rows: list[dict[str, object]] = []
    for side in (16, 32, 64, 128, 256):
        for i, noise in enumerate((0.8, 1.0, 1.25)):
            ratio = k * side**slope * noise
            common = {
                "maze": f"m{side}",
                "route": f"r{i}",
                "faults": "FL:F",
                "fault_at": 0,
                "detection": "now",
                "replicate": 0,
                "maze_width": side,
                "maze_height": side,
                "faulty_encounters": 3,
                "clearance_weight": "0",
            }
            rows.append(
                {
                    **common,
                    "strategy": "replan",
                    "variant": "replan",
                    "replans": 1,
                    "repair_compute_ns": 1e9,
                }
            )
            rows.append(
                {
                    **common,
                    "strategy": "replacement",
                    "variant": "v",
                    "replans": 0,
                    "repair_compute_ns": 1e9 * ratio,
                }
            )
    return rows


def test_crossover_of_a_known_power_law() -> None:
    result = crossover(_scale_rows(10.0, -1.0), "v")  # ratio 10/side: 0.1 at side 100
    assert result.slope == pytest.approx(-1.0)
    assert result.side is not None and result.side.estimate == pytest.approx(100.0)
    assert result.side.low <= 100.0 <= result.side.high
    assert result.first_below == 128
    flat = crossover(_scale_rows(0.5, 0.0), "v")  # never falls: no crossover
    assert flat.side is None and flat.first_below is None
    assert any("no crossover" in line for line in flat.lines())
    assert crossover(_scale_rows(10.0, -1.0)[:12], "v").slope is None  # two sizes only


def test_scale_experiment_is_shipped_offline() -> None:
    from selfrepair.cli.experiments import resolve_experiment
    from selfrepair.experiment.config import load_config
    from selfrepair.experiment.mazes import maze_of
    from selfrepair.experiment.missions import expand

    config = load_config(resolve_experiment("scale"))
    assert config.crossover and config.timing_repeats >= 1
    files = [Path(m.file) for m in config.mazes if m.file is not None]
    assert files and all((config.base_dir / f).is_file() for f in files)
    assert "tests" not in {part for f in files for part in (config.base_dir / f).resolve().parts}
    missions = expand(config)
    sides = {maze_of(canonical_json(m.settings["maze"])).width for m in missions}
    assert min(sides) == 15 and max(sides) == 512
    assert math.isfinite(len(missions)) and len(missions) == 360  # 216 + 144 rewriting
