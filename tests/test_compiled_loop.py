"""The compiled mission loop (:mod:`selfrepair.execution.compiled`) against the Python loop, its
reference: the same trace step by step, the same repairs (every field but the latency) and the
same row (every column but the timings and ``footing``), on random mazes, routes, fault
schedules, strategies and recursion modes; and which missions each footing takes."""

from __future__ import annotations

import dataclasses
import pickle
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from extras import NUMBA
from golden import rows_of
from selfrepair.caching import clear_caches
from selfrepair.errors import ProblemError
from selfrepair.execution.compiled.draws import MAX_SEED, MAX_WORD, draw53, threshold, uniform
from selfrepair.execution.compiled.trace import ArrayTrace
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import Clock, Detection, FaultEvent, FaultSchedule, Persistence
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionResult, MissionSpec, StepSource
from selfrepair.experiment.timing import COLD_CLEARS
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.events import WorldEvent, WorldSchedule
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.routes import random_routes

PROPERTY = settings(
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

TIMING = ("_ns", "compute_per_action")


def _same(python: MissionResult, compiled: MissionResult) -> None:
    """Both loops did the same: steps, repairs (latency aside) and row (timings aside)."""
    assert python.footing == "python" and compiled.footing == "compiled"
    assert len(python.steps) == len(compiled.steps)
    for i, (a, b) in enumerate(zip(python.steps, compiled.steps, strict=True)):
        assert a == b, f"step {i}: {a} != {b}"
    assert [r._replace(latency_ns=0) for r in python.repairs] == [
        r._replace(latency_ns=0) for r in compiled.repairs
    ]
    assert (python.status, python.reason, python.final_pose, python.ticks, python.tally) == (
        compiled.status, compiled.reason, compiled.final_pose, compiled.ticks, compiled.tally,
    )  # fmt: skip
    rows = mission_row(python), mission_row(compiled)
    differ = {
        c: (rows[0][c], rows[1][c])
        for c in rows[0]
        if c != "footing" and not any(t in c for t in TIMING) and rows[0][c] != rows[1][c]
    }
    assert not differ


def _both(spec: MissionSpec, *, cold: bool = False) -> tuple[MissionResult, MissionResult]:
    if cold:
        clear_caches(COLD_CLEARS)
    python = run_mission(dataclasses.replace(spec, footing="python"))
    if cold:
        clear_caches(COLD_CLEARS)
    return python, run_mission(dataclasses.replace(spec, footing="compiled"))


FAULTS = [f for f in FOUR_WHEEL.faults]


PROBABILITIES = st.sampled_from([0.0, 0.1, 0.5, 0.9, 1.0]) | st.floats(0.0, 1.0)


@st.composite
def schedules(draw: st.DrawFn) -> FaultSchedule:
    """Permanent, transient and intermittent faults, on either clock, detected now or on use."""
    events = []
    for _ in range(draw(st.integers(0, 3))):
        persistence = draw(st.sampled_from(list(Persistence)))
        intermittent = persistence is Persistence.INTERMITTENT
        events.append(
            FaultEvent(
                draw(st.sampled_from(FAULTS)),
                at=draw(st.integers(0, 8)),
                clock=draw(st.sampled_from(list(Clock))),
                persistence=persistence,
                duration=draw(st.integers(1, 12)) if persistence is Persistence.TRANSIENT else None,
                probability=draw(PROBABILITIES) if intermittent else None,
            )
        )
    return FaultSchedule(tuple(events), draw(st.sampled_from(["now", "on-use"])))


@NUMBA
@settings(max_examples=400, deadline=None)
@given(
    st.integers(0, 2**16) | st.integers(0, MAX_SEED),
    st.integers(0, 20) | st.integers(0, MAX_WORD),
    st.integers(0, 5000) | st.integers(0, MAX_WORD),
)
def test_compiled_intermittent_draw_is_numpys(seed: int, event: int, step: int) -> None:
    """The kernel's draw is bit for bit the Python simulator's
    ``default_rng([seed, event, step]).random()``."""
    import numpy as np

    expected = float(np.random.default_rng([seed, event, step]).random())
    assert uniform(seed, event, step) == expected
    bits = draw53(seed, event, step)
    for p in (expected, np.nextafter(expected, 2.0), np.nextafter(expected, -1.0), 0.0, 1.0):
        assert (bits < threshold(float(p))) == (expected < p)


@NUMBA
def test_intermittent_faults_run_compiled_and_the_same_as_python() -> None:
    """A paper route with two intermittent faults (and a permanent one), on both clocks and
    both detections: the compiled loop runs it and gives the Python loop's trace."""
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[1]
    fl, rr, rl = sorted(FOUR_WHEEL.parse_faults("FL:F,RR:B,RL:F"))
    for detection, clock in (("now", Clock.STEP), ("on-use", Clock.TICK)):
        events = (
            FaultEvent(fl, persistence=Persistence.INTERMITTENT, probability=0.4, clock=clock),
            FaultEvent(rr, at=3, persistence=Persistence.INTERMITTENT, probability=0.7),
            FaultEvent(rl, at=5, clock=clock),
        )
        for strategy, rewrite in (("replan", False), ("replacement", False), ("replacement", True)):
            spec = MissionSpec(
                maze, route.start, route.goal, schedule=FaultSchedule(events, detection),
                strategy=strategy, seed=7, options=StrategyOptions(rewrite=rewrite, max_wait=3),
            )  # fmt: skip
            python, compiled = _both(spec, cold=True)
            _same(python, compiled)
            assert len({step.known for step in compiled.steps}) > 2  # the faults came and went


STRATEGIES = st.sampled_from(
    [("replan", "flat", False)]
    + [("replacement", mode, rewrite) for mode in ("flat", "guarded", "layered")
       for rewrite in (False, True)]
    + [("replacement", "primitive", False)]
    + [("lookahead", mode, False) for mode in ("flat", "guarded", "layered")]
)  # fmt: skip


@NUMBA
@PROPERTY
@given(
    st.integers(0, 2**16),
    schedules(),
    STRATEGIES,
    st.sampled_from(["handwritten", "generated-agnostic", "generated-indexed"]),
    st.sampled_from([Fraction(0), Fraction(1)]),
    st.booleans(),
    st.sampled_from([(None, "auto"), (None, "python"), (25, "auto")]),
    st.tuples(st.integers(0, 3), st.integers(0, 2), st.sampled_from([1, 6, 20_000])),
)
def test_compiled_loop_gives_the_python_loops_trace(
    seed: int,
    schedule: FaultSchedule,
    strategy: tuple[str, str, bool],
    table: str,
    weight: Fraction,
    cold: bool,
    planner: tuple[int | None, str],
    lookahead: tuple[int, int, int],
) -> None:
    """Replans run in the kernel (backend auto), or in Python (backend python), with a node
    budget that some run out of; lookahead windows of 0 to 3 actions after the faulty one,
    looking 0 to 2 actions ahead, with a window budget some searches run out of."""
    name, mode, rewrite = strategy
    maze = generate_maze(11, 9, braid=0.4, seed=seed)
    route = random_routes(maze, 1, seed)[0]
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=schedule,
        strategy=name,
        options=StrategyOptions(
            table=table,
            recursion=mode,
            rewrite=rewrite,
            max_wait=3,
            window=lookahead[0],
            before=lookahead[1],
            lookahead_expansions=lookahead[2],
        ),
        clearance_weight=weight,
        seed=seed,
        replan_max_expansions=planner[0],
        backend=planner[1],
    )
    _same(*_both(spec, cold=cold))


