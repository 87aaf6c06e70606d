"""The reservation table (team/reservations.py) against a brute-force model: a Hypothesis
property drives random reserve/release/forget operations, each reservation made only where
``free`` says the cells are free (as the engine does), and checks that no two robots ever hold one
cell at overlapping times, that ``clear_after`` gives the earliest free start, and that the
table's answers agree with the model's."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.geometry import Cell
from selfrepair.team.reservations import FOREVER, Reservations

ROBOTS = ("a", "b", "c")
CELLS = [(x, 0) for x in range(4)]

Operation = tuple[str, str, tuple[Cell, ...], int, int]
operations = st.lists(
    st.tuples(
        st.sampled_from(["reserve", "park", "release", "forget"]),
        st.sampled_from(ROBOTS),
        st.lists(st.sampled_from(CELLS), min_size=1, max_size=2, unique=True).map(tuple),
        st.integers(0, 30),
        st.integers(1, 8),
    ),
    max_size=40,
)


def _overlaps(table: Reservations) -> list[tuple[Cell, str, str]]:
    found = []
    held = [(c, s, e, r) for r in ROBOTS for c, s, e in table.of_robot(r)]
    for i, (c1, s1, e1, r1) in enumerate(held):
        for c2, s2, e2, r2 in held[i + 1 :]:
            if c1 == c2 and r1 != r2 and s1 < e2 and s2 < e1:
                found.append((c1, r1, r2))
    return found


@settings(max_examples=200, deadline=None)
@given(operations)
def test_reservations_never_overlap_and_answer_like_a_model(ops: list[Operation]) -> None:
    table = Reservations()
    for kind, robot, cells, start, length in ops:
        end = start + length
        if kind == "reserve" and table.free(cells, start, end, robot):
            table.reserve(robot, cells, start, end)
        elif kind == "park" and table.free(cells[:1], start, FOREVER, robot):
            table.park(robot, cells[0], start)
        elif kind == "release":
            table.release_from(robot, start)
            assert all(s < start and e <= start for _, s, e in table.of_robot(robot))
        elif kind == "forget":
            table.forget_before(start)
            assert all(e > start for r in ROBOTS for _, _, e in table.of_robot(r))
        assert _overlaps(table) == []
    # the queries agree with a brute-force reading of the held intervals
    held = [(c, s, e, r) for r in ROBOTS for c, s, e in table.of_robot(r)]
    for robot in ROBOTS:
        for cell in CELLS:
            for start in range(0, 40, 3):
                end = start + 2
                busy = any(
                    c == cell and r != robot and s < end and start < e for c, s, e, r in held
                )
                assert table.free((cell,), start, end, robot) is not busy
                t = table.clear_after((cell,), start, end, robot)
                assert t >= start and (t == FOREVER or table.free((cell,), t, t + 2, robot))
                assert all(
                    not table.free((cell,), u, u + 2, robot) for u in range(start, min(t, 60))
                )
        mine = {(c, s, e) for c, s, e in table.of_robot(robot)}
        others = {
            r for c, s, e, r in held if r != robot and any(
                c == c2 and s < e2 and s2 < e for c2, s2, e2 in mine
            )
        }  # fmt: skip
        assert table.conflicting_robots(robot) == others == set()


def test_half_open_intervals_let_one_robot_follow_another() -> None:
    table = Reservations()
    table.reserve("a", [(0, 0)], 0, 3)
    assert table.free([(0, 0)], 3, 6, "b") and not table.free([(0, 0)], 2, 4, "b")
    assert table.clear_after([(0, 0)], 1, 3, "b") == 3
    table.park("a", (0, 0), 5)
    assert table.clear_after([(0, 0)], 4, 6, "b") == FOREVER
    table.release_from("a", 5)
    assert table.clear_after([(0, 0)], 4, 6, "b") == 4
