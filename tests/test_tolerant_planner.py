"""The tolerant planner: masks per (pose, action), hard and soft modes, both backends."""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from extras import NUMBA
from selfrepair.errors import ProblemError
from selfrepair.execution.context import mission_context
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.limits import MAX_LOOKUP_PATTERNS
from selfrepair.repair import tolerance_book
from selfrepair.repair.replacement import DEFAULT_MAX_DEPTH, RecursionMode, table_reach
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.repair.tolerance import fault_model, needs_replan, plan_tolerance
from selfrepair.repair.tolerance_book import MaskBook
from selfrepair.repair.tolerance_masks import tolerance_masks, tolerance_term
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan, plan_cost, planning_actions
from selfrepair.search.problem import PlanningProblem, StepTerm
from selfrepair.tables.fileformat import resolve_table
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.routes import random_routes

ACTIONS = planning_actions(FOUR_WHEEL, frozenset())
SINGLE = fault_model(FOUR_WHEEL, 1)
DOUBLE = fault_model(FOUR_WHEEL, 2)
BACKENDS = ["python", pytest.param("numba", marks=NUMBA)]


def _term(maze: Maze, table: str, recursion: str, k: int, penalty: Fraction | None) -> StepTerm:
    t = resolve_table(table)
    grid = maze.free_grid(max(2, table_reach(t)))
    return tolerance_term(t, grid, ACTIONS, fault_model(FOUR_WHEEL, k), penalty=penalty,
                          mode=recursion)  # fmt: skip


def test_masks_are_the_strategys_local_test_at_every_pose() -> None:
    """Every bit of every mask on a small maze equals the replacement strategy's own answer."""
    maze = generate_maze(9, 9, corridor=1, braid=0.3, seed=3)
    for table, recursion in (("handwritten", "flat"), ("generated-indexed", "guarded")):
        spec = MissionSpec(maze, Pose(1, 1, Heading.E), (7, 7),
                           options=StrategyOptions(table=table, recursion=recursion))  # fmt: skip
        t = spec.options.resolved_table()
        context = mission_context(spec, t)
        masks = tolerance_masks(t, context.grid, ACTIONS, SINGLE, mode=recursion)
        set_bits = 0
        for x, y in maze.free_cells():
            for heading in Heading:
                pose = Pose(x, y, heading)
                for k, action in enumerate(ACTIONS):
                    expected = tuple(
                        f for f in SINGLE.fault_sets if needs_replan(context, pose, action, f)
                    )
                    assert masks.fault_sets_at(pose, k) == expected, (pose, action)
                    assert masks.counts[y, x, heading, k] == len(expected)
                    set_bits += len(expected)
        assert set_bits > 0


def _agrees_with_the_strategy(maze: Maze, table: str, recursion: str, k: int) -> int:
    """Every bit of the masks of ``maze`` equals ``needs_replan``; returns the bits set."""
    model = fault_model(FOUR_WHEEL, k)
    spec = MissionSpec(maze, Pose(1, 1, Heading.E), (1, 1),
                       options=StrategyOptions(table=table, recursion=recursion))  # fmt: skip
    t = spec.options.resolved_table()
    context = mission_context(spec, t)
    masks = tolerance_masks(t, context.grid, ACTIONS, model, mode=recursion)
    full = masks.masks
    set_bits = 0
    for x, y in maze.free_cells():
        for heading in Heading:
            pose = Pose(x, y, heading)
            for k_, action in enumerate(ACTIONS):
                expected = tuple(
                    f for f in model.fault_sets if needs_replan(context, pose, action, f)
                )
                assert masks.fault_sets_at(pose, k_) == expected, (pose, action)
                assert masks.counts[y, x, heading, k_] == len(expected)
                bits = sum(int(w) << (64 * i) for i, w in enumerate(full[y, x, heading, k_]))
                assert bits == sum(1 << model.fault_sets.index(f) for f in expected)
                set_bits += len(expected)
    assert not masks.counts[maze.walls].any()
    return set_bits


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.integers(0, 10_000), st.integers(0, 10_000), st.sampled_from([1, 2]),
    st.sampled_from(["handwritten", "generated-agnostic", "generated-indexed"]),
    st.sampled_from(["flat", "guarded", "layered"]),
)  # fmt: skip
def test_a_pattern_answered_on_one_maze_is_right_on_another(
    first: int, second: int, corridor: int, table: str, recursion: str
) -> None:
    """The pattern book is shared by every maze: masks made after another maze filled it
    still equal the strategy's own answer at every pose (single faults)."""
    _agrees_with_the_strategy(generate_maze(9, 9, corridor=corridor, braid=0.4, seed=first),
                              table, recursion, 1)  # fmt: skip
    _agrees_with_the_strategy(generate_maze(9, 9, corridor=corridor, braid=0.4, seed=second),
                              table, recursion, 1)  # fmt: skip


