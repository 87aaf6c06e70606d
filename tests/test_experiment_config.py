"""Experiment TOML: validation errors name the file, the key and its line; expansion is stable."""

from __future__ import annotations

import re
from fractions import Fraction
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from selfrepair.cli import main
from selfrepair.errors import ConfigError, LimitError, TableError
from selfrepair.experiment.config import load_config, parse_config
from selfrepair.experiment.faultsets import PAPER_FAULT_SETS, fault_profile
from selfrepair.experiment.missions import count_missions, expand

GOOD = """\
name = "tiny"
seed = 7

[[mazes]]
bundled = "narrow-short"

[[mazes]]
generate = { width = 15, height = 15, corridor = 1, seed = 3 }
routes = 2

[faults]
sets = ["FL:F", "FL:F,RR:B"]

[planner]
clearance_weights = [0, 0.5]

[[strategies]]
name = "replan"

[[strategies]]
name = "replacement"
tables = ["handwritten"]
"""


def test_good_config_parses_to_frozen_values() -> None:
    config = parse_config(GOOD)
    assert config.name == "tiny"
    assert config.planner.clearance_weights == ("0", "1/2")
    assert config.faults.sets == ("FL:F", "FL:F,RR:B")
    with pytest.raises(Exception, match="frozen"):
        config.seed = 3  # type: ignore[misc]


@pytest.mark.parametrize(
    ("old", "new", "key", "line", "expected"),
    [
        ('tables = ["handwritten"]', "tables = 3", "strategies[1].tables", 22, "expected a list"),
        ('name = "replan"', 'name = "repln"', "strategies[0].name", 18, "replacement"),
        ('["FL:F", "FL:F,RR:B"]', '["FL:X"]', "faults.sets", 12, "WHEEL:MODE"),
        ("routes = 2", 'routes = "bundled"', "mazes[1]", 7, "needs a bundled maze"),
        ("routes = 2", "routes = 0", "mazes[1].routes", 9, "greater than or equal to 1"),
        ("routes = 2", 'routes = [{start="1,1,E"}]', "mazes[1].routes[0].goal", 9, "missing"),
        (
            "routes = 2",
            'routes = [{start="1,1,Q", goal="3,1"}]',
            "mazes[1].routes[0].start",
            9,
            "H in N, E, S, W, got '1,1,Q'",
        ),
        ("seed = 7", 'seed = "x"', "seed", 2, "integer"),
        ("corridor = 1", "corridor = 0", "mazes[1].generate.corridor", 8, "greater than"),
        (
            "clearance_weights = [0, 0.5]",
            "clearance_weight = [0]",
            "planner.clearance_weight",
            15,
            "unknown key",
        ),
        (
            "clearance_weights = [0, 0.5]",
            "clearance_weights = [-1]",
            "planner.clearance_weights",
            15,
            "non-negative",
        ),
        ('tables = ["handwritten"]', "tables = []", "strategies[1].tables", 22, "non-empty list"),
        (
            'tables = ["handwritten"]',
            "recursion = []",
            "strategies[1].recursion",
            22,
            "non-empty list",
        ),
        ('sets = ["FL:F", "FL:F,RR:B"]', 'sets = ["FL:F"]\nat = []', "faults.at", 13, "non-empty"),
        (
            'sets = ["FL:F", "FL:F,RR:B"]',
            'sets = ["FL:F"]\ndetection = []',
            "faults.detection",
            13,
            "non-empty list",
        ),
    ],
)
def test_bad_config_names_file_key_and_line(
    tmp_path: Path, old: str, new: str, key: str, line: int, expected: str
) -> None:
    assert old in GOOD
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace(old, new))
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert message.startswith(f"{path.resolve()}:{line}: key {key!r}"), message
    assert expected in message


def test_missing_strategies_and_unknown_maze(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="'strategies': missing required key"):
        parse_config('name = "x"\n[[mazes]]\nbundled = "narrow-short"\n')
    config = parse_config(GOOD.replace('"narrow-short"', '"nowhere"'))
    with pytest.raises(ConfigError, match=r"mazes\[0\]\.bundled.*narrow-short"):
        expand(config)


