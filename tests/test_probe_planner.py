"""Active diagnosis's probe plans (``ProbePlanner``, ``isolating_probe``) and the confirmation
rule for isolation under noise (``FaultBelief.contenders`` / ``isolated``): hand-made cases with
known answers."""

from __future__ import annotations

import pytest

from selfrepair.diagnosis import (
    FaultBelief,
    Observation,
    ProbePlanner,
    fault_model,
    isolating_probe,
)
from selfrepair.diagnosis.belief import CONFIRMATIONS, predictions
from selfrepair.geometry import FreeGrid, Heading, Pose
from selfrepair.robots.four_wheel import FOUR_WHEEL, SINGLE_FAULTS, parse_action
from selfrepair.world.maze import parse_maze

MODEL = fault_model(FOUR_WHEEL)
CENTRE = Pose(6, 6, Heading.N)
OPEN = parse_maze("\n".join(["." * 13] * 13) + "\n", name="open")


def _true_end(faults: frozenset[object], code: str, start: Pose, grid: FreeGrid | None) -> Pose:
    performed = FOUR_WHEEL.effective(parse_action(code), faults)
    if grid is not None and not grid.all_free(FOUR_WHEEL.footprint(start, performed)):
        return start  # a bump
    return FOUR_WHEEL.apply(start, performed)


def _isolate(faults: frozenset[object], first: str, grid: FreeGrid | None) -> tuple[int, int]:
    """Commands after the surprise ``first`` until one class is left (probing each time), and
    the bumps on the way."""
    belief = FaultBelief(MODEL, grid)
    planner = ProbePlanner(MODEL, grid)
    end = _true_end(faults, first, CENTRE, grid)
    belief.update(Observation(0, parse_action(first), CENTRE, end, end == CENTRE))
    pose, commands, bumps = end, 0, 0
    while belief.isolated() is None:
        probe = isolating_probe(belief, pose, planner=planner)
        assert probe is not None
        for action in probe.actions:
            end = _true_end(faults, action.code, pose, grid)
            moved = FOUR_WHEEL.apply(pose, FOUR_WHEEL.effective(action, faults))
            bumped = end == pose and moved != pose
            belief.update(Observation(commands + 1, action, pose, end, bumped))
            commands, bumps, pose = commands + 1, bumps + bumped, end
        assert commands <= 6
    return commands, bumps


@pytest.mark.parametrize("first", ["FFFF", "SSSS", "BBBB"])
def test_every_single_fault_is_isolated_within_three_probes_in_open_space(first: str) -> None:
    # known answer: an exhaustive search over adaptive plans (every command, every outcome)
    # isolates each single fault from the 78 fault sets within 3 commands after these surprises
    for fault in SINGLE_FAULTS:
        faults = frozenset({fault})
        if _true_end(faults, first, CENTRE, None) == FOUR_WHEEL.apply(CENTRE, parse_action(first)):
            continue  # no surprise
        commands, bumps = _isolate(faults, first, OPEN.free_grid(2))
        assert commands <= 3, (str(fault), first, commands)
        assert bumps == 0  # in open space nothing is hit


def test_probes_avoid_walls_when_a_safe_split_exists() -> None:
    corridor = parse_maze("\n".join(["#.#"] * 9) + "\n", name="corridor")
    grid = corridor.free_grid(2)
    start = Pose(1, 4, Heading.N)
    belief = FaultBelief(MODEL, grid)
    faults = FOUR_WHEEL.parse_faults("FL:F")
    end = _true_end(faults, "FFFF", start, grid)
    assert end == start  # the arc to the left hits the corridor's wall: a bump
    belief.update(Observation(0, parse_action("FFFF"), start, end, True))
    probe = isolating_probe(belief, start)
    assert probe is not None and len(probe.actions) == 1
    a = MODEL.index[probe.actions[0]]
    for group, (_, bumps, _) in predictions(MODEL, a, start, grid):
        if group.mask & belief.alive:
            assert not bumps, (probe.actions[0], MODEL.describe(group.mask & belief.alive))


def test_nothing_to_probe_once_one_class_is_left() -> None:
    belief = FaultBelief(MODEL)
    belief.alive = 1 << MODEL.sets.index(FOUR_WHEEL.parse_faults("FL:F"))
    assert isolating_probe(belief, CENTRE) is None
    assert ProbePlanner(MODEL, None).plan(belief, CENTRE) is None


def test_two_hypotheses_one_command_apart_are_split_by_one_command() -> None:
    belief = FaultBelief(MODEL)
    fl, rl = (MODEL.sets.index(FOUR_WHEEL.parse_faults(f)) for f in ("FL:F", "RL:F"))
    mask = 1 << fl | 1 << rl
    action = ProbePlanner(MODEL, None).plan(belief, CENTRE, mask, depth=2)
    assert action is not None
    assert MODEL.performed[fl][MODEL.index[action]] != MODEL.performed[rl][MODEL.index[action]]


def _noisy(code: str, start: Pose, end: Pose, noise: float = 0.01) -> Observation:
    return Observation(0, parse_action(code), start, end, False, False, noise)


def _none_or_fl_s() -> FaultBelief:
    """A belief down to "none" and FL:S: ``SSSS`` waits under "none" and turns right under FL:S
    (``FSSS``), readings one perturbation apart (same cell, another heading)."""
    belief = FaultBelief(MODEL)
    belief.alive = 1 | 1 << MODEL.sets.index(FOUR_WHEEL.parse_faults("FL:S"))
    return belief


def test_one_reading_never_isolates_a_class_under_noise_a_second_confirms_it() -> None:
    belief = _none_or_fl_s()
    wait, turned = CENTRE, Pose(CENTRE.x, CENTRE.y, Heading.E)
    belief.update(_noisy("SSSS", CENTRE, wait))
    assert belief.class_posterior()[0] > 0.99  # the mass alone would isolate "none"
    assert belief.isolated(0.01) is None  # one reading: not confirmed
    assert belief.contenders(0.01) == belief.alive
    for _ in range(CONFIRMATIONS - 1):
        belief.update(_noisy("SSSS", CENTRE, wait))
    assert belief.isolated(0.01) == 0 and belief.contenders(0.01) == 1
    assert belief.isolated(0.0) is None  # exact isolation: FL:S is still possible
    # a wrong reading after that puts the rival back in the running
    belief.update(_noisy("SSSS", CENTRE, turned))
    assert belief.isolated(0.01) is None


def test_exact_readings_isolate_as_before() -> None:
    belief = _none_or_fl_s()
    belief.update(Observation(0, parse_action("SSSS"), CENTRE, CENTRE))
    assert belief.alive == 1 and belief.isolated(0.01) == 0 and belief.isolated() == 0