def test_double_fault_masks_and_a_book_that_starts_afresh(monkeypatch: pytest.MonkeyPatch) -> None:
    """Masks of the 78 single and double faults agree with the strategy; a book past its row
    bound starts afresh, and masks made before keep their own rows."""
    one = generate_maze(9, 9, corridor=1, braid=0.3, seed=5)
    two = generate_maze(9, 9, corridor=2, braid=0.3, seed=6)
    assert _agrees_with_the_strategy(one, "handwritten", "flat", 2) > 0
    monkeypatch.setattr(tolerance_book, "MAX_BOOK_ROWS", 1)
    before = tolerance_masks(resolve_table("handwritten"), one.free_grid(2), ACTIONS, DOUBLE)
    saved = before.masks.copy()
    assert _agrees_with_the_strategy(two, "handwritten", "flat", 2) > 0
    assert np.array_equal(before.masks, saved)


def test_hard_plan_is_tolerant_and_costs_at_least_the_optimum() -> None:
    maze = load_bundled("narrow-short")
    for route in bundled_routes("narrow-short"):
        for table in ("handwritten", "generated-indexed"):
            term = _term(maze, table, "flat", 1, None)
            optimum = plan(PlanningProblem(maze, route.start, route.goal))
            hard = plan(PlanningProblem(maze, route.start, route.goal, step_term=term))
            assert hard.status is PlanStatus.SOLVED and optimum.cost is not None
            assert hard.cost == hard.duration >= optimum.cost
            spec = MissionSpec(maze, route.start, route.goal,
                               options=StrategyOptions(table=table))  # fmt: skip
            context = mission_context(spec, spec.options.resolved_table())
            tolerance = plan_tolerance(context, hard.poses, hard.actions, SINGLE)
            assert tolerance.tolerant and tolerance.replan_steps == 0


def test_hard_mode_proves_that_no_tolerant_plan_exists() -> None:
    """A one-cell corridor: with FL:F and FL:S the front-left wheel only goes backward, and
    the hand-written table has no replacement for a forward step there."""
    walls = np.ones((3, 9), dtype=bool)
    walls[1, :] = False
    maze = Maze(walls)
    term = _term(maze, "handwritten", "flat", 2, None)
    found = plan(PlanningProblem(maze, Pose(0, 1, Heading.E), (8, 1), step_term=term))
    assert found.status is PlanStatus.UNSOLVABLE
    single = _term(maze, "handwritten", "flat", 1, None)
    assert plan(PlanningProblem(maze, Pose(0, 1, Heading.E), (8, 1), step_term=single)).actions


def test_soft_cost_is_duration_plus_penalty_per_step_that_needs_a_replan() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(maze, route.start, route.goal)
    context = mission_context(spec, spec.options.resolved_table())
    optimum = plan(PlanningProblem(maze, route.start, route.goal))
    base = plan_tolerance(context, optimum.poses, optimum.actions, DOUBLE)
    for penalty in (Fraction(1, 3), Fraction(1), Fraction(5)):
        term = _term(maze, "handwritten", "flat", 2, penalty)
        problem = PlanningProblem(maze, route.start, route.goal, step_term=term)
        soft = plan(problem)
        assert soft.cost is not None and optimum.cost is not None
        steps = plan_tolerance(context, soft.poses, soft.actions, DOUBLE).replan_steps
        assert soft.cost == soft.duration + penalty * steps == plan_cost(problem, soft.actions)
        assert soft.cost <= optimum.cost + penalty * base.replan_steps  # the soft optimum