def test_bad_toml_syntax_reports_line() -> None:
    with pytest.raises(ConfigError, match=r"x.toml:2:\d+: invalid TOML"):
        parse_config('name = "x"\nseed = = 3\n', source="x.toml")


def test_cli_bad_toml_is_one_line_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(GOOD.replace('tables = ["handwritten"]', 'tables = ["handwritten"]\ndepth = 3'))
    assert main(["experiment", str(path), "--db", str(tmp_path / "r.sqlite")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "key 'strategies[1].depth': unknown key" in err and ":23:" in err


def test_expansion_is_stable_and_complete() -> None:
    config = parse_config(GOOD)
    missions = expand(config)
    # 4 bundled routes + 2 random routes, 2 fault sets, (replan + replacement) x 2 weights
    assert len(missions) == 6 * 2 * 2 * 2
    assert len({m.key for m in missions}) == len(missions)
    again = expand(parse_config(GOOD))
    assert [m.key for m in missions] == [m.key for m in again]
    assert [m.seed for m in missions] == [m.seed for m in again]
    # seeds are paired across strategies: same situation, same seed
    by_situation: dict[tuple[object, ...], set[int]] = {}
    for m in missions:
        labels = dict(m.labels)
        by_situation.setdefault((labels["maze"], labels["route"], labels["faults"]), set()).add(
            m.seed
        )
    assert all(len(seeds) == 1 for seeds in by_situation.values())
    # a different base seed gives different keys and seeds
    other = expand(parse_config(GOOD.replace("seed = 7", "seed = 8")))
    assert not {m.key for m in other} & {m.key for m in missions}


def test_fault_profiles() -> None:
    assert len(fault_profile("paper")) == 12 == len(set(PAPER_FAULT_SETS))
    assert sum(1 for s in fault_profile("paper") if "," in s) == 10
    assert len(fault_profile("singles")) == 12
    assert len(fault_profile("doubles")) == 66
    assert len(set(fault_profile("all"))) == 78


@pytest.mark.parametrize("name", ["paper", "full", "tolerance"])
def test_bundled_experiments_load(name: str) -> None:
    from selfrepair.cli.experiments import resolve_experiment

    config = load_config(resolve_experiment(name))
    assert config.name == name


@settings(max_examples=40, deadline=None)
@given(st.lists(st.fractions(min_value=0, max_value=50, max_denominator=8), min_size=1, max_size=4))
def test_clearance_weights_are_exact_and_canonical(weights: list[Fraction]) -> None:
    """Weights written as decimals or fractions come out as exact canonical text."""
    decimals = ", ".join(f'"{w}"' for w in weights)
    config = parse_config(
        GOOD.replace("clearance_weights = [0, 0.5]", f"clearance_weights = [{decimals}]")
    )
    assert [Fraction(w) for w in config.planner.clearance_weights] == weights
    assert all(w == str(Fraction(w)) for w in config.planner.clearance_weights)


FILES = """\
name = "files"
seed = 1
[[mazes]]
file = "data/m.maze"
routes = 1
[faults]
sets = ["FL:F"]
[[strategies]]
name = "replacement"
tables = ["data/t.json"]
"""


def _write_files_experiment(root: Path) -> Path:
    from importlib import resources

    data = root / "data"
    data.mkdir(parents=True)
    maze = resources.files("selfrepair").joinpath("data", "mazes", "narrow-short.maze")
    (data / "m.maze").write_text(maze.read_text(encoding="utf-8"), encoding="utf-8")
    table = resources.files("selfrepair").joinpath("data", "tables", "handwritten.json")
    (data / "t.json").write_text(table.read_text(encoding="utf-8"), encoding="utf-8")
    path = root / "files.toml"
    path.write_text(FILES, encoding="utf-8")
    return path


def test_file_keys_follow_content_not_location(tmp_path: Path) -> None:
    """Moving the files keeps keys and seeds; editing the table file changes the keys."""
    first = expand(load_config(_write_files_experiment(tmp_path / "a")))
    moved = expand(load_config(_write_files_experiment(tmp_path / "elsewhere" / "b")))
    assert [(m.key, m.seed) for m in first] == [(m.key, m.seed) for m in moved]
    assert str(tmp_path / "a") in first[0].config  # workers still load from the real path
    table = tmp_path / "a" / "data" / "t.json"
    table.write_text(table.read_text(encoding="utf-8").replace("by hand", "by hand!"))
    edited = expand(load_config(tmp_path / "a" / "files.toml"))
    assert not {m.key for m in edited} & {m.key for m in first}


# --- hostile input and limits ------------------------------------------------------------------


def test_a_file_that_is_not_utf8_is_a_config_error_with_its_line(tmp_path: Path) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes(GOOD.encode() + b'description = "caf\xe9"\n')
    with pytest.raises(ConfigError, match="UTF-8 text experiment file, got the byte 0xe9") as info:
        load_config(path)
    assert (info.value.line, info.value.column) == (GOOD.count("\n") + 1, 19)


def test_a_byte_order_mark_is_ignored() -> None:
    assert parse_config("\ufeff" + GOOD) == parse_config(GOOD)


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("description = " + "[" * 5000 + "]" * 5000, "nested too deep"),  # was a RecursionError
        ("seed = " + "1" * 5000, "at most 4300 digits"),  # was a ValueError
    ],
)
def test_hostile_toml_is_a_config_error(line: str, expected: str) -> None:
    with pytest.raises(ConfigError, match=expected):
        parse_config(line + "\n" + GOOD.replace("seed = 7\n", ""), source="x.toml")


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("seed = 7", "seed = 7\nrepeats = true", "repeats"),  # was read as 1
        ("seed = 7", "seed = true", "seed"),
        ("routes = 2", "routes = true", "mazes[1].routes"),
        ("corridor = 1", "corridor = true", "mazes[1].generate.corridor"),
        ("seed = 3 }", "seed = 3, braid = true }", "mazes[1].generate.braid"),
        ('["FL:F", "FL:F,RR:B"]', '["FL:F"]\nat = [false]', "faults.at[0]"),
        ("clearance_weights = [0, 0.5]", "clearance_radius = true", "planner.clearance_radius"),
        ("[0, 0.5]", "[true]", "planner.clearance_weights"),
    ],
)
def test_booleans_are_not_numbers(old: str, new: str, key: str) -> None:
    assert old in GOOD
    with pytest.raises(ConfigError, match=rf"key '{re.escape(key)}'.*(True|False)"):
        parse_config(GOOD.replace(old, new))


