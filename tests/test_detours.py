"""Local detours round cells believed blocked: the detour table (generated for any robot), the
compiled look-up against a plain reference, and missions that take detours instead of
replanning."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import selfrepair as sr
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.detours import MAX_WINDOW, DetourFinder, believed_free, find_detour
from selfrepair.tables.detours import detour_table
from selfrepair.world.events import WorldEvent, WorldSchedule
from selfrepair.world.maze import parse_maze
from test_world_events import swept_blocked

ROBOT = sr.get_domain("four-wheel")
ROOM = parse_maze("\n".join(["###########", *["#.........#"] * 7, "###########"]))


@pytest.mark.parametrize("name", ["four-wheel", "three-action"])
def test_every_candidate_ends_at_its_key_and_stays_in_the_window(name: str) -> None:
    domain = sr.get_domain(name)
    table = detour_table(domain)
    assert table.size() > len(table.entries) > 0
    for (h0, dx, dy, h1), candidates in table.entries.items():
        assert candidates, (h0, dx, dy, h1)
        for candidate, cells in zip(candidates, table.cells[(h0, dx, dy, h1)], strict=True):
            pose, swept = Pose(0, 0, Heading(h0)), set()
            for k in candidate:
                swept.update(domain.footprint(pose, table.actions[k]))
                pose = domain.apply(pose, table.actions[k])
            assert pose == Pose(dx, dy, Heading(h1))
            assert swept == cells
            assert max(max(abs(x), abs(y)) for x, y in swept) <= table.window
    straight = table.candidates((1, 2, 0, 1))  # east, two cells on, still east
    assert len(straight) >= 2 and {(1, 0)} <= table.cells[(1, 2, 0, 1)][0]
    assert any((1, 0) not in cells for cells in table.cells[(1, 2, 0, 1)])  # a way round


def reference(
    pose: Pose, queue: tuple[Any, ...], known: frozenset[Any], blocked: frozenset[Cell]
) -> tuple[int, tuple[Any, ...]] | None:
    """The detour rule written plainly: windows shortest first, each ending on a free cell with
    a next action that sweeps no blocked cell (a candidate window), the first valid candidate
    of the first window that has one; a candidate window ending beyond the table's radius ends
    the search."""
    table = detour_table(ROBOT)
    grid = ROOM.free_grid(4)
    free = believed_free(grid, blocked)
    end = pose
    for j in range(1, min(len(queue), MAX_WINDOW) + 1):
        end = ROBOT.apply(end, queue[j - 1])
        rx, ry = end.x - pose.x, end.y - pose.y
        if end.cell in blocked or not grid.is_free(*end.cell):
            continue
        if j < len(queue) and not free(ROBOT.footprint(end, queue[j])):
            continue
        if max(abs(rx), abs(ry)) > table.radius:
            return None
        found = find_detour(table, (pose.heading, rx, ry, end.heading), pose, known, free)
        if found is not None:
            return j, found[1]
    return None


def _on_the_room(pose: Pose, queue: tuple[Any, ...]) -> bool:
    """Whether every pose ``queue`` predicts from ``pose`` is on the room's grid (a planned
    queue's are)."""
    for action in queue:
        pose = ROBOT.apply(pose, action)
        if not (0 <= pose.x < ROOM.width and 0 <= pose.y < ROOM.height):
            return False
    return True


@settings(max_examples=150, deadline=None)
@given(
    x=st.integers(3, 7),
    y=st.integers(3, 5),
    heading=st.sampled_from(list(Heading)),
    actions=st.lists(st.sampled_from(ROBOT.actions), min_size=1, max_size=MAX_WINDOW + 2),
    cells=st.sets(st.tuples(st.integers(1, 9), st.integers(1, 7)), max_size=6),
    faults=st.sampled_from(["", "FL:F", "FR:B,RL:S"]),
    form=st.sampled_from(["tuple", "list", "iterator", "copies"]),
)
def test_the_compiled_detour_is_the_reference_on_any_queue(
    x: int,
    y: int,
    heading: Heading,
    actions: list[Any],
    cells: set[Cell],
    faults: str,
    form: str,
) -> None:
    """Any queue (mixed actions, windows that leave the radius, come back, end on walls or on
    blocked cells), given as a tuple, a list, a one-pass iterator (as the stepper's queue view
    iterates) or as equal copies of the domain's actions: the reference's answer, cold and
    warm."""
    pose = Pose(x, y, heading)
    queue = tuple(actions)
    if not _on_the_room(pose, queue):
        return
    known = frozenset(ROBOT.parse_faults(faults)) if faults else frozenset()
    first = ROBOT.footprint(pose, queue[0])
    blocked = (frozenset(cells) | set(first[1:])) - {pose.cell}  # the first action meets one
    finder = DetourFinder(ROBOT, ROOM.free_grid(4), lambda i, acts, j: (j, acts))
    expected = reference(pose, queue, known, blocked)
    for _ in range(2):
        given_queue: Any = {
            "tuple": queue,
            "list": list(queue),
            "iterator": iter(queue),
            "copies": tuple(dataclasses.replace(a) for a in queue),
        }[form]
        got = finder.find(pose, given_queue, known, blocked)
        assert got == expected
        if got is not None:
            assert all(ROBOT.available(a, known) for a in got[1])


def test_a_mission_takes_a_detour_round_a_blocked_cell() -> None:
    world = WorldSchedule((WorldEvent((4, 3), True, 0),))
    spec = sr.MissionSpec(ROOM, Pose(1, 3, Heading.E), (8, 3), world=world)
    result = sr.run_mission(spec)
    row = sr.mission_row(result)
    assert result.reached and row["detours"] == 1 and row["replans"] == 0
    assert (4, 3) not in {s.end.cell for s in result.steps}
    assert {s.source.value for s in result.steps} >= {"detour"}
    assert swept_blocked(result) == []
    replanned = sr.run_mission(sr.MissionSpec(ROOM, spec.start, spec.goal, strategy="replan",
                                              world=world))  # fmt: skip
    assert sr.mission_row(replanned)["replans"] == 1 and replanned.ticks <= result.ticks


def test_no_detour_in_a_corridor_means_a_replan() -> None:
    corridor = parse_maze("#########\n#.......#\n#########\n")
    world = WorldSchedule((WorldEvent((4, 1), True, 0), WorldEvent((4, 1), False, 6)))
    result = sr.run_mission(
        sr.MissionSpec(corridor, Pose(1, 1, Heading.E), (7, 1), world=world, max_steps=200)
    )
    attempts = [r.repair.attempts for r in result.repairs]
    assert attempts and attempts[0][0] == "detour" and "replan" in attempts[0]
    assert result.reached  # it waited for the cell to be free again
    assert swept_blocked(result) == []
