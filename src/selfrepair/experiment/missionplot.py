"""One mission drawn: the maze, the initial plan, every executed step coloured by its source, and
every repair (the report's ``mission.png``, the animation's frames and their legend).

A :class:`MissionPicture` is what the drawing needs, read from a trace
(:func:`picture_from_trace`); :func:`draw_background`, :func:`draw_steps` and
:func:`mission_legend` draw it in parts so the animation can add steps frame by frame.
"""

from __future__ import annotations

import itertools
import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import TYPE_CHECKING

import numpy as np

from selfrepair.experiment.figstyle import WALL, colour_of, figure, save
from selfrepair.geometry import Cell, Pose, turn_corner
from selfrepair.optional import matplotlib
from selfrepair.repair.strategies import StrategyName
from selfrepair.world.maze import Maze

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.text import Text

    from selfrepair.execution.traceformat import Trace

__all__ = [
    "MissionPicture",
    "draw_background",
    "draw_mission",
    "draw_steps",
    "figure_mission",
    "fit_title",
    "mission_legend",
    "move_points",
    "path_points",
    "picture_from_trace",
    "robot_marker",
    "short_name",
]


@dataclass(frozen=True, slots=True)
class MissionPicture:
    """What a mission drawing needs: the maze, the route, the initial plan's poses, every
    executed step as ``(from, to, source)`` and every repair as ``(step index, pose, source)``
    (the repair happened before step ``index`` of :attr:`steps`; its source is what resolved it,
    or ``"failed"``)."""

    maze: Maze
    start: Pose
    goal: Cell
    planned: tuple[Pose, ...]
    steps: tuple[tuple[Pose, Pose, str], ...]
    faults: str
    title: str
    repairs: tuple[tuple[int, Pose, str], ...] = ()


def picture_from_trace(trace: Trace) -> MissionPicture:
    """A :class:`MissionPicture` from a parsed :class:`selfrepair.execution.trace.Trace`."""
    from selfrepair.execution.trace import spec_from_header

    spec = spec_from_header(trace.header, trace.source)
    domain = spec.domain
    poses = [spec.start]
    for code in trace.header.get("initial_plan", []):
        poses.append(domain.apply(poses[-1], domain.parse_action(code)))
    faults = domain.format_faults(spec.schedule.all_faults()) or "none"
    strategy = str(spec.strategy)
    if strategy != StrategyName.REPLAN:
        table = short_name(spec.options.table_label)
        strategy += f" [{table}, {spec.options.recursion.value}]"
    summary = trace.summary or {}
    status = summary.get("status", "?")
    title = (
        f"{short_name(spec.maze.name or 'maze')}: {spec.start} -> {spec.goal[0]},{spec.goal[1]}, "
        f"faults {faults}\n{strategy}, clearance weight {spec.clearance_weight}: {status}"
    )
    steps = tuple((s.start, s.end, s.source) for s in trace.steps)
    index = {s.step: i for i, s in enumerate(trace.steps)}
    repairs = tuple(
        (
            index.get(r.step, len(steps)),
            r.pose,
            str(r.source) if r.status == "repaired" else "failed",
        )
        for r in trace.repairs
    )
    return MissionPicture(
        spec.maze, spec.start, spec.goal, tuple(poses), steps, faults, title, repairs
    )


def short_name(label: str) -> str:
    """A file's name without its folders (a table or maze given by path), else ``label``."""
    return PurePath(label).name if "/" in label or "\\" in label else label


ARC_SAMPLES = 9
"""Points drawn along one arc (a quarter ellipse), ends included."""


def move_points(start: Pose, end: Pose) -> list[tuple[float, float]]:
    """The drawn path of one move from ``start`` to ``end``, both as the domain's ``apply``
    gives them: a quarter ellipse tangent to both headings when the move turns as it goes
    (:func:`~selfrepair.geometry.turn_corner`; a quarter circle for the four-wheel robot's
    arcs), else the straight segment."""
    corner = turn_corner(start, end)
    if corner is None:
        return [(start.x, start.y), (end.x, end.y)]
    cx, cy = start.x + end.x - corner[0], start.y + end.y - corner[1]
    angles = np.linspace(0.0, math.pi / 2, ARC_SAMPLES)
    return [
        (
            float(cx + (start.x - cx) * math.cos(t) + (end.x - cx) * math.sin(t)),
            float(cy + (start.y - cy) * math.cos(t) + (end.y - cy) * math.sin(t)),
        )
        for t in angles
    ]


