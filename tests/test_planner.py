"""The robot-lattice planner: hand-checked optimal costs, statuses, budgets, errors, costs."""

from __future__ import annotations

from fractions import Fraction

import pytest

from extras import NUMBA
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose, parse_pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action, parse_faults
from selfrepair.search.astar import PlanResult, PlanStatus
from selfrepair.search.lattice import HEURISTICS, action_cost, plan, plan_cost, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.maze import Maze, clearance_map, parse_maze

BACKENDS = ["python", pytest.param("numba", marks=NUMBA)]

CORRIDOR = parse_maze(".....\n")
OPEN_2X2 = parse_maze("..\n..\n")
NOTCHED_2X2 = parse_maze("..\n#.\n")
U_TURN = parse_maze(".....\n.###.\n.....\n")
SPLIT = parse_maze("..#..\n..#..\n")
OPEN_5X5 = parse_maze(".....\n.....\n.....\n.....\n.....\n")


def solve(
    maze: Maze,
    start: str,
    goal: str,
    *,
    faults: str = "",
    weight: Fraction = Fraction(0),
    radius: int = 2,
    backend: str = "python",
    heuristic: str = "grid-distance",
) -> PlanResult:
    parts = goal.split(",")
    heading = Heading[parts[2]] if len(parts) == 3 else None
    problem = PlanningProblem(
        maze,
        parse_pose(start),
        (int(parts[0]), int(parts[1])),
        goal_heading=heading,
        faults=parse_faults(faults),
        clearance_weight=weight,
        clearance_radius=radius,
    )
    return plan(problem, heuristic=heuristic, backend=backend)


# Each case: maze, start, goal, faults, weight, optimal cost, and why (checked by hand).
ZOO = [
    (CORRIDOR, "0,0,E", "4,0", "", 0, 4, "four FFFF straights of 1 tick"),
    (CORRIDOR, "0,0,W", "4,0", "", 0, 4, "four BBBB (backward) straights of 1 tick"),
    (CORRIDOR, "0,0,N", "4,0", "", 0, 5, "one quarter turn (1 tick) then four straights"),
    (CORRIDOR, "0,0,E", "4,0,N", "", 0, 5, "four straights then a quarter turn to face N"),
    (CORRIDOR, "0,0,E", "4,0,W", "", 0, 6, "four straights then two quarter turns"),
    (OPEN_2X2, "0,0,E", "1,1", "", 0, 2, "one forward-right arc of 2 ticks"),
    (NOTCHED_2X2, "0,0,E", "1,1", "", 0, 3, "arc blocked by the wall: straight, turn, straight"),
    (U_TURN, "0,0,E", "4,2", "", 0, 7, "4 straights, a turn, 2 straights (no 2x2 room to arc)"),
    (CORRIDOR, "0,0,E", "4,0", "FL:F", 0, 6,
     "FL:F halves forward speed (2 ticks/cell): turn around (2) and back up 4 cells (4)"),
    (CORRIDOR, "0,0,E", "4,0", "FL:F,FL:B", 0, 8,
     "FL only stops: no turn in place at 1 tick; straights at 2 ticks beat turning"),
    (CORRIDOR, "0,0,E", "4,0", "", Fraction(1, 2), 8,
     "every cell has clearance 1 < 2: each straight sweeps 2 cells, 1 + 1/2 * 2 = 2 per step"),
    (CORRIDOR, "0,0,E", "4,0", "", Fraction(1, 2), 4, "radius 1: no cell is penalised"),
]  # fmt: skip
ZOO_RADIUS = [2] * 11 + [1]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    ("case", "radius"), list(zip(ZOO, ZOO_RADIUS, strict=True)), ids=[c[6] for c in ZOO]
)
def test_zoo_optimal_costs(case: tuple, radius: int, backend: str) -> None:
    maze, start, goal, faults, weight, expected, _why = case
    result = solve(
        maze, start, goal, faults=faults, weight=Fraction(weight), radius=radius, backend=backend
    )
    assert result.status is PlanStatus.SOLVED
    assert result.cost == expected
    assert len(result.poses) == len(result.actions) + 1
    assert result.poses[0] == parse_pose(start)


def test_zoo_case_with_faults_uses_only_available_actions() -> None:
    result = solve(CORRIDOR, "0,0,E", "4,0", faults="FL:F")
    assert all(four_wheel.available(a, parse_faults("FL:F")) for a in result.actions)
    assert [a.motion.name for a in result.actions].count("backward") == 4
    assert result.duration == 6


def test_a_wheel_that_can_do_nothing_leaves_no_action_and_no_plan() -> None:
    # Every command of FL is faulty: no action at all is available, so no heading change either.
    maze = parse_maze(".\n")
    result = solve(maze, "0,0,E", "0,0,W", faults="FL:F,FL:S,FL:B")
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.actions == () and result.poses == () and result.cost is None


