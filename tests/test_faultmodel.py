"""Fault schedules and the simulator that holds the true faults."""

from __future__ import annotations

from fractions import Fraction

import pytest

from selfrepair.errors import InputError
from selfrepair.execution.faults import FaultEvent, FaultSchedule
from selfrepair.execution.simulator import Simulator
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.maze import parse_maze

FLF = four_wheel.parse_fault("FL:F")
RRB = four_wheel.parse_fault("RR:B")
CORRIDOR = parse_maze("#####\n#...#\n#####")


def test_permanent_faults_start_at_their_step() -> None:
    schedule = FaultSchedule.permanent([RRB, FLF], at=3)
    assert [e.fault for e in schedule.events] == [FLF, RRB]
    assert schedule.active_faults(2, Fraction(10)) == frozenset()
    assert schedule.active_faults(3, Fraction(0)) == {FLF, RRB}
    assert schedule.active_faults(1000, Fraction(0)) == {FLF, RRB}


def test_tick_clock_and_transient_window() -> None:
    event = FaultEvent(FLF, at=2, clock="tick", persistence="transient", duration=3)
    schedule = FaultSchedule((event,))
    active = [bool(schedule.active_faults(0, Fraction(t, 2))) for t in range(0, 14)]
    # ticks 0, 0.5, ..., 6.5: active for 2 <= t < 5
    assert active == [t >= 4 and t < 10 for t in range(0, 14)]


def test_intermittent_faults_are_seeded_and_have_their_rate() -> None:
    schedule = FaultSchedule((FaultEvent(FLF, persistence="intermittent", probability=0.3),))
    draws = [bool(schedule.active_faults(k, Fraction(0), seed=7)) for k in range(2000)]
    again = [bool(schedule.active_faults(k, Fraction(0), seed=7)) for k in range(2000)]
    other = [bool(schedule.active_faults(k, Fraction(0), seed=8)) for k in range(2000)]
    assert draws == again and draws != other
    assert 0.25 < sum(draws) / len(draws) < 0.35


@pytest.mark.parametrize(
    "kwargs",
    [
        {"persistence": "sometimes"},
        {"clock": "moon"},
        {"at": -1},
        {"persistence": "transient"},
        {"persistence": "intermittent", "probability": 1.5},
    ],
)
def test_bad_events_raise(kwargs: dict[str, object]) -> None:
    with pytest.raises(InputError):
        FaultEvent(FLF, **kwargs)  # type: ignore[arg-type]


def test_schedule_json_round_trips() -> None:
    schedule = FaultSchedule(
        (
            FaultEvent(FLF, at=4, clock="tick", persistence="transient", duration=2),
            FaultEvent(RRB, persistence="intermittent", probability=0.25),
        ),
        detection="on-use",
    )
    assert FaultSchedule.from_json(schedule.to_json(FOUR_WHEEL), FOUR_WHEEL) == schedule
    assert "detected on-use" in schedule.describe()
    with pytest.raises(InputError):
        FaultSchedule(detection="psychic")


def test_simulator_moves_with_the_robot_model() -> None:
    sim = Simulator(FOUR_WHEEL, CORRIDOR, Pose(1, 1, Heading.E), FaultSchedule())
    outcome = sim.execute(four_wheel.parse_action("FFSS"))
    assert outcome.status == "moved" and outcome.end == Pose(2, 1, Heading.E)
    assert sim.pose == outcome.end and sim.steps == 1 and sim.ticks == 2


def test_failed_attempt_stays_put_costs_one_tick_and_names_the_fault() -> None:
    sim = Simulator(
        FOUR_WHEEL,
        CORRIDOR,
        Pose(1, 1, Heading.E),
        FaultSchedule.permanent([FLF, RRB], detection="on-use"),
    )
    assert sim.sense() == frozenset()
    assert sim.true_faults() == {FLF, RRB}
    outcome = sim.execute(four_wheel.parse_action("FFFF"))
    assert outcome.status == "failed-attempt" and outcome.blocking == {FLF}
    assert sim.pose == Pose(1, 1, Heading.E) and sim.ticks == 1 and sim.steps == 1


def test_detection_now_senses_the_active_faults() -> None:
    sim = Simulator(
        FOUR_WHEEL, CORRIDOR, Pose(1, 1, Heading.E), FaultSchedule.permanent([FLF], at=1)
    )
    assert sim.sense() == frozenset()
    sim.execute(four_wheel.parse_action("BFBF"))
    assert sim.sense() == {FLF}


def test_collision_is_refused() -> None:
    sim = Simulator(FOUR_WHEEL, CORRIDOR, Pose(1, 1, Heading.N), FaultSchedule())
    outcome = sim.execute(four_wheel.parse_action("FFFF"))
    assert outcome.status == "collision" and sim.pose == Pose(1, 1, Heading.N) and sim.steps == 0