def test_integers_are_strict() -> None:
    with pytest.raises(ConfigError, match=r"key 'seed': expected a valid integer \(got 7.0\)"):
        parse_config(GOOD.replace("seed = 7", "seed = 7.0"))


def test_an_empty_route_list_is_refused() -> None:
    # It used to give "0 missions" and exit code 0.
    with pytest.raises(ConfigError, match=r"'mazes\[1\]\.routes': expected a list of at least 1"):
        parse_config(GOOD.replace("routes = 2", "routes = []"))


def test_an_experiment_without_missions_is_an_error() -> None:
    config = parse_config(GOOD)
    no_routes = config.mazes[1].model_copy(update={"routes": ()})  # past validation
    empty = config.model_copy(update={"mazes": (no_routes,)})
    with pytest.raises(ConfigError, match="at least one mission, got none"):
        expand(empty)


@pytest.mark.parametrize("weight", ["1e308", "1000001", '"1000000001/1000"'])
def test_clearance_weight_above_the_bound_is_refused(weight: str) -> None:
    # 1e308 used to overflow in the metrics and stop the whole sweep.
    with pytest.raises(ConfigError, match="weight of at most 1,000,000"):
        parse_config(GOOD.replace("[0, 0.5]", f"[{weight}]"))
    assert parse_config(GOOD.replace("[0, 0.5]", "[1000000]")).planner.clearance_weights == (
        "1000000",
    )