@pytest.mark.parametrize("backend", BACKENDS)
def test_walled_off_goal_is_unsolvable_not_budget(backend: str) -> None:
    result = solve(SPLIT, "0,0,E", "4,1", backend=backend)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.cost is None and result.duration == 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_zero_heuristic_still_explores_a_split_maze_before_giving_up(backend: str) -> None:
    result = solve(SPLIT, "0,0,E", "4,1", heuristic="zero", backend=backend)
    assert result.status is PlanStatus.UNSOLVABLE
    assert result.expansions == 16  # 4 free cells x 4 headings on the start side


@pytest.mark.parametrize("backend", BACKENDS)
def test_node_budget_gives_budget_exhausted(backend: str) -> None:
    result = plan(
        PlanningProblem(U_TURN, parse_pose("0,0,E"), (4, 2)), max_expansions=3, backend=backend
    )
    assert result.status is PlanStatus.BUDGET_EXHAUSTED
    assert result.expansions == 3
    assert result.cost is None and result.actions == ()


@pytest.mark.parametrize("backend", BACKENDS)
def test_zero_time_limit_gives_budget_exhausted(backend: str) -> None:
    result = plan(PlanningProblem(U_TURN, parse_pose("0,0,E"), (4, 2)), time_limit=0.0,
                  backend=backend)  # fmt: skip
    assert result.status is PlanStatus.BUDGET_EXHAUSTED


def test_budget_large_enough_solves() -> None:
    full = solve(U_TURN, "0,0,E", "4,2")
    result = plan(
        PlanningProblem(U_TURN, parse_pose("0,0,E"), (4, 2)), max_expansions=full.expansions
    )
    assert result.status is PlanStatus.SOLVED and result.cost == full.cost


def test_start_equal_goal_is_solved_with_an_empty_plan() -> None:
    result = solve(CORRIDOR, "2,0,E", "2,0")
    assert result.status is PlanStatus.SOLVED
    assert result.actions == () and result.poses == (parse_pose("2,0,E"),)
    assert result.cost == 0 and result.duration == 0 and result.expansions == 0


def test_goal_heading_at_the_start_cell_needs_turns() -> None:
    assert solve(CORRIDOR, "2,0,E", "2,0,W").cost == 2


@pytest.mark.parametrize("heuristic", sorted(HEURISTICS))
def test_every_heuristic_finds_the_same_optimum(heuristic: str) -> None:
    expected = solve(OPEN_5X5, "0,0,N", "4,3", heuristic="zero").cost
    assert solve(OPEN_5X5, "0,0,N", "4,3", heuristic=heuristic).cost == expected


def test_informed_heuristic_expands_fewer_nodes_than_zero() -> None:
    zero = solve(OPEN_5X5, "0,0,N", "4,4", heuristic="zero")
    informed = solve(OPEN_5X5, "0,0,N", "4,4", heuristic="grid-distance")
    assert informed.expansions < zero.expansions


def test_clearance_weight_moves_the_plan_away_from_walls() -> None:
    # A 7x7 room: with weight 0 the robot hugs the top wall, with a weight it keeps off it.
    room = parse_maze("\n".join(["......."] * 7) + "\n")
    plain = solve(room, "0,0,E", "6,0")
    careful = solve(room, "0,0,E", "6,0", weight=Fraction(2), radius=3)
    assert plain.duration == 6
    assert careful.duration > plain.duration
    assert any(p.y > 0 for p in careful.poses)
    assert careful.cost == plan_cost(
        PlanningProblem(room, parse_pose("0,0,E"), (6, 0), clearance_weight=Fraction(2),
                        clearance_radius=3),
        careful.actions,
    )  # fmt: skip


def test_action_cost_formula_by_hand() -> None:
    maze = parse_maze("....\n....\n....\n")
    clearance = clearance_map(maze)  # indexed [y, x]; the outside counts as wall
    assert (clearance[1, 1], clearance[1, 2], clearance[2, 1], clearance[2, 2]) == (2, 2, 1, 1)
    pose = parse_pose("1,1,E")
    arc = four_wheel.fastest_by_motion()[
        next(m for m in four_wheel.MOTIONS if m.name == "arc-forward-right")
    ]
    # Sweeps (1,1), (2,1), (1,2), (2,2) with clearances 2, 2, 1, 1: penalty 1 + 1 + 2 + 2 = 6.
    cost = action_cost(maze, pose, arc, clearance_weight=Fraction(1, 4), clearance_radius=3)
    assert cost == arc.duration + Fraction(6, 4) == Fraction(7, 2)
    assert action_cost(maze, pose, arc, clearance_weight=Fraction(0), clearance_radius=3) == 2


def test_plan_cost_re_simulates_and_rejects_bad_plans() -> None:
    problem = PlanningProblem(CORRIDOR, parse_pose("0,0,E"), (2, 0))
    ffff = parse_action("FFFF")
    assert plan_cost(problem, [ffff, ffff]) == 2
    with pytest.raises(ProblemError, match="not at the goal"):
        plan_cost(problem, [ffff])
    with pytest.raises(ProblemError, match="sweeps a wall"):
        plan_cost(problem, [parse_action("BBBB")])
    faulty = PlanningProblem(CORRIDOR, parse_pose("0,0,E"), (2, 0), faults=parse_faults("FL:F"))
    with pytest.raises(ProblemError, match="not available"):
        plan_cost(faulty, [ffff, ffff])


