"""The wheel view of cooperative diagnosis: a teammate in range also reads which wheels turn and
which way (the effective command, ``Domain.effective``), each wheel misread at its noise rate."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.diagnosis import (
    FaultBelief,
    Observation,
    ObservationModel,
    ProbePlanner,
    fault_model,
)
from selfrepair.diagnosis.cooperative import (
    Observer,
    ObserverView,
    SensingRange,
    observer_streams,
    observer_team,
    team_observations,
)
from selfrepair.diagnosis.observation import actuators_of, read_actuators
from selfrepair.errors import ProblemError
from selfrepair.execution.executor import mission_context, run_mission, start_repairer
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.metrics import mission_row
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.world.bundled import bundled_routes, load_bundled
from selfrepair.world.maze import parse_maze

ROOM = parse_maze("\n".join(["." * 11] * 11) + "\n", name="room")
WHEELS = ObserverView.WHEELS
HIDDEN = Detection.HIDDEN


def _outcome(start: Pose, action: object, faults: frozenset[object]) -> tuple[Pose, object]:
    performed = FOUR_WHEEL.effective(action, faults)
    if not ROOM.free_grid(2).all_free(FOUR_WHEEL.footprint(start, performed)):
        return start, performed
    return FOUR_WHEEL.apply(start, performed), performed


def test_a_single_fault_is_isolated_in_one_command_with_the_wheel_view() -> None:
    # k = 1: FFFF under FL:F performs SFFF, under RL:F FFSF, the same arc: the pose cannot tell
    model = fault_model(FOUR_WHEEL, k=1)
    faults, action = FOUR_WHEEL.parse_faults("FL:F"), parse_action("FFFF")
    start = Pose(5, 5, Heading.N)
    end, performed = _outcome(start, action, faults)
    assert FOUR_WHEEL.format_action(performed) == "SFFF"
    beliefs = {}
    for view in ObserverView:
        observer = Observer("t1", 0.0, SensingRange(3), view)
        belief = FaultBelief(model, ROOM.free_grid(2))
        belief.update(Observation(0, action, start, end, False, False, 0.0))
        for seen in team_observations(0, action, start, end, False, (observer,),
                                      (Pose(4, 5, Heading.N),), observer_streams(0, (observer,)),
                                      performed=performed, domain=FOUR_WHEEL):  # fmt: skip
            belief.update(seen)
        beliefs[view] = belief
    assert len(beliefs[ObserverView.POSE].classes_alive()) == 2  # FL:F or RL:F
    wheels = beliefs[WHEELS]
    assert wheels.isolated() == model.class_of[model.sets.index(faults)]


def test_a_wheel_reading_weighs_by_its_noise_per_wheel() -> None:
    model = fault_model(FOUR_WHEEL, k=1)
    start, action = Pose(5, 5, Heading.N), parse_action("FFFF")
    end = FOUR_WHEEL.apply(start, parse_action("SFFF"))
    p = 0.1
    belief = FaultBelief(model)
    belief.update(Observation(0, action, start, end, None, False, p, "t1", parse_action("SFFB")))
    fl, rl = model.sets.index(FOUR_WHEEL.parse_faults("FL:F")), model.sets.index(
        FOUR_WHEEL.parse_faults("RL:F"))  # fmt: skip
    # FL:F performs SFFF: one wheel misread (RR); RL:F performs FFSF: three wheels misread
    want = ((1 - p) ** 3 * (p / 2)) / ((1 - p) * (p / 2) ** 3)
    got = (belief.weights[fl] / model.prior[fl]) / (belief.weights[rl] / model.prior[rl])
    assert got == pytest.approx(want)
    assert (belief.misses[fl], belief.misses[rl]) == (1.0, 3.0)


def test_actuator_readings_are_seeded_and_misread_at_the_rate() -> None:
    performed = parse_action("SFFF")
    assert read_actuators(FOUR_WHEEL, performed, 0.0, None) == performed
    import numpy as np

    def draws(seed: int) -> list[object]:
        rng = np.random.default_rng(seed)
        return [read_actuators(FOUR_WHEEL, performed, 0.2, rng) for _ in range(500)]

    assert draws(3) == draws(3) and draws(3) != draws(4)
    table = actuators_of(FOUR_WHEEL)
    wrong = sum(table.mismatches(FOUR_WHEEL.actions.index(r), FOUR_WHEEL.actions.index(performed))
                for r in draws(3))  # fmt: skip
    assert 0.15 < wrong / 2000 < 0.25
    with pytest.raises(ProblemError, match="declares no actuators"):
        actuators_of(THREE_ACTION)


def test_pose_readings_are_the_same_draws_under_either_view() -> None:
    start, action = Pose(5, 5, Heading.E), parse_action("FFFF")
    end = FOUR_WHEEL.apply(start, action)

    def ends(view: ObserverView) -> list[Pose]:
        observers = (Observer("t1", 0.3, SensingRange(3), view),)
        streams = observer_streams(5, observers)
        return [o.end for step in range(60)
                for o in team_observations(step, action, start, end, False, observers,
                                           (start,), streams, performed=action,
                                           domain=FOUR_WHEEL)]  # fmt: skip

    assert ends(ObserverView.POSE) == ends(WHEELS)
    with pytest.raises(ProblemError, match="wheel view needs"):
        team_observations(0, action, start, end, False, (Observer("t1", 0.0, view=WHEELS),),
                          (start,), observer_streams(0, (Observer("t1"),)))  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(
    faults=st.sampled_from(list(FOUR_WHEEL.fault_sets)),
    commands=st.lists(st.sampled_from(list(FOUR_WHEEL.actions)), min_size=1, max_size=6),
    offsets=st.lists(st.tuples(st.integers(-3, 3), st.integers(-3, 3)), min_size=1, max_size=3),
    heading=st.sampled_from(list(Heading)),
    noise=st.sampled_from([0.0, 0.05]),
)
def test_the_wheel_view_never_rules_out_the_truth(
    faults: frozenset[object],
    commands: list[object],
    offsets: list[tuple[int, int]],
    heading: Heading,
    noise: float,
) -> None:
    model = fault_model(FOUR_WHEEL)
    truth = model.sets.index(faults)
    observers = tuple(Observer(f"t{i}", noise, SensingRange(2), WHEELS)
                      for i in range(len(offsets)))  # fmt: skip
    streams = observer_streams(0, observers)
    belief = FaultBelief(model, ROOM.free_grid(2))
    pose = Pose(5, 5, heading)
    for step, action in enumerate(commands):
        end, performed = _outcome(pose, action, faults)
        poses = tuple(Pose(pose.x + dx, pose.y + dy, Heading.N) for dx, dy in offsets)
        for seen in team_observations(step, action, pose, end, False, observers, poses, streams,
                                      performed=performed, domain=FOUR_WHEEL):  # fmt: skip
            belief.update(seen)
        assert belief.alive >> truth & 1
        pose = end


def test_the_probe_planner_counts_wheel_readings() -> None:
    # FL:F or RL:F (k = 1): FFFF gives them the same arc; watched with the wheel view it tells
    model = fault_model(FOUR_WHEEL, k=1)
    belief = FaultBelief(model, ROOM.free_grid(2))
    pair = sum(1 << model.sets.index(FOUR_WHEEL.parse_faults(t)) for t in ("FL:F", "RL:F"))
    pose = Pose(5, 5, Heading.N)
    planner = ProbePlanner(model, belief.grid)
    wheels = ((Observer("t1", 0.0, SensingRange(3), WHEELS), Pose(5, 6, Heading.N)),)
    poses = ((Observer("t1", 0.0, SensingRange(3)), Pose(5, 6, Heading.N)),)
    a = model.index[parse_action("FFFF")]
    fl, rl = (model.class_of[model.sets.index(FOUR_WHEEL.parse_faults(t))]
              for t in ("FL:F", "RL:F"))  # fmt: skip
    planner.plan(belief, pose, pair, watchers=poses)
    assert planner.view(pose).label[a, fl] == planner.view(pose).label[a, rl]
    chosen = planner.plan(belief, pose, pair, watchers=wheels)
    assert planner.view(pose).label[a, fl] != planner.view(pose).label[a, rl]
    c = model.index[chosen]
    assert planner.view(pose).label[c, fl] != planner.view(pose).label[c, rl]


def _watched_repairer(noise: float) -> Any:
    spec = MissionSpec(
        ROOM, Pose(5, 5, Heading.N), (5, 1), strategy="active-diagnosis", seed=0,
        schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FR:B"), detection=HIDDEN),
        observation=ObservationModel(noise), observers=observer_team(2, noise, 3, WHEELS),
    )  # fmt: skip
    return start_repairer(spec, mission_context(spec, spec.options.resolved_table()))


def test_a_wheel_the_teammates_see_stalled_is_a_surprise_without_going_astray() -> None:
    # FBFB under FR:B performs FSFB, the same turn on the spot: the pose reading is as commanded
    start, turn = Pose(5, 5, Heading.N), parse_action("FBFB")
    end = FOUR_WHEEL.apply(start, turn)
    assert end == FOUR_WHEEL.apply(start, parse_action("FSFB"))
    own = Observation(0, turn, start, end, False, False, 0.01)
    stalled = Observation(0, turn, start, end, None, False, 0.01, "t1", parse_action("FSFB"))
    right = stalled._replace(source="t2", wheels=turn)
    repairer = _watched_repairer(0.01)
    repairer.observe(own, False, True, (stalled, right))  # one misread wheel: not yet evidence
    assert repairer.surprise_step is None and not repairer.assumption().known
    repairer = _watched_repairer(0.01)
    assert repairer.observe(own, False, True, (stalled, stalled._replace(source="t2")))
    assert repairer.surprise_step == 0  # confirmed: diagnosis starts, a probe comes next
    assert FOUR_WHEEL.parse_faults("FR:B") <= repairer.assumption().known


@pytest.mark.parametrize("noise", [0.0, 0.01])
def test_a_team_with_the_wheel_view_starts_diagnosing_at_the_turn_that_shows_the_fault(
    noise: float,
) -> None:
    # narrow-short's first route under FR:B,RL:S: its 7th command, FBFB, turns as commanded
    # (FSFB), so the robot alone is surprised only at the 14th; its watched twin was never
    # surprised, and never isolated, before the wheel readings could start diagnosis
    route = bundled_routes("narrow-short")[0]
    rows = {}
    for count in (0, 2):
        spec = MissionSpec(
            load_bundled("narrow-short"), route.start, route.goal, strategy="active-diagnosis",
            schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults("FR:B,RL:S"),
                                             detection=HIDDEN),
            seed=3, observation=ObservationModel(noise),
            observers=observer_team(count, noise, 3, WHEELS) if count else (),
        )  # fmt: skip
        rows[count] = mission_row(run_mission(spec))
    assert rows[0]["surprise_step"] == 13 and rows[2]["surprise_step"] == 6
    for row in rows.values():
        assert row["reached"] == 1 and row["isolated_right"] == 1
    assert rows[2]["isolation_actions"] < rows[0]["isolation_actions"]