def test_missions_are_counted_before_they_are_built() -> None:
    config = parse_config(GOOD)
    assert count_missions(config) == len(expand(config)) == 48
    message = r"at most 47 missions, got 48 \(routes 6 x fault sets 2 x"
    with pytest.raises(LimitError, match=message):
        expand(config, max_missions=47)
    # About 312 million missions: refused at once instead of running out of memory.
    huge = parse_config(
        GOOD.replace("seed = 7", "seed = 7\nrepeats = 1000")
        .replace("width = 15, height = 15", "width = 1024, height = 1024")
        .replace("routes = 2", "routes = 10000")
        .replace('["FL:F", "FL:F,RR:B"]', '"all"')
    )
    assert count_missions(huge) == 10004 * 78 * 1000 * 4
    with pytest.raises(LimitError, match="--max-missions") as info:
        expand(huge)
    assert info.value.limit == "max_missions"


@settings(max_examples=30, deadline=None)
@given(
    repeats=st.integers(1, 3),
    routes=st.integers(1, 3),
    at=st.lists(st.integers(0, 2), min_size=1, max_size=2),
    weights=st.lists(st.sampled_from(["0", "1", "2"]), min_size=1, max_size=2),
)
def test_mission_count_bounds_the_expansion(
    repeats: int, routes: int, at: list[int], weights: list[str]
) -> None:
    text = (
        GOOD.replace("seed = 7", f"seed = 7\nrepeats = {repeats}")
        .replace("routes = 2", f"routes = {routes}")
        .replace('["FL:F", "FL:F,RR:B"]', f'["FL:F", "FL:F,RR:B"]\nat = {at}')
        .replace("[0, 0.5]", "[" + ", ".join(weights) + "]")
    )
    config = parse_config(text)
    missions = expand(config)
    assert len(missions) <= count_missions(config)
    if len(set(at)) == len(at) and len(set(weights)) == len(weights):
        assert len(missions) == count_missions(config)


def test_maze_file_over_the_cell_limit_stops_the_experiment(tmp_path: Path) -> None:
    config = load_config(_write_files_experiment(tmp_path))
    with pytest.raises(LimitError, match="at most 224 cells, got 225"):
        expand(config, max_cells=224)
    assert len(expand(config, max_cells=225)) == 1


def test_a_bad_table_file_stops_the_experiment_before_the_sweep(tmp_path: Path) -> None:
    path = _write_files_experiment(tmp_path)
    (tmp_path / "data" / "t.json").write_text('{"format": "selfrepair-table"}')
    with pytest.raises(TableError, match="expected a 'version' key"):
        expand(load_config(path))


def _plus_robot() -> None:
    """Register ``three-action-plus``: the three-action robot, its fault sets written ``L+R``."""
    import dataclasses
    from collections.abc import Iterable

    from selfrepair.robots.registry import register_domain
    from selfrepair.robots.three_action import THREE_ACTION

    def parse(text: str) -> frozenset[str]:
        return frozenset(p.strip().upper() for p in text.split("+") if p.strip())

    def write(faults: Iterable[str]) -> str:
        return "+".join(sorted(faults, key="FLR".index))

    plus = dataclasses.replace(
        THREE_ACTION, name="three-action-plus", parse_faults=parse, format_faults=write
    )
    register_domain(plus, replace=True)


def test_fault_count_is_the_robots_count_of_its_fault_set() -> None:
    """``fault_count`` asks the robot's domain what a fault text holds (issue 23): a robot that
    writes its fault sets ``L+R`` has two faults there, not one comma-less item."""
    _plus_robot()
    text = (
        'name = "plus"\nseed = 1\ndomain = "three-action-plus"\n\n[[mazes]]\n'
        'bundled = "narrow-short"\n\n[faults]\nsets = ["L", "L+R"]\n\n'
        '[[strategies]]\nname = "replan"\n'
    )
    labels = [dict(m.labels) for m in expand(parse_config(text))]
    assert {row["faults"]: row["fault_count"] for row in labels} == {"L": 1, "L+R": 2}
