"""Rewriting with detours: with ``rewrite`` on, the repair of a blocked action replaces every
later window of the queue that sweeps a believed-blocked cell by a detour, in one pass, and the
robot replans only where a window has none (docs/dynamic.md, "Local detours")."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import selfrepair as sr
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.world.events import Sensing, WorldEvent, WorldSchedule, random_world
from selfrepair.world.maze import parse_maze
from test_world_events import swept_blocked

ROBOT = sr.get_domain("four-wheel")

HALL = parse_maze("\n".join(["#############", *["#...........#"] * 5, "#############"]))
"""An open hall, 11 by 5 free cells: room for a detour round any one cell."""

SEEN_AT_ONCE = WorldSchedule(
    (WorldEvent((4, 3), True, 1), WorldEvent((8, 3), True, 1)),
    sensing=Sensing.RANGE,
    sensing_range=12,
)
"""Two cells on the straight route blocked just after the first command, and seen at once (the
robot sees the whole hall): the plan's two windows meet them."""


def _run(rewrite: bool, world: WorldSchedule = SEEN_AT_ONCE) -> sr.MissionResult:
    spec = sr.MissionSpec(
        HALL,
        Pose(1, 3, Heading.E),
        (11, 3),
        world=world,
        options=StrategyOptions(rewrite=rewrite),
    )
    return sr.run_mission(spec)


def test_one_rewriting_repair_takes_both_detours() -> None:
    each = _run(rewrite=False)
    once = _run(rewrite=True)
    assert [r.repair.attempts for r in each.repairs] == [("detour",), ("detour",)]
    assert [r.repair.attempts for r in once.repairs] == [("detour",)]
    assert once.repairs[0].repair.rewritten == 1
    # the same motions: a detour ends where the window it replaces ends
    assert [(s.action, s.start, s.end) for s in once.steps] == [
        (s.action, s.start, s.end) for s in each.steps
    ]
    for result in (each, once):
        assert result.reached and swept_blocked(result) == []
        assert sr.mission_row(result)["replans"] == 0
    assert sr.mission_row(once)["detours"] == sr.mission_row(each)["detours"] == 2


def test_a_window_without_a_detour_ends_the_pass_and_the_robot_replans_there() -> None:
    """The second blocked cell sits in a one-cell gap of a wall across the hall: no detour
    round it, so the rewriting repair takes the first detour only and the robot replans when
    it meets the gap, as without rewriting."""
    walled = parse_maze(
        "\n".join(
            [
                "#############",
                "#.......#...#",
                "#.......#...#",
                "#...........#",
                "#.......#...#",
                "#.......#...#",
                "#############",
            ]
        )
    )
    world = WorldSchedule(
        (WorldEvent((4, 3), True, 1), WorldEvent((8, 3), True, 1), WorldEvent((8, 3), False, 60)),
        sensing_range=12,
    )
    runs = []
    for rewrite in (False, True):
        spec = sr.MissionSpec(
            walled, Pose(1, 3, Heading.E), (11, 3), world=world,
            options=StrategyOptions(rewrite=rewrite), max_steps=400,
        )  # fmt: skip
        runs.append(sr.run_mission(spec))
    each, once = runs
    assert once.repairs[0].repair.attempts == ("detour",)
    assert once.repairs[0].repair.rewritten == 0  # the gap has no detour: nothing more
    assert [r.repair.attempts for r in once.repairs] == [r.repair.attempts for r in each.repairs]
    assert ("detour", "replan") in [r.repair.attempts for r in once.repairs]
    assert [(s.action, s.end) for s in once.steps] == [(s.action, s.end) for s in each.steps]
    assert swept_blocked(once) == []


WIDE = sr.load_bundled("wide-long")
WIDE_ROUTES = sr.bundled_routes("wide-long")


def _plan_cells(route: int) -> list[tuple[int, int]]:
    """The cells the fault-free plan of a wide-long route ends its steps on, start and goal
    left out."""
    r = WIDE_ROUTES[route]
    plan = sr.run_mission(sr.MissionSpec(WIDE, r.start, r.goal, strategy="replan"))
    return [s.end.cell for s in plan.steps if s.end.cell not in (r.start.cell, r.goal)]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    route=st.integers(0, len(WIDE_ROUTES) - 1),
    picks=st.lists(st.floats(0, 1, exclude_max=True), min_size=1, max_size=5, unique=True),
)
def test_with_the_belief_fixed_rewriting_makes_the_same_motions_in_fewer_repairs(
    route: int, picks: list[float]
) -> None:
    """Cells along the plan blocked for good just after the first command and seen at once
    (range over the whole maze): rewriting makes the same motions and replans as meeting each
    window in turn (the same or fewer replans, here the same), in at most as many repairs, and
    no motion of either sweeps a blocked cell (the independent re-simulation)."""
    cells = _plan_cells(route)
    chosen = sorted({cells[int(p * len(cells))] for p in picks})
    world = WorldSchedule(
        tuple(WorldEvent(c, True, 1) for c in chosen), sensing_range=max(WIDE.width, WIDE.height)
    )
    r = WIDE_ROUTES[route]
    each, once = (
        sr.run_mission(
            sr.MissionSpec(
                WIDE,
                r.start,
                r.goal,
                world=world,
                max_steps=3000,
                options=StrategyOptions(rewrite=rewrite),
            )
        )
        for rewrite in (False, True)
    )
    assert swept_blocked(each) == [] and swept_blocked(once) == []
    assert [(s.action, s.end) for s in once.steps] == [(s.action, s.end) for s in each.steps]
    row_each, row_once = sr.mission_row(each), sr.mission_row(once)
    assert row_once["replans"] <= row_each["replans"]
    assert row_once["detours"] == row_each["detours"]
    assert len(once.repairs) <= len(each.repairs)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    rate=st.sampled_from([10.0, 40.0]),
    faults=st.sampled_from(["", "FL:F"]),
    sensing_range=st.sampled_from([2, 8]),
)
def test_rewriting_in_a_changing_world_sweeps_no_blocked_cell(
    seed: int, rate: float, faults: str, sensing_range: int
) -> None:
    """Random obstacles that come and go near the route, seen within 2 or 8 cells, with and
    without a fault: the rewriting robot never sweeps a cell blocked at that time (its
    rewritten windows were free when it looked; a cell blocked since is met again)."""
    r = WIDE_ROUTES[0]
    world = random_world(
        [r.start.cell, *_plan_cells(0)], WIDE.free_cells(), seed=seed, rate=rate, duration=30,
        distance=1, horizon=400, exclude=[r.start.cell, r.goal], sensing_range=sensing_range,
    )  # fmt: skip
    schedule = sr.FaultSchedule.permanent(ROBOT.parse_faults(faults)) if faults else None
    spec = sr.MissionSpec(
        WIDE, r.start, r.goal, world=world, max_steps=3000,
        options=StrategyOptions(rewrite=True), **({"schedule": schedule} if schedule else {}),
    )  # fmt: skip
    result = sr.run_mission(spec)
    assert swept_blocked(result) == []
    assert result.status.value in {"reached", "stuck", "step_limit"}