def path_points(poses: Sequence[Pose]) -> list[tuple[float, float]]:
    """The drawn path through consecutive ``poses`` (one move between each two)."""
    points = [(float(poses[0].x), float(poses[0].y))] if poses else []
    for start, end in itertools.pairwise(poses):
        points += move_points(start, end)[1:]
    return points


def draw_background(ax: Axes, picture: MissionPicture) -> None:
    """The parts of a mission drawing that never change: maze, initial plan, start and goal."""
    maze = picture.maze
    mpl = matplotlib()
    cmap = mpl.colors.ListedColormap(["white", WALL])
    ax.imshow(
        maze.walls.astype(int),
        cmap=cmap,
        vmin=0,
        vmax=1,
        interpolation="nearest",
        extent=(-0.5, maze.width - 0.5, maze.height - 0.5, -0.5),
    )
    ax.grid(False)
    ax.set_xticks([])
    ax.set_yticks([])
    # The initial plan is drawn thin and dashed ABOVE the executed path (which is wider), so
    # both stay visible where they coincide.
    plan = path_points(picture.planned)
    ax.plot(
        [x for x, _ in plan],
        [y for _, y in plan],
        color=PLAN_COLOUR,
        linestyle=(0, (3, 2)),
        linewidth=1.3,
        zorder=PLAN_ZORDER,
        gid="initial-plan",
    )
    ax.plot(picture.start.x, picture.start.y, marker="o", color="#111111", markersize=9, zorder=7)
    ax.plot(
        *picture.goal,
        marker="*",
        color="#F0E442",
        markeredgecolor="#111111",
        markersize=15,
        zorder=7,
    )


PLAN_COLOUR = "#222222"
PLAN_ZORDER = 5
"""The initial plan is drawn above the executed steps (z-order 3 and 4)."""
REPAIR_ZORDER = 6


def draw_steps(ax: Axes, picture: MissionPicture, first: int, stop: int) -> None:
    """Executed steps ``first .. stop - 1``, coloured by source, and one X per repair made
    before them (coloured by what resolved it; red when it failed)."""
    if first >= stop and first > 0:
        return  # nothing new since the previous call (an animation's held last frame)
    maze = picture.maze
    width = max(1.8, 90 / max(maze.width, maze.height))
    for start, end, source in picture.steps[first:stop]:
        colour = colour_of(source, "#000000")
        if source == "failed-attempt":
            ax.plot(start.x, start.y, marker="x", color=colour, markersize=7, zorder=4, gid="step")
        elif start.cell == end.cell:
            ax.plot(
                start.x,
                start.y,
                marker="o",
                color=colour,
                markersize=width * 1.6,
                zorder=3,
                alpha=0.9,
                gid="step",
            )
        else:
            points = move_points(start, end)
            ax.plot(
                [x for x, _ in points],
                [y for _, y in points],
                color=colour,
                linewidth=width,
                solid_capstyle="round",
                zorder=3 if source == "plan" else 4,
                gid="step",
            )
    last = stop >= len(picture.steps)
    for index, pose, source in picture.repairs:
        if first <= index < stop or (last and index >= len(picture.steps)):
            ax.plot(
                pose.x,
                pose.y,
                marker="X",
                color=colour_of(source, "#D55E00"),
                markersize=8,
                markeredgecolor="#111111",
                markeredgewidth=0.8,
                linestyle="",
                zorder=REPAIR_ZORDER,
                gid="repair",
            )


def robot_marker(pose: Pose) -> tuple[int, int, int]:
    """A triangle marker pointing along ``pose``'s heading (screen up is north)."""
    return (3, 0, -90 * pose.heading.value)


