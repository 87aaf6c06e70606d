"""The report's figures and captions: a visible initial plan and one mark per repair in the
mission picture, a readable heat map for many fault sets, no empty clearance figure, and
singular nouns for one."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from extras import need
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.trace import read_trace, write_trace
from selfrepair.experiment import missionplot, plots
from selfrepair.experiment.report import counted, render_markdown
from selfrepair.geometry import parse_pose
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots.four_wheel import parse_faults
from selfrepair.tables.fileformat import bundled_table, dump_table
from selfrepair.world.bundled import load_bundled


@pytest.fixture(autouse=True)
def _viz() -> None:
    need("matplotlib", "viz")


def new_figure() -> Any:
    """A matplotlib figure (imported here: the module must import without the viz extra)."""
    from matplotlib.figure import Figure

    return Figure()


@pytest.fixture(scope="module")
def trace_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    spec = MissionSpec(
        load_bundled("narrow-short"),
        parse_pose("1,1,E"),
        (13, 13),
        schedule=FaultSchedule.permanent(parse_faults("FL:F,RR:B")),
        strategy="replacement",
    )
    trace = tmp_path_factory.mktemp("trace") / "t.jsonl"
    write_trace(run_mission(spec), trace)
    return trace


@pytest.fixture(scope="module")
def picture(trace_file: Path) -> missionplot.MissionPicture:
    return missionplot.picture_from_trace(read_trace(trace_file))


def _drawn(picture: missionplot.MissionPicture) -> Any:
    fig = new_figure()
    ax = fig.subplots()
    missionplot.draw_mission(ax, picture)
    return ax


def test_mission_picture_marks_every_repair(picture: missionplot.MissionPicture) -> None:
    assert len(picture.repairs) > 10  # the replacing robot meets its faulty actions again
    marks = [line for line in _drawn(picture).lines if line.get_gid() == "repair"]
    assert len(marks) == len(picture.repairs)
    assert [(m.get_xdata()[0], m.get_ydata()[0]) for m in marks] == [
        (pose.x, pose.y) for _, pose, _ in picture.repairs
    ]


def test_initial_plan_is_drawn_over_the_executed_path(picture: missionplot.MissionPicture) -> None:
    ax = _drawn(picture)
    (plan,) = [line for line in ax.lines if line.get_gid() == "initial-plan"]
    executed = [line for line in ax.lines if line.get_gid() == "step"]
    assert executed and plan.get_zorder() > max(line.get_zorder() for line in executed)
    assert len(plan.get_xdata()) >= len(picture.planned)


def test_animation_marks_each_repair_once(picture: missionplot.MissionPicture) -> None:
    fig = new_figure()
    ax = fig.subplots()
    missionplot.draw_background(ax, picture)
    total = len(picture.steps)
    drawn = 0
    for upto in [*range(0, total + 1, 7), total, total, total]:  # held last frames
        missionplot.draw_steps(ax, picture, drawn, upto)
        drawn = max(drawn, upto)
    marks = [line for line in ax.lines if line.get_gid() == "repair"]
    assert len(marks) == len(picture.repairs)


def _heat_rows(fault_sets: int, mazes: int = 4) -> list[dict[str, Any]]:
    return [
        {
            "variant": "replacement[handwritten,flat]",
            "strategy": "replacement",
            "clearance_weight": "0",
            "maze": f"maze-{m}",
            "maze_free_cells": 100 * (m + 1),
            "faults": f"F{f:02d}" if f < 12 else f"F{f % 12:02d},G{f:02d}",
            "faulty_encounters": 10,
            "replacements": f % 10,
            "lookaheads": 0,
            "extra_ticks": float(f),
        }
        for f in range(fault_sets)
        for m in range(mazes)
    ]


def test_heatmap_of_78_fault_sets_stays_a_readable_size(tmp_path: Path) -> None:
    from PIL import Image

    path = plots.figure_heatmap(_heat_rows(78), tmp_path / "heat.png")
    with Image.open(path) as image:
        width, height = image.size
    assert width < 2000 and height < 1500, (width, height)


def test_heatmap_of_a_few_fault_sets_keeps_its_numbers(tmp_path: Path) -> None:
    from PIL import Image

    path = plots.figure_heatmap(_heat_rows(12), tmp_path / "heat.png")
    with Image.open(path) as image:
        assert image.size[1] > 400


def test_no_clearance_figure_for_a_single_weight(tmp_path: Path) -> None:
    rows = _heat_rows(3)
    assert plots.figure_clearance(rows, tmp_path / "c.png") is None
    assert not (tmp_path / "c.png").exists()
    two = rows + [{**r, "clearance_weight": "1"} for r in rows]
    assert plots.figure_clearance(two, tmp_path / "c.png") == tmp_path / "c.png"


def _report(chosen: dict[str, Any], *, clearance: bool) -> str:
    rows = [{**chosen, "experiment": "e", "version": "0", "faults": "FL:F", "worker_seconds": 1}]
    return render_markdown(rows, [], [], chosen, "db", heatmap_variant="v", clearance=clearance)


CHOSEN = {
    "key": "abcdef123456789",
    "maze": "narrow-short",
    "route": "r1",
    "config": json.dumps({"faults": "FL:F"}),
    "variant": "replacement[handwritten,flat]",
    "clearance_weight": "0",
}


def test_caption_counts_in_the_singular_for_one() -> None:
    assert counted(1, "replan") == "1 replan" and counted(13, "replan") == "13 replans"
    assert counted(None, "replan") == "0 replans"
    text = _report({**CHOSEN, "replacements": 1, "replans": 1}, clearance=True)
    assert "1 table replacement, 1 replan." in text and "1 replans" not in text


def test_report_leaves_out_the_clearance_figure_it_did_not_draw() -> None:
    assert "clearance.png" in _report({**CHOSEN, "replacements": 2, "replans": 0}, clearance=True)
    assert "clearance.png" not in _report(
        {**CHOSEN, "replacements": 2, "replans": 0}, clearance=False
    )


def test_animate_reports_the_frames_in_the_gif_and_its_progress(
    trace_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: Any
) -> None:
    """The GIF writer merges the held last frames: the count printed is the file's own."""
    import sys

    from PIL import Image

    from selfrepair.cli import main
    from selfrepair.experiment.animate import animate_trace

    seen: list[tuple[int, int]] = []
    gif = tmp_path / "a.gif"
    frames = animate_trace(
        trace_file, gif, fps=3, max_frames=8, on_frame=lambda d, t: seen.append((d, t))
    )
    with Image.open(gif) as image:
        assert frames == image.n_frames
    assert seen and seen[-1][0] == seen[-1][1]
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    monkeypatch.setattr(sys.stdout, "isatty", lambda: True)  # a terminal: the bar is drawn
    again = tmp_path / "b.gif"
    assert main(["animate", str(trace_file), "-o", str(again), "--max-frames", "8"]) == 0
    out = capsys.readouterr().out
    with Image.open(again) as image:
        assert f"wrote {again} ({image.n_frames} frames)" in out