def test_plan_reports_the_fastest_wheel_action_per_motion() -> None:
    faults = parse_faults("FR:F")
    result = solve(OPEN_5X5, "0,0,E", "4,0", faults="FR:F")
    fastest = {a.motion: a for a in planning_actions(FOUR_WHEEL, faults)}
    assert fastest == {
        m: a for m, a in four_wheel.fastest_by_motion(faults).items() if m.name != "wait"
    }
    for action in result.actions:
        assert fastest[action.motion] == action


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"start": "9,0,E"}, "outside"),
        ({"start": "1,1,E"}, "wall"),
        ({"goal": (1, 1)}, "wall"),
        ({"goal": (0, 7)}, "outside"),
        ({"heuristic": "euclid"}, "unknown heuristic"),
        ({"backend": "cuda"}, "unknown backend"),
        ({"max_expansions": -1}, "max_expansions"),
        ({"time_limit": -1.0}, "time_limit"),
        ({"weight": Fraction(-1)}, "clearance_weight"),
        ({"weight": Fraction(10**6) + Fraction(1, 3)}, "clearance_weight must be from 0 to 1,000"),
        ({"weight": Fraction(10**308)}, "got a number of 309 digits"),  # overflowed in metrics
        ({"radius": -1}, "clearance_radius"),
        ({"radius": 10**20}, "clearance_radius"),
        ({"time_limit": float("nan")}, "time_limit"),
        ({"time_limit": float("inf")}, "time_limit"),
    ],
)
def test_misuse_raises_problem_error(kwargs: dict, message: str) -> None:
    problem = PlanningProblem(
        U_TURN,
        parse_pose(kwargs.get("start", "0,0,E")),
        kwargs.get("goal", (4, 2)),
        clearance_weight=kwargs.get("weight", Fraction(0)),
        clearance_radius=kwargs.get("radius", 2),
    )
    with pytest.raises(ProblemError, match=message):
        plan(
            problem,
            heuristic=kwargs.get("heuristic", "grid-distance"),
            backend=kwargs.get("backend", "python"),
            max_expansions=kwargs.get("max_expansions"),
            time_limit=kwargs.get("time_limit"),
        )


@pytest.mark.parametrize("backend", BACKENDS)
def test_huge_budget_and_weight_fall_back_instead_of_crashing(backend: str) -> None:
    """A budget beyond int64 is capped; a weight too fine for the kernel's integer costs (scaled
    by its denominator) uses the Python search."""
    weight = Fraction(1, 10**40)
    problem = PlanningProblem(
        U_TURN, parse_pose("0,0,E"), (4, 2), clearance_weight=weight, clearance_radius=0
    )
    result = plan(problem, backend=backend, max_expansions=10**23)
    assert result.status is PlanStatus.SOLVED and result.cost == 7


def test_integer_weight_is_accepted_and_exact() -> None:
    result = plan(PlanningProblem(CORRIDOR, parse_pose("0,0,E"), (4, 0), clearance_weight=1))  # type: ignore[arg-type]
    assert result.cost == Fraction(12) and isinstance(result.cost, Fraction)


def test_healthy_heuristic_rate_is_one_tick_per_cell() -> None:
    actions = planning_actions(FOUR_WHEEL, frozenset())
    bound = HEURISTICS["grid-distance"](U_TURN, (4, 2), FOUR_WHEEL, actions)
    assert bound.rate == 1
    assert bound.distance[0, 0] == 6 and bound.distance[1, 1] < 0


def test_heuristic_rate_under_slowing_faults() -> None:
    # FL and FR can only stop: each side drive is -1..1, so straights take 2 ticks and no arc
    # exists (an arc needs two different drives of the same sign).
    actions = planning_actions(FOUR_WHEEL, parse_faults("FL:F,FL:B,FR:F,FR:B"))
    assert HEURISTICS["manhattan"](OPEN_5X5, (0, 0), FOUR_WHEEL, actions).rate == 2
    assert solve(CORRIDOR, "0,0,E", "4,0", faults="FL:F,FL:B,FR:F,FR:B").cost == 8


def test_wait_is_never_a_planning_motion() -> None:
    actions = planning_actions(FOUR_WHEEL, frozenset())
    assert all(a.motion.kind is not four_wheel.MotionKind.WAIT for a in actions)
    assert len(actions) == 8


def test_result_headings_are_poses() -> None:
    result = solve(U_TURN, "0,0,E", "4,2")
    assert all(isinstance(p, Pose) for p in result.poses)
    assert result.poses[-1].cell == (4, 2)


@pytest.mark.parametrize("backend", BACKENDS)
def test_costs_beyond_int64_fall_back_to_exact_python(backend: str) -> None:
    # A weight just under the bound with a denominator of 10**18: the kernel scales costs by
    # 3 * 10**18, so its int64 would overflow, and the planner must still answer exactly (via the
    # pure-Python search).
    weight = Fraction(10**24 - 1, 10**18)
    result = solve(CORRIDOR, "0,0,E", "4,0", weight=weight, radius=2, backend=backend)
    assert result.status is PlanStatus.SOLVED
    assert result.cost == 4 + weight * 8
