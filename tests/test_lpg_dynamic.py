"""LPG-adapt in a changing world: told the believed-blocked cells (as walls of the map its
problem is posed on), asked for blocked actions as for faulty ones, and never sweeping a cell
blocked at that time."""

from __future__ import annotations

import selfrepair as sr
import selfrepair.baselines  # registers lpg-adapt
from extras import LPG
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.world.events import WorldEvent, WorldSchedule
from selfrepair.world.maze import believed_maze, parse_maze
from test_world_events import swept_blocked

ROOM = parse_maze("\n".join(["#########", *["#.......#"] * 3, "#########"]))


def test_the_believed_maze_has_the_cells_as_walls() -> None:
    walled = believed_maze(ROOM, frozenset({(3, 2), (0, 0), (40, 40)}))
    assert not walled.is_free(3, 2) and ROOM.is_free(3, 2)
    assert walled.free_cells() == [c for c in ROOM.free_cells() if c != (3, 2)]


@LPG
def test_lpg_adapt_is_asked_for_a_blocked_action_and_goes_round_it() -> None:
    world = WorldSchedule((WorldEvent((4, 2), True, 1),))
    spec = sr.MissionSpec(
        ROOM,
        Pose(1, 2, Heading.E),
        (7, 2),
        strategy="lpg-adapt",
        world=world,
        options=StrategyOptions(lpg_time_limit_s=20),
    )
    result = sr.run_mission(spec)
    assert result.reached and swept_blocked(result) == []
    attempts = [r.repair.attempts for r in result.repairs]
    assert attempts and str(attempts[0][0]).startswith("lpg-adapt")  # not a plain replan
    assert (4, 2) not in {s.end.cell for s in result.steps if s.end.cell != s.start.cell}