def draw_mission(ax: Axes, picture: MissionPicture) -> None:
    """The whole mission: maze, initial plan, every executed step, start and goal."""
    draw_background(ax, picture)
    draw_steps(ax, picture, 0, len(picture.steps))


def mission_legend(fig: Figure, picture: MissionPicture, *, with_robot: bool = False) -> None:
    """A legend for :func:`draw_mission` listing only the sources that occur."""
    from matplotlib.lines import Line2D

    used = {s for _, _, s in picture.steps}
    handles = [Line2D([], [], color=PLAN_COLOUR, linestyle=(0, (3, 2)), label="initial plan")]
    names = {
        "plan": "executed: plan",
        "replacement": "executed: table replacement",
        "lookahead": "executed: lookahead window",
        "replan": "executed: replanned",
        "failed-attempt": "failed attempt",
    }
    for source, label in names.items():
        if source == "failed-attempt" and source in used:
            handles.append(
                Line2D(
                    [],
                    [],
                    color=colour_of(source, "#000000"),
                    marker="x",
                    linestyle="",
                    label=label,
                )
            )
        elif source in used:
            handles.append(
                Line2D([], [], color=colour_of(source, "#000000"), linewidth=3, label=label)
            )
    if picture.repairs:
        handles.append(
            Line2D(
                [],
                [],
                marker="X",
                color="#bbbbbb",
                linestyle="",
                markeredgecolor="#111111",
                markersize=8,
                label=f"repair ({len(picture.repairs)}; colour: what resolved it)",
            )
        )
    handles += [
        Line2D([], [], marker="o", color="#111111", linestyle="", label="start"),
        Line2D(
            [],
            [],
            marker="*",
            color="#F0E442",
            markeredgecolor="#111111",
            linestyle="",
            markersize=13,
            label="goal",
        ),
    ]
    if with_robot:
        handles.append(
            Line2D(
                [],
                [],
                marker=(3, 0, -90),
                color="#D55E00",
                linestyle="",
                markeredgecolor="#111111",
                markersize=10,
                label="robot",
            )
        )
    fig.legend(handles=handles, loc="outside right upper", fontsize=8)


def fit_title(
    fig: Figure, ax: Axes, text: str, *, fontsize: float = 9, smallest: float = 6.5
) -> Text:
    """Set ``text`` as the title of ``ax`` so that it fits: centred on the axes, between the
    figure's left edge and its legend (or right edge). The font shrinks from ``fontsize`` to
    ``smallest`` as needed; a title still too wide is wrapped at spaces. Measured with
    matplotlib's renderer after the layout is done; returns the title artist."""
    title = ax.set_title(text, fontsize=fontsize)
    lines = text.splitlines()
    width = max(map(len, lines), default=0)
    for _ in range(8):
        fig.draw_without_rendering()  # the constrained layout moves the axes as the title changes
        box = title.get_window_extent()
        frame = ax.get_window_extent()
        centre = (frame.x0 + frame.x1) / 2
        right = min((legend.get_window_extent().x0 for legend in fig.legends), default=fig.bbox.x1)
        room = 2 * min(centre - fig.bbox.x0, right - centre) - 8  # a few pixels clear
        if box.width <= room and box.y1 <= fig.bbox.y1:
            break
        ratio = room / box.width
        size = float(title.get_fontsize())  # points (matplotlib types it float | str)
        if size > smallest:
            title.set_fontsize(max(smallest, size * min(ratio, 0.95)))
        else:
            width = max(12, int(width * min(ratio, 0.9)))
            wrapped = [part for line in lines for part in textwrap.wrap(line, width) or [""]]
            title.set_text("\n".join(wrapped))
    return title


def figure_mission(picture: MissionPicture, path: Path) -> Path:
    """One mission: maze, planned and executed paths, repairs and replaced segments."""
    size = 7.0 * min(1.0, max(0.6, picture.maze.width / 40))
    with figure(size + 2.6, size * picture.maze.height / picture.maze.width + 0.8) as (fig, (ax,)):
        draw_mission(ax, picture)
        mission_legend(fig, picture)
        fit_title(fig, ax, picture.title)
        return save(fig, path)


# --- scale -------------------------------------------------------------------------------------
