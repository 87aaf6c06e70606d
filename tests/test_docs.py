"""The docs show tables and pictures generated from the code; these tests keep them in step."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from selfrepair.robots import four_wheel_docs
from selfrepair.world import bundled
from selfrepair.world.render import render_ascii, route_layers

DOCS = Path(__file__).parent.parent / "docs"


def generated_block(text: str, name: str) -> str:
    match = re.search(
        rf"<!-- BEGIN generated: {name} -->\n(.*?)<!-- END generated: {name} -->", text, re.S
    )
    assert match is not None, f"docs block {name} is missing"
    return match.group(1)


@pytest.mark.parametrize(
    "name",
    ["markdown_action_table", "markdown_single_fault_table", "markdown_double_fault_summary"],
)
def test_robot_doc_tables_match_the_code(name: str) -> None:
    text = (DOCS / "robot.md").read_text(encoding="utf-8")
    assert generated_block(text, name) == getattr(four_wheel_docs, name)()


def test_action_table_has_81_rows_in_code_order() -> None:
    text = (DOCS / "robot.md").read_text(encoding="utf-8")
    table = generated_block(text, "markdown_action_table")
    rows = [line.split("|")[1].strip() for line in table.splitlines()[2:]]
    assert len(rows) == 81 and rows[0] == "FFFF" and rows[-1] == "BBBB"


@pytest.mark.parametrize("name", bundled.maze_names())
def test_maze_doc_shows_each_maze_with_its_routes(name: str) -> None:
    text = (DOCS / "mazes.md").read_text(encoding="utf-8")
    picture = render_ascii(bundled.load_bundled(name), route_layers(bundled.bundled_routes(name)))
    assert f"```text\n{picture}```" in text
    for route in bundled.bundled_routes(name):
        assert f"`{route.start}` | `{route.goal[0]},{route.goal[1]}`" in text


def test_readme_library_example_prints_what_the_readme_says(
    capsys: pytest.CaptureFixture[str],
) -> None:
    readme = (DOCS.parent / "README.md").read_text(encoding="utf-8")
    match = re.search(r"```python\n(.*?)```", readme, re.S)
    assert match is not None, "README has no python example"
    code = match.group(1)
    expected = [line[2:] for line in code.splitlines() if line.startswith("# ")]
    assert expected, "the example states its output in '# ' comment lines"
    exec(compile(code, "README.md", "exec"), {})
    assert capsys.readouterr().out.splitlines() == expected


def test_team_doc_table_matches_the_code() -> None:
    from selfrepair.team.table import HANDWRITTEN, markdown_team_table

    text = (DOCS / "team.md").read_text(encoding="utf-8")
    assert generated_block(text, "markdown_team_table") == markdown_team_table(HANDWRITTEN)