@pytest.fixture(scope="module")
def arc_picture(tmp_path_factory: pytest.TempPathFactory) -> missionplot.MissionPicture:
    """The report's mission of `experiment paper`: in wide corridors the robot turns by arcs."""
    spec = MissionSpec(
        load_bundled("wide-short"),
        parse_pose("17,7,S"),
        (15, 20),
        schedule=FaultSchedule.permanent(parse_faults("FL:B,RL:S")),
        strategy="replacement",
    )
    trace = tmp_path_factory.mktemp("arcs") / "t.jsonl"
    write_trace(run_mission(spec), trace)
    return missionplot.picture_from_trace(read_trace(trace))


def test_arcs_are_drawn_as_quarter_circles(arc_picture: missionplot.MissionPicture) -> None:
    arcs = [
        (start, end)
        for start, end, _ in arc_picture.steps
        if (end.heading - start.heading) % 2 == 1 and start.x != end.x and start.y != end.y
    ]
    assert len(arcs) >= 3  # moves that change cell and turn a quarter: the four-wheel arcs
    lines = {
        (line.get_xdata()[0], line.get_ydata()[0], line.get_xdata()[-1], line.get_ydata()[-1]): line
        for line in _drawn(arc_picture).lines
        if line.get_gid() == "step" and len(line.get_xdata()) > 1
    }
    for start, end in arcs:
        line = lines[(start.x, start.y, end.x, end.y)]
        xs, ys = line.get_xdata(), line.get_ydata()
        assert len(xs) > 2, f"the arc {start} -> {end} is drawn as a straight segment"
        # a quarter circle of radius 1 about the cell of its 2x2 block that is not on the line
        # through the start along its heading
        vertical = start.heading.vector[0] == 0
        centre = (end.x, start.y) if vertical else (start.x, end.y)
        radii = [math.hypot(x - centre[0], y - centre[1]) for x, y in zip(xs, ys, strict=True)]
        assert radii == pytest.approx([1.0] * len(radii))