@NUMBA
@pytest.mark.parametrize("maze_name", ["narrow-short", "wide-long"])
@pytest.mark.parametrize("rewrite", [False, True])
def test_compiled_loop_on_a_bundled_route_with_a_paper_fault_set(
    maze_name: str, rewrite: bool
) -> None:
    maze = load_bundled(maze_name)
    route = bundled_routes(maze_name)[1]
    spec = MissionSpec(
        maze,
        route.start,
        route.goal,
        schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FL:F,RR:B")),
        strategy="replacement",
        options=StrategyOptions(table="handwritten", recursion="guarded", rewrite=rewrite),
    )
    python, compiled = _both(spec, cold=True)
    _same(python, compiled)
    assert compiled.repairs and all(r.latency_ns > 0 for r in compiled.repairs)


@NUMBA
def test_the_compiled_trace_is_made_from_the_rows_and_is_the_python_loops() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[1]
    spec = MissionSpec(
        maze, route.start, route.goal,
        schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FL:F,RR:B")),
        strategy="replacement", options=StrategyOptions(table="handwritten"),
    )  # fmt: skip
    python, compiled = _both(spec)
    trace, steps = compiled.steps, python.steps
    assert isinstance(trace, ArrayTrace) and isinstance(steps, tuple)
    assert trace == steps and steps == trace and tuple(trace) == steps
    assert hash(trace) == hash(steps) and trace != steps[:-1]
    n = len(steps)
    assert [trace[i] for i in (0, 7, n - 1, -1, -n)] == [steps[i] for i in (0, 7, n - 1, -1, -n)]
    assert trace[3:11] == steps[3:11] and trace[::-5] == steps[::-5]
    for bad in (n, -n - 1):
        with pytest.raises(IndexError):
            trace[bad]
    assert not trace.rows.flags.writeable
    assert pickle.loads(pickle.dumps(trace)) == steps
    assert trace.count_source(StepSource.FAILED_ATTEMPT) == sum(
        s.source is StepSource.FAILED_ATTEMPT for s in steps
    )
    # the row from the tally (no step made) is the row measured from the steps
    assert mission_row(compiled) == mission_row(dataclasses.replace(compiled, tally=None))


