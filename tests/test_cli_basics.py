"""The basic commands, run in-process: actions and the maze group (show, list, generate,
routes)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from selfrepair.cli import main
from selfrepair.robots.four_wheel import ACTIONS
from selfrepair.world import bundled
from selfrepair.world.loading import load_maze
from selfrepair.world.maze import format_maze, parse_maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.render import render_ascii, route_layers


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def assert_bad_input(result: tuple[int, str, str], *fragments: str) -> None:
    code, out, err = result
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("selfrepair: error: "), err
    for fragment in fragments:
        assert fragment in err


def test_actions_json_has_81_rows(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "actions", "--json")
    rows = json.loads(out)
    assert code == 0 and len(rows) == 81
    assert rows[0] == {"action": "FFFF", "l": 2, "r": 2, "motion": "forward", "kind": "straight",
                       "duration": "1"}
    assert [r["action"] for r in rows] == [a.code for a in ACTIONS]


def test_actions_table(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "actions")
    assert code == 0
    assert "FSFB" in out and "4/3" in out and "arc-forward-left" in out


def test_maze_show_bundled_is_the_plain_text(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "maze", "show", "narrow-short")
    assert code == 0
    assert out == format_maze(bundled.load_bundled("narrow-short"))


def test_maze_show_with_routes(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "maze", "show", "wide-short", "--routes")
    maze = bundled.load_bundled("wide-short")
    routes = bundled.bundled_routes("wide-short")
    assert code == 0
    lines = out.splitlines()
    assert "\n".join(lines[: maze.height]) + "\n" == render_ascii(maze, route_layers(routes))
    assert len(lines) == maze.height + 4
    for index, route in enumerate(routes, start=1):
        line = lines[maze.height + index - 1]
        assert line.split()[:2] == [str(index), route.name]
        assert str(route.start) in line


def test_maze_show_one_route(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "maze", "show", "narrow-short", "--route", "r3")
    route = bundled.bundled_routes("narrow-short")[2]
    assert code == 0
    rows = out.splitlines()
    assert rows[route.goal[1]][route.goal[0]] == "G"
    assert rows[route.start.y][route.start.x] == "<"  # r3 starts facing west
    assert sum(row.count("G") for row in rows[:15]) == 1


def test_maze_show_files_and_sibling_routes(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    maze_file = tmp_path / "m.maze"
    maze_file.write_text("#####\n#...#\n#.#.#\n#...#\n#####\n")
    code, out, _ = run(capsys, "maze", "show", str(maze_file))
    assert (code, out) == (0, maze_file.read_text())
    assert_bad_input(run(capsys, "maze", "show", str(maze_file), "--routes"), "m.routes")
    (tmp_path / "m.routes").write_text("a 1,1,E 3,3\n")
    code, out, _ = run(capsys, "maze", "show", str(maze_file), "--routes")
    assert code == 0 and out.startswith("#####\n#>..#\n#.#.#\n#..G#\n")
    other = tmp_path / "other.routes"
    other.write_text("b 3,3,N 1,1\n")
    code, out, _ = run(capsys, "maze", "show", str(maze_file), "--routes-file", str(other))
    assert code == 0 and out.startswith("#####\n#G..#\n#.#.#\n#..^#\n")


def test_maze_show_movingai_map(capsys: pytest.CaptureFixture[str]) -> None:
    path = Path(__file__).parent / "data" / "movingai" / "maze512-1-0.map"
    code, out, _ = run(capsys, "maze", "show", str(path))
    assert code == 0 and len(out.splitlines()) == 512


def test_maze_show_bad_input(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert_bad_input(run(capsys, "maze", "show", "nowhere"), "nowhere", "narrow-short")
    bad = tmp_path / "bad.maze"
    bad.write_text("###\n#.\n###\n")
    assert_bad_input(run(capsys, "maze", "show", str(bad)), f"{bad}:2:3")
    assert_bad_input(run(capsys, "maze", "show", "narrow-short", "--route", "zz"), "zz")
    routes = tmp_path / "r.routes"
    routes.write_text("a 0,0,E 1,1\n")
    assert_bad_input(
        run(capsys, "maze", "show", "narrow-short", "--routes-file", str(routes)),
        f"{routes}:1:3",
        "wall",
    )


def test_maze_generate_to_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out_file = tmp_path / "g.maze"
    args = ["maze", "generate", "--width", "21", "--height", "15", "--corridor", "2",
            "--braid", "0.5", "--seed", "4", "-o", str(out_file)]
    code, out, _ = run(capsys, *args)
    assert code == 0 and f"wrote {out_file}" in out
    expected = generate_maze(21, 15, corridor=2, braid=0.5, seed=4)
    assert load_maze(out_file) == expected
    code, out, _ = run(capsys, *args[:-2])
    assert code == 0 and parse_maze(out) == expected


def test_maze_generate_bad_input(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    base = ["maze", "generate", "--width", "15", "--height", "15"]
    assert_bad_input(run(capsys, *base, "--seed", "1", "--corridor", "0"), "corridor width")
    assert_bad_input(run(capsys, *base, "--seed", "1", "--braid", "2"), "braid")
    assert_bad_input(run(capsys, *base, "--seed", "-3"), "seed")
    assert_bad_input(run(capsys, *base), "--seed")
    assert_bad_input(run(capsys, *base, "--seed", "x"), "--seed", "integer")
    assert_bad_input(
        run(capsys, *base, "--seed", "1", "-o", str(tmp_path / "no" / "such" / "dir.maze")),
        "cannot write",
    )
    assert_bad_input(run(capsys, *base, "--seed", "1", "-o", str(tmp_path / "m.map")), "m.map")


def test_maze_list_prints_every_bundled_maze_with_its_routes(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, err = run(capsys, "maze", "list")
    assert code == 0 and err == ""
    for name in bundled.maze_names():
        maze = bundled.load_bundled(name)
        picture = render_ascii(maze, route_layers(bundled.bundled_routes(name)))
        assert f"== {name}: " in out
        assert picture in out
        for route in bundled.bundled_routes(name):
            assert str(route.start) in out


def test_demo_is_not_a_command_any_more(capsys: pytest.CaptureFixture[str]) -> None:
    """`selfrepair demo` printed mazes and clashed with `make demo`; it is `maze list` now."""
    assert_bad_input(run(capsys, "demo"), "demo")


def test_maze_routes_are_seeded_and_valid(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    from selfrepair.world.routes import load_routes, parse_routes, random_routes

    code, out, _ = run(capsys, "maze", "routes", "wide-short", "-n", "5", "--seed", "3")
    maze = bundled.load_bundled("wide-short")
    routes = parse_routes(out, maze=maze)  # every start and goal is free
    assert code == 0 and routes == random_routes(maze, 5, 3)
    assert [r.name for r in routes] == ["q1", "q2", "q3", "q4", "q5"]
    assert run(capsys, "maze", "routes", "wide-short", "-n", "5", "--seed", "3")[1] == out
    assert run(capsys, "maze", "routes", "wide-short", "-n", "5", "--seed", "4")[1] != out
    target = tmp_path / "w.routes"
    code, out, _ = run(capsys, "maze", "routes", "wide-short", "-n", "2", "-o", str(target))
    assert code == 0 and f"wrote {target}: 2 routes" in out
    assert load_routes(target, maze=maze) == random_routes(maze, 2, 0)


def test_maze_generate_with_routes_then_show_them(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The issue: `maze generate` wrote no routes and `maze show my.maze --routes` failed."""
    maze_file = tmp_path / "my.maze"
    args = ["maze", "generate", "--width", "21", "--height", "21", "--seed", "7"]
    code, out, _ = run(capsys, *args, "--routes", "3", "-o", str(maze_file))
    assert code == 0 and f"wrote {tmp_path / 'my.routes'}: 3 routes" in out
    text = (tmp_path / "my.routes").read_text()
    assert "made by: selfrepair maze generate" in text and "--routes 3" in text
    code, out, _ = run(capsys, "maze", "show", str(maze_file), "--routes")
    assert code == 0 and len(out.splitlines()) == 21 + 3
    assert_bad_input(run(capsys, *args, "--routes", "3"), "--routes", "-o FILE")
    assert_bad_input(run(capsys, *args, "--routes", "0", "-o", str(maze_file)), "--routes")


def test_maze_routes_bad_input(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert_bad_input(run(capsys, "maze", "routes", "nowhere"), "nowhere")
    assert_bad_input(run(capsys, "maze", "routes", "narrow-short", "-n", "0"), "--count")
    assert_bad_input(run(capsys, "maze", "routes", "narrow-short", "-n", "10001"), "10000")
    assert_bad_input(run(capsys, "maze", "routes", "narrow-short", "--seed", "-1"), "--seed")
    tiny = tmp_path / "tiny.maze"
    tiny.write_text("###\n#.#\n###\n")
    assert_bad_input(run(capsys, "maze", "routes", str(tiny)), "two free cells")


def test_missing_sibling_routes_say_how_to_make_them(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    maze_file = tmp_path / "m.maze"
    maze_file.write_text("#####\n#...#\n#####\n")
    assert_bad_input(run(capsys, "maze", "show", str(maze_file), "--routes"), "maze routes")
