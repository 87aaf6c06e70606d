"""Cooperative diagnosis (issue 24 item 5): teammates in sensing range add readings to the
faulty robot's belief (selfrepair.diagnosis.cooperative)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.diagnosis import FaultBelief, Observation, fault_model
from selfrepair.diagnosis.cooperative import (
    Metric,
    Observer,
    SensingRange,
    observer_streams,
    team_observations,
)
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action
from selfrepair.world.maze import parse_maze

ROOM = parse_maze("\n".join(["." * 11] * 11) + "\n", name="room")


def _outcome(start: Pose, action: object, faults: frozenset[object]) -> tuple[Pose, bool]:
    performed = FOUR_WHEEL.effective(action, faults)
    end = FOUR_WHEEL.apply(start, performed)
    if not ROOM.free_grid(2).all_free(FOUR_WHEEL.footprint(start, performed)):
        return start, True
    return end, False


def test_ranges_chebyshev_and_manhattan() -> None:
    cheb, manh = SensingRange(2), SensingRange(2, Metric.MANHATTAN)
    assert cheb.sees((0, 0), (2, 2)) and not manh.sees((0, 0), (2, 2))
    assert manh.sees((0, 0), (1, 1)) and manh.sees((0, 0), (0, -2))
    assert not cheb.sees((0, 0), (3, 0))
    with pytest.raises(ProblemError):
        SensingRange(-1)
    with pytest.raises(ProblemError):
        Observer("self")
    with pytest.raises(ProblemError):
        Observer("t1", noise=0.7)


def test_in_range_observer_isolates_like_an_exact_self_reading() -> None:
    # FL:F under the default stall model: commanded FFFF performs SFFF, an arc (as RL:F does).
    model = fault_model(FOUR_WHEEL)
    faults = FOUR_WHEEL.parse_faults("FL:F")
    action = parse_action("FFFF")
    start = Pose(5, 5, Heading.N)
    end, _ = _outcome(start, action, faults)
    assert end != FOUR_WHEEL.apply(start, action)  # the robot went astray
    near = Observer("t1", 0.0, SensingRange(2))
    far = Observer("t2", 0.0, SensingRange(2, Metric.MANHATTAN))
    poses = (Pose(6, 6, Heading.W), Pose(7, 6, Heading.W))  # t2: Manhattan 3 from start
    seen = team_observations(0, action, start, end, False, (near, far), poses,
                             observer_streams(0, (near, far)))  # fmt: skip
    assert [o.source for o in seen] == ["t1"]
    assert seen[0].end == end and seen[0].bumped is None and seen[0].noise == 0.0
    team = FaultBelief(model, ROOM.free_grid(2))
    team.update(seen[0])
    alone = FaultBelief(model, ROOM.free_grid(2))
    alone.update(Observation(0, action, start, end, None, False, 0.0))
    assert team.alive == alone.alive
    survivors = model.faults_of(team.alive)
    assert faults in survivors and frozenset() not in survivors
    assert FOUR_WHEEL.parse_faults("RL:F") in survivors  # the same arc: FFFF cannot tell them
    # nobody in range: nothing reaches the belief
    nobody = team_observations(0, action, start, end, False, (far,), (poses[1],),
                               observer_streams(0, (far,)))  # fmt: skip
    assert nobody == ()


def test_observer_mismatch_raises() -> None:
    with pytest.raises(ProblemError, match="one pose and one stream"):
        team_observations(0, parse_action("FFFF"), Pose(1, 1, Heading.N), Pose(1, 0, Heading.N),
                          False, (Observer("t1"),), (), ())  # fmt: skip


def test_same_seed_same_readings() -> None:
    observers = (Observer("t1", 0.3), Observer("t2", 0.3))
    start, action = Pose(5, 5, Heading.E), parse_action("FFFF")
    end = FOUR_WHEEL.apply(start, action)
    poses = (Pose(5, 6, Heading.N), Pose(4, 5, Heading.N))

    def run(seed: int) -> list[Observation]:
        streams = observer_streams(seed, observers)
        return [o for step in range(40)
                for o in team_observations(step, action, start, end, False, observers, poses,
                                           streams)]  # fmt: skip

    assert run(7) == run(7)
    assert run(7) != run(8)  # 80 readings at 30% noise: some differ
    # independent streams: the two observers' readings are not the same draws
    both = run(7)
    assert [o.end for o in both[0::2]] != [o.end for o in both[1::2]]


@settings(max_examples=60, deadline=None)
@given(
    faults=st.sampled_from(list(FOUR_WHEEL.fault_sets)),
    commands=st.lists(st.sampled_from(list(FOUR_WHEEL.actions)), min_size=1, max_size=6),
    offsets=st.lists(st.tuples(st.integers(-3, 3), st.integers(-3, 3)), min_size=1, max_size=3),
    heading=st.sampled_from(list(Heading)),
)
def test_exact_observers_never_rule_out_the_truth(
    faults: frozenset[object],
    commands: list[object],
    offsets: list[tuple[int, int]],
    heading: Heading,
) -> None:
    model = fault_model(FOUR_WHEEL)
    truth = model.sets.index(faults)
    observers = tuple(Observer(f"t{i}", 0.0, SensingRange(2)) for i in range(len(offsets)))
    streams = observer_streams(0, observers)
    belief = FaultBelief(model, ROOM.free_grid(2))
    pose = Pose(5, 5, heading)
    for step, action in enumerate(commands):
        end, _ = _outcome(pose, action, faults)
        poses = tuple(Pose(pose.x + dx, pose.y + dy, Heading.N) for dx, dy in offsets)
        for seen in team_observations(step, action, pose, end, False, observers, poses, streams):
            belief.update(seen)
        assert belief.alive >> truth & 1
        pose = end
