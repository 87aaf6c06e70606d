"""docs/baselines.md shows schemas and sizes computed by the code; these tests keep them in step."""

from __future__ import annotations

import re
from pathlib import Path

from selfrepair.baselines.pddl import export_pddl
from selfrepair.baselines.pddltext import domain_text
from selfrepair.geometry import Heading, Pose
from selfrepair.search.problem import PlanningProblem
from selfrepair.world import bundled
from selfrepair.world.maze import parse_maze

DOC = Path(__file__).parent.parent / "docs" / "baselines.md"


def test_schemas_shown_are_those_written() -> None:
    text = DOC.read_text(encoding="utf-8")
    match = re.search(
        r"<!-- BEGIN generated: schemas -->\n```text\n(.*?)```\n<!-- END generated: schemas -->",
        text,
        re.S,
    )
    assert match is not None, "docs block 'schemas' is missing"
    maze = parse_maze(".....\n.###.\n.....\n")
    domain = domain_text(export_pddl(PlanningProblem(maze, Pose(0, 0, Heading.E), (4, 2))))
    shown = match.group(1).split("  (:action ")[1:]
    assert [s.split("\n")[0] for s in shown] == ["ffff", "fffs", "fbfb", "ssss"]
    for schema in shown:
        assert "  (:action " + schema.rstrip() + "\n" in domain


def test_size_table_is_that_of_the_bundled_mazes() -> None:
    text = DOC.read_text(encoding="utf-8")
    for name in bundled.maze_names():
        route = bundled.bundled_routes(name)[0]
        task = export_pddl(PlanningProblem(bundled.load_bundled(name), route.start, route.goal))
        row = re.search(
            rf"^\| {name} \(\d+x\d+\) \| ([\d,]+) \| ([\d,]+) \| ([\d,]+) \|", text, re.M
        )
        assert row is not None, name
        numbers = [int(n.replace(",", "")) for n in row.groups()]
        assert numbers == [len(task.cells), task.static_facts, task.ground_actions], name


def test_readme_baselines_figures_are_those_of_the_documented_run() -> None:
    """Every median with its interval in the README's baselines paragraph is in the full tables
    of docs/baselines.md (the one run both come from)."""
    readme = (DOC.parent.parent / "README.md").read_text(encoding="utf-8")
    match = re.search(r"^## Against D\* Lite and LPG-adapt\n(.*?)^## ", readme, re.S | re.M)
    assert match is not None, "README has no baselines section"
    figures = re.findall(r"[\d,.]+ \[[\d,.]+, [\d,.]+\]", match.group(1))
    assert len(figures) >= 10
    tables = DOC.read_text(encoding="utf-8")
    results = tables[tables.index("### Results") :]
    for figure in figures:
        assert f"| {figure} |" in results, figure
