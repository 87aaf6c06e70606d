"""Diagnosis from observed motion: observations, hypotheses and classes, the belief, probes."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.diagnosis import (
    FaultBelief,
    Observation,
    ObservationModel,
    best_probe,
    fault_model,
    perturbed,
)
from selfrepair.errors import ProblemError
from selfrepair.execution.faults import Detection, FaultSchedule
from selfrepair.execution.simulator import Outcome, Simulator
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import FaultBehaviour
from selfrepair.robots.four_wheel import FOUR_WHEEL, parse_action
from selfrepair.robots.three_action import THREE_ACTION
from selfrepair.world.maze import Maze, parse_maze

OPEN = parse_maze("\n".join(["." * 9] * 9) + "\n", name="open")
MODEL = fault_model(FOUR_WHEEL)
CENTRE = Pose(4, 4, Heading.N)


def _observe(faults: str, code: str, start: Pose = CENTRE) -> Observation:
    action = parse_action(code)
    performed = FOUR_WHEEL.effective(action, FOUR_WHEEL.parse_faults(faults))
    return Observation(0, action, start, FOUR_WHEEL.apply(start, performed))


def _index(faults: str) -> int:
    return MODEL.sets.index(FOUR_WHEEL.parse_faults(faults))


def test_the_hypotheses_are_none_then_the_fault_sets_up_to_k() -> None:
    assert MODEL.size == 79 and MODEL.sets[0] == frozenset()
    assert MODEL.sets[1:] == FOUR_WHEEL.fault_sets
    assert fault_model(FOUR_WHEEL, k=1).size == 13
    assert abs(float(MODEL.prior.sum()) - 1.0) < 1e-12
    assert MODEL.prior[0] > MODEL.prior[1] > MODEL.prior[13]  # none, a single, a double
    # under every shipped model each hypothesis of the four-wheel robot is its own class
    for name in FOUR_WHEEL.behaviour_names():
        assert len(fault_model(FOUR_WHEEL, name).classes) == 79


def test_hypotheses_that_behave_alike_everywhere_are_one_class() -> None:
    def harmless(action: str, faults: frozenset[str]) -> str:
        return action  # a fault that changes nothing the robot can see

    def turns(action: str, faults: frozenset[str]) -> str:
        return "L" if action == "R" else action  # a forbidden right turn turns left

    unseen = replace(THREE_ACTION, name="unseen", behaviours=(FaultBehaviour("h", "", harmless),))
    model = fault_model(unseen)
    assert model.size == 7 and model.classes == (model.all,)
    lefty = replace(THREE_ACTION, name="lefty", behaviours=(FaultBehaviour("t", "", turns),))
    model = fault_model(lefty)
    # a forbidden F or L still does what it should; a forbidden R turns left
    assert [model.describe(c) for c in model.classes] == ["none | F | L | F,L", "R | F,R | L,R"]


def test_front_wheels_and_rear_wheels_of_one_side_need_a_specific_action() -> None:
    belief = FaultBelief(MODEL)
    belief.update(_observe("FL:F", "FFFF"))  # SFFF and FFSF: the same arc to the left
    alive = belief.alive
    assert alive >> _index("FL:F") & 1 and alive >> _index("RL:F") & 1
    assert not alive & 1  # "none" would have gone straight
    assert MODEL.class_of[_index("FL:F")] != MODEL.class_of[_index("RL:F")]
    belief.update(_observe("FL:F", "FSSS"))  # FL:F: a wait; RL:F: FSSS itself, a right turn
    assert belief.alive >> _index("FL:F") & 1 and not belief.alive >> _index("RL:F") & 1
    other = FaultBelief(MODEL)
    other.update(_observe("RL:F", "FFFF"))
    other.update(_observe("RL:F", "FSSS"))
    assert other.alive >> _index("RL:F") & 1 and not other.alive >> _index("FL:F") & 1


def test_a_probe_splits_what_the_plan_could_not() -> None:
    belief = FaultBelief(MODEL)
    start = Pose(4, 4, Heading.N)
    belief.update(_observe("FL:F", "FFFF", start))
    probe = best_probe(belief, start)
    assert probe is not None and probe.information > 0
    before = len(belief.classes_alive())
    for action in probe.actions:
        belief.update(_observe("FL:F", action.code, start))
    assert len(belief.classes_alive()) < before
    for _ in range(6):  # keep probing: the true class is isolated
        probe = best_probe(belief, start)
        if probe is None:
            break
        for action in probe.actions:
            belief.update(_observe("FL:F", action.code, start))
    assert belief.isolated() == MODEL.class_of[_index("FL:F")]
    assert best_probe(belief, start) is None


def test_a_bump_is_an_observation_too() -> None:
    corridor = parse_maze("#####\n##.##\n##.##\n##.##\n#####\n", name="corridor")
    grid = corridor.free_grid(2)
    start = Pose(2, 3, Heading.N)
    with_switch, without = FaultBelief(MODEL, grid), FaultBelief(MODEL, grid)
    seen = Observation(0, parse_action("FFFF"), start, start, bumped=True)
    with_switch.update(seen)
    without.update(seen._replace(bumped=None))
    # the arc of FL:F sweeps the wall: the robot stays; a fault-free robot would have moved
    assert with_switch.alive >> _index("FL:F") & 1 and not with_switch.alive & 1
    assert without.alive >> _index("FL:F") & 1 and not without.alive & 1
    assert with_switch.alive == without.alive  # no hypothesis performs a wait for FFFF


def test_noisy_readings_never_rule_out_the_truth_by_one_wrong_reading() -> None:
    belief = FaultBelief(MODEL)
    truth = _observe("FL:F", "FFFF")
    wrong = truth._replace(end=perturbed(truth.end)[2], noise=0.05)
    belief.update(wrong)
    assert belief.alive >> _index("FL:F") & 1
    for _ in range(5):
        belief.update(truth._replace(noise=0.05))
    best, faults = belief.most_probable()
    assert best == MODEL.class_of[_index("FL:F")] or faults == FOUR_WHEEL.parse_faults("RL:F")
    assert belief.posterior()[_index("FL:F")] > 0.3


def test_an_impossible_observation_changes_nothing() -> None:
    belief = FaultBelief(fault_model(FOUR_WHEEL, k=0))  # only "none"
    belief.update(_observe("FL:F", "FFFF"))
    assert belief.alive == 1 and belief.inexplicable == 1


def test_the_observation_model() -> None:
    with pytest.raises(ProblemError, match="noise rate"):
        ObservationModel(noise=0.7)
    start, end = Pose(1, 1, Heading.N), Pose(1, 0, Heading.N)
    exact = ObservationModel(bumps=True).read(3, "a", start, end, False, False, None)
    assert exact == Observation(3, "a", start, end, False, False, 0.0, "self")
    noisy = ObservationModel(noise=0.3)
    readings = [
        noisy.read(0, "a", start, end, False, False, np.random.default_rng([7, 24])).end
        for _ in range(1)
    ]
    rng = np.random.default_rng([7, 24])
    many = [noisy.read(0, "a", start, end, False, False, rng).end for _ in range(2000)]
    wrong = [r for r in many if r != end]
    assert set(wrong) <= set(perturbed(end)) and 450 < len(wrong) < 750
    assert readings[0] == many[0]  # seeded: the same generator state gives the same reading
    assert len(set(perturbed(end))) == 7 and end not in perturbed(end)
    with pytest.raises(ProblemError, match="random generator"):
        noisy.read(0, "a", start, end, False, False, None)


def _random_maze(seed: int) -> Maze:
    rng = np.random.default_rng(seed)
    walls = rng.random((7, 7)) < 0.25
    walls[3, 3] = False
    return Maze(walls, name=f"random-{seed}")


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    hypothesis=st.integers(0, MODEL.size - 1),
    commands=st.lists(st.integers(0, len(FOUR_WHEEL.actions) - 1), min_size=1, max_size=12),
    heading=st.sampled_from(list(Heading)),
    bumps=st.booleans(),
    behaviour=st.sampled_from(FOUR_WHEEL.behaviour_names()),
)
def test_exact_observations_never_rule_out_the_truth(
    seed: int, hypothesis: int, commands: list[int], heading: Heading, bumps: bool,
    behaviour: str,
) -> None:  # fmt: skip
    maze = _random_maze(seed)
    faults = MODEL.sets[hypothesis]
    schedule = FaultSchedule.permanent(faults, detection=Detection.HIDDEN)
    sim = Simulator(
        FOUR_WHEEL, maze, Pose(3, 3, heading), schedule, behaviour=behaviour,
        observation=ObservationModel(bumps=bumps),
    )  # fmt: skip
    belief = FaultBelief(fault_model(FOUR_WHEEL, behaviour), maze.free_grid(2))
    for step, index in enumerate(commands):
        start, action = sim.pose, FOUR_WHEEL.actions[index]
        outcome = sim.advance(action)
        assert outcome in (Outcome.MOVED, Outcome.BUMPED)
        belief.update(sim.observe(step, action, start, outcome))
        assert belief.alive >> hypothesis & 1
    assert belief.inexplicable == 0
