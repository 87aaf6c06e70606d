"""The report's figures and captions: a visible initial plan and one mark per repair in the
mission picture, a readable heat map for many fault sets, no empty clearance figure, and
singular nouns for one."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from extras import need
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.trace import read_trace, write_trace
from selfrepair.experiment import plots
from selfrepair.experiment.report import counted, render_markdown
from selfrepair.geometry import parse_pose
from selfrepair.robots.four_wheel import parse_faults
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
def picture(trace_file: Path) -> plots.MissionPicture:
    return plots.picture_from_trace(read_trace(trace_file))


def _drawn(picture: plots.MissionPicture) -> Any:
    fig = new_figure()
    ax = fig.subplots()
    plots.draw_mission(ax, picture)
    return ax


def test_mission_picture_marks_every_repair(picture: plots.MissionPicture) -> None:
    assert len(picture.repairs) > 10  # the replacing robot meets its faulty actions again
    marks = [line for line in _drawn(picture).lines if line.get_gid() == "repair"]
    assert len(marks) == len(picture.repairs)
    assert [(m.get_xdata()[0], m.get_ydata()[0]) for m in marks] == [
        (pose.x, pose.y) for _, pose, _ in picture.repairs
    ]


def test_initial_plan_is_drawn_over_the_executed_path(picture: plots.MissionPicture) -> None:
    ax = _drawn(picture)
    (plan,) = [line for line in ax.lines if line.get_gid() == "initial-plan"]
    executed = [line for line in ax.lines if line.get_gid() == "step"]
    assert executed and plan.get_zorder() > max(line.get_zorder() for line in executed)
    assert len(plan.get_xdata()) == len(picture.planned)


def test_animation_marks_each_repair_once(picture: plots.MissionPicture) -> None:
    fig = new_figure()
    ax = fig.subplots()
    plots.draw_background(ax, picture)
    total = len(picture.steps)
    drawn = 0
    for upto in [*range(0, total + 1, 7), total, total, total]:  # held last frames
        plots.draw_steps(ax, picture, drawn, upto)
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