def test_initial_plan_follows_the_arcs_too(arc_picture: missionplot.MissionPicture) -> None:
    (plan,) = [line for line in _drawn(arc_picture).lines if line.get_gid() == "initial-plan"]
    points = set(zip(plan.get_xdata(), plan.get_ydata(), strict=True))
    assert {(p.x, p.y) for p in arc_picture.planned} <= points  # every pose of the plan on it
    assert len(points) > len(arc_picture.planned)  # and points along its arcs between them


@pytest.fixture(scope="module")
def deep_table_picture(tmp_path_factory: pytest.TempPathFactory) -> missionplot.MissionPicture:
    """A mission whose table is a file deep in a directory tree (as an experiment file's
    ``table = "..."`` becomes an absolute path in the trace)."""
    folder = tmp_path_factory.mktemp("tables")
    for part in ("a-rather-long-folder-name", "of-replacement-tables", "for-the-four-wheel-robot"):
        folder = folder / part
    folder.mkdir(parents=True)
    table = folder / "my-table.json"
    table.write_text(dump_table(bundled_table("handwritten")), encoding="utf-8")
    spec = MissionSpec(
        load_bundled("narrow-short"),
        parse_pose("1,1,E"),
        (13, 13),
        schedule=FaultSchedule.permanent(parse_faults("FL:F,RR:B")),
        strategy="replacement",
        options=StrategyOptions(table=str(table.resolve())),
    )
    trace = folder / "t.jsonl"
    write_trace(run_mission(spec), trace)
    return missionplot.picture_from_trace(read_trace(trace))


def test_mission_title_names_the_table_file_not_its_path(
    deep_table_picture: missionplot.MissionPicture,
) -> None:
    assert "my-table.json" in deep_table_picture.title
    assert (
        "/" not in deep_table_picture.title and "for-the-four-wheel" not in deep_table_picture.title
    )


def test_mission_title_fits_the_figure(
    deep_table_picture: missionplot.MissionPicture, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    figures: list[Any] = []
    monkeypatch.setattr(missionplot, "save", lambda fig, path: figures.append(fig) or path)
    long = replace(deep_table_picture, title=deep_table_picture.title + ", and more" * 12)
    for picture in (deep_table_picture, long):
        missionplot.figure_mission(picture, tmp_path / "mission.png")
        fig = figures[-1]
        fig.draw_without_rendering()
        title = fig.axes[0].title
        box = title.get_window_extent()
        assert box.x0 >= 0 and box.x1 <= fig.bbox.width, title.get_text()
        assert box.y0 >= 0 and box.y1 <= fig.bbox.height, title.get_text()
        assert title.get_fontsize() >= 6
        for legend in fig.legends:  # and clear of the legend
            assert box.x1 <= legend.get_window_extent().x0, title.get_text()