@NUMBA
@pytest.mark.parametrize("maze_name", ["narrow-short", "wide-long"])
def test_primitive_recursion_defers_alike_on_the_paper_routes(maze_name: str) -> None:
    """The paper's primitive/complex scheme, which defers faulty complex actions and carries
    their guard sets over to the repair where the robot reaches them: the compiled loop gives
    the Python loop's trace on every route of the maze, with the hand-written table under a
    paper fault set and with the generated agnostic table under faults that defer (often, and
    with guard sets nested several levels)."""
    maze = load_bundled(maze_name)
    deferred = 0
    runs = [("handwritten", "FL:F,RR:B")] + [
        ("generated-agnostic", f)
        for f in ("FL:B,FR:S,FR:F", "FL:B,FL:F,RL:F", "FL:B,RR:S,RR:F", "FL:B,FL:S,FR:S,FR:F")
    ]  # the last two: without the carried guard the robot would cycle to the step limit
    for route in bundled_routes(maze_name):
        for table, faults in runs:
            known = frozenset(FOUR_WHEEL.parse_faults(faults))
            spec = MissionSpec(
                maze, route.start, route.goal, schedule=FaultSchedule.permanent(known),
                strategy="replacement",
                options=StrategyOptions(table=table, recursion="primitive"),
            )  # fmt: skip
            python, compiled = _both(spec, cold=True)
            _same(python, compiled)
            deferred += sum(  # a hit that keeps a faulty action: a deferred one
                1 for r in compiled.repairs if r.repair.replans == 0
                and not all(FOUR_WHEEL.available(b, known) for b in r.repair.actions)
            )  # fmt: skip
    assert deferred > 10


@NUMBA
@pytest.mark.parametrize("maze_name", ["narrow-short", "wide-long"])
def test_lookahead_windows_alike_on_the_paper_routes(maze_name: str) -> None:
    """The paper's lookahead (window 3, looking 0 or 2 actions ahead) and a tight window budget
    whose searches fail, so the replacement and replan fallbacks run from past the healthy
    prefix: the compiled loop gives the Python loop's trace on every route of the maze."""
    maze = load_bundled(maze_name)
    sources: set[tuple[str, ...]] = set()
    early = 0
    for route in bundled_routes(maze_name):
        for faults in ("FL:F,RR:B", "FL:B,FR:F"):
            for before, budget in ((0, 20_000), (2, 20_000), (2, 3)):
                spec = MissionSpec(
                    maze, route.start, route.goal,
                    schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults(faults)),
                    strategy="lookahead",
                    options=StrategyOptions(table="handwritten", recursion="guarded", window=3,
                                            before=before, lookahead_expansions=budget),
                )  # fmt: skip
                python, compiled = _both(spec, cold=True)
                _same(python, compiled)
                sources |= {r.repair.attempts for r in compiled.repairs}
                early += sum(
                    1 for r in compiled.repairs
                    if r.action is not None and r.repair.consumed > 1
                    and r.repair.attempts[0] == "lookahead" and r.repair.source != "lookahead"
                )  # fmt: skip
    assert ("lookahead",) in sources and ("lookahead", "replacement") in sources
    assert early > 0  # fallbacks that kept a healthy prefix in front