def test_a_term_for_other_actions_or_another_maze_is_refused() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    term = _term(maze, "handwritten", "flat", 1, None)
    faults = FOUR_WHEEL.parse_faults("FL:F")
    with pytest.raises(ProblemError, match="other planning actions"):
        plan(PlanningProblem(maze, route.start, route.goal, faults=faults, step_term=term))
    other = load_bundled("wide-short")
    with pytest.raises(ProblemError, match="maze"):
        plan(PlanningProblem(other, Pose(1, 1, Heading.E), (2, 2), step_term=term))
    with pytest.raises(ProblemError, match="non-deferring"):
        _term(maze, "handwritten", "primitive", 1, None)
    with pytest.raises(ProblemError, match="shape"):
        StepTerm(ACTIONS, np.zeros((2, 2, 4, 3), dtype=np.int32))


@st.composite
def _problems(draw: st.DrawFn) -> tuple[PlanningProblem, int]:
    seed = draw(st.integers(0, 10_000))
    maze = generate_maze(11, 11, corridor=draw(st.sampled_from([1, 2])), braid=0.4, seed=seed)
    route = random_routes(maze, 1, seed)[0]
    table = draw(st.sampled_from(["handwritten", "generated-indexed"]))
    recursion = draw(st.sampled_from(["flat", "guarded", "layered"]))
    k = draw(st.sampled_from([1, 2]))
    penalty = draw(st.sampled_from([None, Fraction(0), Fraction(1, 2), Fraction(3)]))
    weight = draw(st.sampled_from([Fraction(0), Fraction(1)]))
    term = _term(maze, table, recursion, k, penalty)
    problem = PlanningProblem(maze, route.start, route.goal, clearance_weight=weight,
                              step_term=term)  # fmt: skip
    return problem, k


@NUMBA
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_problems())
def test_backends_agree_on_tolerant_plans(case: tuple[PlanningProblem, int]) -> None:
    problem, _ = case
    fast = plan(problem, backend="numba")
    slow = plan(problem, backend="python")
    assert (fast.status, fast.actions, fast.poses, fast.cost) == (
        slow.status, slow.actions, slow.poses, slow.cost,
    )  # fmt: skip
    term = problem.step_term
    assert term is not None and term.source is not None  # the kernel read it per cell
    dense = StepTerm(term.actions, term.dense_counts(), term.penalty)  # and as a dense array
    same = plan(replace(problem, step_term=dense), backend="numba")
    assert (same.status, same.actions, same.cost) == (slow.status, slow.actions, slow.cost)
    if fast.status is PlanStatus.SOLVED:
        assert plan_cost(problem, fast.actions) == fast.cost


@NUMBA
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.integers(0, 10_000), st.sampled_from([9, 13]), st.sampled_from([1, 2]),
    st.sampled_from([1, 2]),
    st.sampled_from(["handwritten", "generated-agnostic", "generated-indexed"]),
    st.sampled_from(["flat", "guarded", "layered"]),
)  # fmt: skip
def test_the_kernels_pattern_reading_equals_the_reference_masks(
    seed: int, size: int, corridor: int, k: int, table: str, recursion: str
) -> None:
    """The counts the compiled search reads per expanded cell (its own pattern gather and index
    probe, the book filling the patterns it lacks) equal the masks of a book of their own."""
    from selfrepair.search import _kernels
    maze = generate_maze(size, size, corridor=corridor, braid=0.4, seed=seed)
    t = resolve_table(table)
    grid = maze.free_grid(max(2, table_reach(t)))
    model = fault_model(FOUR_WHEEL, k)
    term = tolerance_term(t, grid, ACTIONS, model, mode=recursion)
    assert term.source is not None and term.counts is None
    mode = RecursionMode(recursion)
    reference = MaskBook(t, ACTIONS, model, mode, DEFAULT_MAX_DEPTH, MAX_LOOKUP_PATTERNS)
    expected = reference.masks(grid).counts
    assert np.array_equal(_kernels.term_counts(term), expected)
    assert np.array_equal(term.dense_counts(), expected)
    assert expected.any()


