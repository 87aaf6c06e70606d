"""Team scenario files: read by the same TOML/pydantic machinery as experiment files, so a key
of the wrong type is one line naming file, line and expectation (exit 2); hand-made scenarios
with known contents; random scenarios are deterministic and always pass the checks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.errors import ConfigError, InputError
from selfrepair.team.check import check_scenario
from selfrepair.team.grid import components, grid_distances, largest_area
from selfrepair.team.model import TeamFaultKind, Trigger
from selfrepair.team.randomteam import GripperMix, random_scenario
from selfrepair.team.scenario import parse_scenario, resolve_scenario, scenario_digest
from selfrepair.world.bundled import resolve_maze
from selfrepair.world.maze import parse_maze

SCENARIO = """name = "mine"
maze = "wide-short"

[[robots]]
name = "r1"
start = "1,1,E"

[[robots]]
name = "r2"
start = "22,13,W"
gripper = false

[[tasks]]
item = "i1"
pickup = "5,4"
dropoff = "16,1"

[[faults]]
kind = "gripper"
robot = "r2"
at = 4
"""


def _error(text: str) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        parse_scenario(text, source="s.toml")
    return info.value


def test_a_hand_made_scenario_reads_as_written() -> None:
    scenario = parse_scenario(SCENARIO, source="s.toml")
    assert scenario.name == "mine" and scenario.maze.name == "wide-short"
    assert [(r.name, str(r.start), r.gripper) for r in scenario.robots] == [
        ("r1", "1,1,E", True),
        ("r2", "22,13,W", False),
    ]
    assert [(t.item, t.pickup, t.dropoff) for t in scenario.tasks] == [("i1", (5, 4), (16, 1))]
    (fault,) = scenario.faults
    assert (fault.kind, fault.robot, fault.at, fault.trigger) == (
        TeamFaultKind.GRIPPER,
        "r2",
        4,
        Trigger.TICK,
    )
    assert scenario.table == "" and scenario.digest == scenario_digest(SCENARIO)
    assert scenario.without_faults().faults == () and not scenario.without_faults().digest


@pytest.mark.parametrize(
    ("old", "new", "line", "expected"),
    [
        ('name = "mine"', "name = 5", 1, "key 'name': expected a valid string (got 5)"),
        ('maze = "wide-short"', "maze = 3", 2, "key 'maze': expected a valid string"),
        ('name = "mine"', "seed = true", 1, "key 'seed': expected a valid integer"),
        ('name = "mine"', "seed = -1", 1, "key 'seed': expected greater than or equal to 0"),
        ("gripper = false", 'gripper = "no"', 11, "key 'robots[1].gripper': expected a valid bool"),
        ('start = "22,13,W"', "start = 7", 10, "key 'robots[1].start': expected a valid string"),
        ('item = "i1"', 'item = "1x"', 14, "key 'tasks[0].item': expected a name"),
        ('dropoff = "16,1"', 'dropoff = "16"', 16, "key 'tasks[0].dropoff'"),
        ("at = 4", "at = 4.5", 21, "key 'faults[0].at': expected a valid integer"),
        ('robot = "r2"\nat', 'robot = "r2"\ncolour = 1\nat', 21, "key 'faults[0].colour'"),
        ('kind = "gripper"', 'kind = "blocked"', 18, "a blocked fault names cells and no robot"),
        ('name = "mine"', 'grippers = "some"', 1, "key 'grippers': expected 'all' or 'mixed'"),
    ],
)
def test_a_key_of_the_wrong_type_names_its_line(
    old: str, new: str, line: int, expected: str
) -> None:
    text = SCENARIO.replace(old, new, 1)
    assert text != SCENARIO
    error = _error(text)
    assert error.line == line and expected in str(error), str(error)


def test_a_count_must_be_a_whole_number() -> None:
    error = _error('maze = "wide-short"\nrobots = 2.5\n')
    assert error.line == 2 and "key 'robots'" in str(error)


def test_cli_refuses_a_wrongly_typed_name_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO.replace('name = "mine"', "name = 5"), encoding="utf-8")
    assert main(["team", "run", str(path)]) == 2
    err = capsys.readouterr().err
    assert err == f"selfrepair: error: {path}:1: key 'name': expected a valid string (got 5)\n"


def test_checks_point_at_the_offending_entry() -> None:
    text = SCENARIO.replace('start = "22,13,W"', 'start = "1,1,S"')
    with pytest.raises(InputError, match="robots r1 and r2 both start at 1,1") as info:
        parse_scenario(text, source="s.toml")
    assert info.value.line == 10
    with pytest.raises(InputError, match="unknown robot 'r9'") as info:
        parse_scenario(SCENARIO.replace('robot = "r2"', 'robot = "r9"'), source="s.toml")
    assert info.value.line == 20


def test_counts_draw_the_same_team_from_the_same_seed() -> None:
    text = 'maze = "wide-short"\nseed = 7\nrobots = 3\ntasks = 4\ngrippers = "mixed"\n'
    one, two = parse_scenario(text), parse_scenario(text)
    assert one.robots == two.robots and one.tasks == two.tasks and len(one.tasks) == 4
    assert [r.gripper for r in one.robots] == [True, True, False]
    other = parse_scenario(text.replace("seed = 7", "seed = 8"))
    assert (other.robots, other.tasks) != (one.robots, one.tasks)


def test_the_table_key_and_a_relative_table_file(tmp_path: Path) -> None:
    from selfrepair.tables.fileformat import bundled_table, dump_table

    with pytest.raises(ConfigError, match=r"faults\[0\]\.table"):
        parse_scenario(SCENARIO + 'table = "handwritten"\n', source="s.toml")
    top = parse_scenario('table = "handwritten"\n' + SCENARIO, source="s.toml")
    assert top.table == "handwritten"
    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "x.json").write_text(dump_table(bundled_table("handwritten")), "utf-8")
    filed = parse_scenario('table = "t/x.json"\n' + SCENARIO, base_dir=tmp_path)
    assert filed.table == str(tmp_path / "t" / "x.json")
    with pytest.raises(ConfigError, match="key 'table': cannot read table file") as info:
        parse_scenario('\ntable = "t/missing.json"\n' + SCENARIO, base_dir=tmp_path)
    assert info.value.line == 2


def test_bundled_scenario_is_found_and_hashed() -> None:
    scenario = resolve_scenario("three-robots")
    assert scenario.source == "<bundled:three-robots>" and len(scenario.digest) == 64


# --- reachability and random scenarios ---------------------------------------------------------

SPLIT = parse_maze("#######\n#..#..#\n#..#.##\n#######\n", name="split")


def test_components_and_distances_on_a_hand_made_maze() -> None:
    label = components(SPLIT)
    assert label[(1, 1)] == label[(2, 2)] != label[(4, 1)] == label[(5, 1)] == label[(4, 2)]
    assert grid_distances(SPLIT, (1, 1)) == {(1, 1): 0, (2, 1): 1, (1, 2): 1, (2, 2): 2}
    assert grid_distances(SPLIT, (1, 1), frozenset({(2, 1)}))[(2, 2)] == 2
    assert largest_area(SPLIT) == [(1, 1), (1, 2), (2, 1), (2, 2)]


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    robots=st.integers(1, 6),
    tasks=st.integers(0, 6),
    mix=st.sampled_from(list(GripperMix)),
)
def test_random_scenarios_always_pass_the_checks(
    seed: int, robots: int, tasks: int, mix: GripperMix
) -> None:
    maze = resolve_maze("wide-short")
    scenario = random_scenario(maze, robots, tasks, np.random.default_rng(seed), grippers=mix)
    check_scenario(scenario)
    cells = [r.start.cell for r in scenario.robots] + [
        c for t in scenario.tasks for c in (t.pickup, t.dropoff)
    ]
    assert len(cells) == len(set(cells)) == robots + 2 * tasks
    area = set(largest_area(maze))
    assert all(c in area for c in cells)


# --- the robots' own table ---------------------------------------------------------------------

THREE_ACTION = SCENARIO.replace(
    'maze = "wide-short"', 'maze = "wide-short"\ndomain = "three-action"'
)
THREE_ACTION = THREE_ACTION.replace(
    'kind = "gripper"\nrobot = "r2"', 'kind = "wheels"\nrobot = "r1"\nwheel_faults = "L"'
)
THREE_ACTION = THREE_ACTION.replace("gripper = false\n", "")


def test_a_three_action_team_runs_to_delivery(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "three.toml"
    path.write_text(THREE_ACTION, encoding="utf-8")
    trace = tmp_path / "t.jsonl"
    assert main(["team", "run", str(path), "--trace", str(trace)]) == 0
    assert "1/1 delivered" in capsys.readouterr().out
    assert main(["team", "replay", str(trace)]) == 0
    scenario = parse_scenario(THREE_ACTION)
    from selfrepair.team.result import TeamOptions
    from selfrepair.team.robottable import robot_table, robot_table_label

    assert robot_table(scenario, TeamOptions()).domain is scenario.domain
    assert robot_table_label(scenario, TeamOptions()) == "three-action"


def test_a_table_for_another_robot_is_refused_with_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = 'table = "handwritten"\n' + THREE_ACTION
    with pytest.raises(ConfigError, match="key 'table': the robots' table 'handwritten' is for "
                       "the four-wheel robot") as info:  # fmt: skip
        parse_scenario(text, source="s.toml")
    assert info.value.line == 1
    path = tmp_path / "three.toml"
    path.write_text(THREE_ACTION, encoding="utf-8")
    assert main(["team", "run", str(path), "--robot-table", "handwritten"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is for the four-wheel robot" in err


def test_a_robot_without_a_bundled_table_gets_a_generated_one() -> None:
    from selfrepair.robots.registry import load_plugin
    from selfrepair.team.result import TeamOptions
    from selfrepair.team.robottable import robot_table, robot_table_label

    load_plugin(Path(__file__).parent / "data" / "robots" / "hopper.py")
    text = THREE_ACTION.replace('"three-action"', '"hopper"').replace('"L"', '"HOP"')
    scenario = parse_scenario(text)
    assert robot_table_label(scenario, TeamOptions()) == "generated"
    table = robot_table(scenario, TeamOptions())
    assert table.domain is scenario.domain and table.domain.name == "hopper"