@NUMBA
def test_waits_and_a_mission_that_gives_up_end_alike() -> None:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    every = FOUR_WHEEL.parse_faults("FL:F,FL:B,FR:F,FR:B,RL:F,RL:B,RR:F,RR:B")  # only waits
    events = tuple(
        FaultEvent(f, at=0, persistence=Persistence.TRANSIENT, duration=2, clock=Clock.STEP)
        for f in sorted(every)
    )
    for schedule in (FaultSchedule(events), FaultSchedule.permanent(every)):
        spec = MissionSpec(
            maze, route.start, route.goal, schedule=schedule, strategy="replacement",
            options=StrategyOptions(max_wait=4),
        )  # fmt: skip
        python, compiled = _both(spec)
        _same(python, compiled)
    assert compiled.status != "reached" and compiled.reason == python.reason


def _spec(**changes: Any) -> MissionSpec:
    maze = load_bundled("narrow-short")
    route = bundled_routes("narrow-short")[0]
    spec = MissionSpec(maze, route.start, route.goal)
    return dataclasses.replace(spec, **changes)


@NUMBA
def test_footings_that_the_compiled_loop_cannot_take_run_in_python() -> None:
    lookahead = _spec(strategy="lookahead", options=StrategyOptions(before=2))
    assert run_mission(lookahead).footing == "compiled"
    deferring = _spec(strategy="lookahead", options=StrategyOptions(recursion="primitive"))
    assert run_mission(deferring).footing == "python"
    primitive = _spec(options=StrategyOptions(recursion="primitive"))
    assert run_mission(primitive).footing == "compiled"
    event = FaultEvent(FAULTS[0], persistence=Persistence.INTERMITTENT, probability=0.5)
    intermittent = _spec(schedule=FaultSchedule((event,)))
    assert run_mission(intermittent).footing == "compiled"
    assert run_mission(dataclasses.replace(intermittent, seed=MAX_SEED + 1)).footing == "python"
    hidden = _spec(schedule=FaultSchedule.permanent(FAULTS[:1], detection=Detection.HIDDEN))
    assert run_mission(hidden).footing == "python"
    changing = _spec(world=WorldSchedule((WorldEvent((3, 3), at=2),)))
    assert run_mission(changing).footing == "python"
    assert run_mission(_spec()).footing == "compiled"
    assert run_mission(_spec(footing="python")).footing == "python"
    with pytest.raises(ProblemError, match="footing 'compiled' cannot run this mission: strategy"):
        run_mission(dataclasses.replace(_spec(strategy="dstar-lite"), footing="compiled"))
    with pytest.raises(ProblemError, match="footing must be"):
        _spec(footing="fast")


def test_row_says_which_footing_ran() -> None:
    row = mission_row(run_mission(_spec(footing="python", start=Pose(1, 1, Heading.E))))
    assert row["footing"] == "python"


SMALL = """\
name = "footings"
seed = 1
[[mazes]]
bundled = "narrow-short"
[faults]
sets = ["FL:F,RR:B"]
[[strategies]]
name = "replan"
[[strategies]]
name = "replacement"
tables = ["generated-indexed"]
recursion = ["guarded"]
"""


@NUMBA
def test_experiment_footing_option_chooses_the_loop_and_rows_say_which(tmp_path: Path) -> None:
    from selfrepair.cli import main

    config = tmp_path / "footings.toml"
    config.write_text(SMALL, encoding="utf-8")
    rows = {}
    for footing in ("python", "auto"):
        db = tmp_path / f"{footing}.sqlite"
        assert main(["experiment", str(config), "--jobs", "1", "--db", str(db),
                     "--footing", footing]) == 0  # fmt: skip
        rows[footing] = rows_of(db)
    assert {r["footing"] for r in rows["python"].values()} == {"python"}
    assert {r["footing"] for r in rows["auto"].values()} == {"compiled"}
    assert len(rows["python"]) == 8 and rows["python"].keys() == rows["auto"].keys()
    for key, row in rows["python"].items():
        assert {c: v for c, v in row.items() if c != "footing"} == {
            c: v for c, v in rows["auto"][key].items() if c != "footing"
        }
    assert main(["experiment", str(config), "--footing", "fast", "--db", str(db)]) == 2


@NUMBA
def test_a_replan_whose_heap_must_grow_gives_the_same_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    from selfrepair.search import _kernels

    monkeypatch.setattr(_kernels, "_FIRST_HEAP", 8)  # the kernel planner's first heap: 8 records
    clear_caches()
    maze = load_bundled("wide-long")
    route = bundled_routes("wide-long")[2]
    spec = MissionSpec(
        maze, route.start, route.goal, strategy="replan",
        schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FL:F,RR:B")),
    )  # fmt: skip
    python, compiled = _both(spec)
    _same(python, compiled)
    assert compiled.repairs[0].repair.expansions > 8
    clear_caches()