@NUMBA
def test_a_book_that_starts_afresh_during_a_search_gives_the_same_plan(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """With a book bound of 3 rows, the kernel's misses on a map the book has not met start the
    book afresh again and again during one search: the cell rows it read before are dropped, and
    the plans equal the pure-Python search's on the dense masks."""
    monkeypatch.setattr(tolerance_book, "MAX_BOOK_ROWS", 3)
    starts = []
    start = MaskBook._start

    def counted(book: MaskBook) -> None:
        starts.append(book)
        start(book)

    monkeypatch.setattr(MaskBook, "_start", counted)
    maze = generate_maze(15, 15, corridor=1, braid=0.4, seed=41)
    for penalty in (None, Fraction(1)):
        term = _term(maze, "generated-agnostic", "flat", 1, penalty)
        for route in random_routes(maze, 3, 5):
            problem = PlanningProblem(maze, route.start, route.goal, step_term=term)
            before = len(starts)
            fast = plan(problem, backend="numba")
            if route is random_routes(maze, 3, 5)[0] and penalty is None:
                assert len(starts) > before + 1  # afresh more than once in the first search
            slow = plan(problem, backend="python")
            assert (fast.status, fast.actions, fast.cost) == (slow.status, slow.actions, slow.cost)
    rows = tolerance_masks(resolve_table("generated-agnostic"), maze.free_grid(2), ACTIONS,
                           SINGLE).counts  # fmt: skip
    assert rows.any()


def _kernel_rows(seed: int, corridor: int, k: int, table: str) -> int:
    """Plan soft on a map the book has not met (after another map taught it parts) and check the
    rows the search added against a fresh book's (see the test below); returns how many rows the
    compiled search made itself."""
    from selfrepair.caching import CacheKind, clear_caches
    from selfrepair.repair import tolerance_masks as masks_module

    clear_caches([CacheKind.REPAIR])  # a book that has met the warm-up map only
    t = resolve_table(table)
    model = fault_model(FOUR_WHEEL, k)
    margin = max(2, table_reach(t))
    warm = generate_maze(13, 13, corridor=corridor, braid=0.4, seed=seed + 1)
    tolerance_masks(t, warm.free_grid(margin), ACTIONS, model)  # parts met on another map
    maze = generate_maze(13, 13, corridor=corridor, braid=0.4, seed=seed)
    grid = maze.free_grid(margin)
    term = tolerance_term(t, grid, ACTIONS, model, penalty=Fraction(1))  # soft: reads far
    assert term.source is not None
    book = masks_module._book(t, ACTIONS, model, RecursionMode.FLAT, DEFAULT_MAX_DEPTH,
                              MAX_LOOKUP_PATTERNS)  # fmt: skip
    handed: list[int] = []
    fill = MaskBook.fill

    def checked(b: MaskBook, g: object, x: int, y: int, code: int | None = None) -> int:
        assert code == b.code(grid, x, y)
        handed.append(x)
        return fill(b, grid, x, y, code)

    before = book.rows
    for route in random_routes(maze, 3, seed):
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(MaskBook, "fill", checked)
            plan(PlanningProblem(maze, route.start, route.goal, step_term=term), backend="numba")
    fresh = MaskBook(t, ACTIONS, model, RecursionMode.FLAT, DEFAULT_MAX_DEPTH, MAX_LOOKUP_PATTERNS)
    expected = fresh.masks(grid)
    made = tolerance_masks(t, grid, ACTIONS, model)
    assert np.array_equal(made.counts, expected.counts)
    assert np.array_equal(made.masks, expected.masks)
    assert np.array_equal(term.dense_counts(), expected.counts)
    return book.rows - before - len(handed)


@NUMBA
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.integers(0, 10_000), st.sampled_from([1, 2]), st.sampled_from([1, 2]),
    st.sampled_from(["handwritten", "generated-agnostic"]),
)  # fmt: skip
def test_rows_the_kernel_adds_equal_a_fresh_books_rows(
    seed: int, corridor: int, k: int, table: str
) -> None:
    """On a map the book has not met, the compiled search adds the rows of new patterns whose
    parts the book knows from another map itself, and hands the others to the book with the
    code it read (which is the book's own reading of the cell). The counts and fault sets of
    every row made either way equal those of a fresh book that has met no other map."""
    _kernel_rows(seed, corridor, k, table)


@NUMBA
@pytest.mark.parametrize("k", [1, 2])
def test_the_kernel_adds_rows_itself(k: int) -> None:
    """With the fault-agnostic table's wide patterns, a map the book has not met has new
    patterns made of parts it knows, and the search adds their rows without the book."""
    assert _kernel_rows(0, 1, k, "generated-agnostic") > 0
