"""Figures of the experiment report (matplotlib, PNG; needs the ``viz`` extra).

Every figure is drawn with matplotlib's object API (no pyplot state, no GUI backend) on an
explicitly white background with dark text, so it reads the same in light and dark viewers.
Colours come from the Okabe-Ito palette, which stays distinguishable for colour-blind readers.
Functions take result rows (dicts from the store) and a path, and return the path written.
"""

from __future__ import annotations

import itertools
import math
import textwrap
from collections import defaultdict
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path, PurePath
from typing import Any

import numpy as np

from selfrepair.experiment.findings import (
    NEGLIGIBLE,
    Row,
    group_label,
    repairs_of,
)
from selfrepair.experiment.scale import Crossover
from selfrepair.experiment.summary import is_reference_replan
from selfrepair.geometry import Cell, Pose, turn_corner
from selfrepair.optional import matplotlib
from selfrepair.repair.strategies import RepairSource, StrategyName
from selfrepair.stats import lower_median, percentile
from selfrepair.world.maze import Maze

__all__ = [
    "SOURCE_COLOURS",
    "MissionPicture",
    "draw_mission",
    "figure_baselines",
    "figure_clearance",
    "figure_heatmap",
    "figure_latency",
    "figure_latency_vs_size",
    "figure_mission",
    "fit_title",
    "move_points",
    "picture_from_trace",
]

OKABE_ITO = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#F0E442", "#000000")
SOURCE_COLOURS = {
    "plan": "#0072B2",
    "replacement": "#009E73",
    "lookahead": "#CC79A7",
    "replan": "#E69F00",
    "plan-repair": "#56B4E9",
    "failed-attempt": "#D55E00",
}
WALL = "#3b3b3b"
STYLE = {
    "figure.facecolor": "white",
    "axes.facecolor": "white",
    "savefig.facecolor": "white",
    "savefig.edgecolor": "white",
    "text.color": "#111111",
    "axes.labelcolor": "#111111",
    "axes.edgecolor": "#333333",
    "xtick.color": "#111111",
    "ytick.color": "#111111",
    "axes.grid": True,
    "grid.color": "#d9d9d9",
    "grid.linewidth": 0.6,
    "font.size": 10,
    "axes.titlesize": 11,
    "legend.framealpha": 1.0,
    "legend.facecolor": "white",
}


@contextmanager
def _figure(width: float, height: float, ncols: int = 1) -> Iterator[tuple[Any, Any]]:
    """A white figure with ``ncols`` axes in the report's style."""
    mpl = matplotlib()
    from matplotlib.figure import Figure

    with mpl.rc_context(STYLE):
        fig = Figure(figsize=(width, height), dpi=110, layout="constrained")
        axes = fig.subplots(1, ncols, squeeze=False)[0]
        yield fig, axes


def _save(fig: Any, path: Path) -> Path:
    fig.savefig(path, format="png", facecolor="white", transparent=False)
    return path


def _weight(row: Row) -> Fraction:
    return Fraction(str(row.get("clearance_weight") or "0"))


# --- latency -----------------------------------------------------------------------------------


def figure_latency(rows: Sequence[Row], path: Path) -> Path:
    """Repair latency distributions per strategy variant (weight 0), horizontal box plots on a
    log scale; whiskers at the 1st and 99th percentiles; table hits and replans of the
    replacement variants are shown as separate boxes."""
    groups: dict[str, list[float]] = defaultdict(list)
    for row in rows:
        if _weight(row) != 0:
            continue
        label = group_label(row)
        for source, latency in repairs_of(row):
            key = label if row.get("strategy") == StrategyName.REPLAN else f"{label}: {source}"
            groups[key].append(latency / 1000)
    labels = sorted(groups, key=lambda k: lower_median(groups[k]) if groups[k] else 0)
    with _figure(9.5, 1.2 + 0.42 * max(1, len(labels))) as (fig, (ax,)):
        if not labels:
            ax.text(0.5, 0.5, "no repairs in these results", ha="center", transform=ax.transAxes)
        else:
            data = [groups[k] for k in labels]
            box = ax.boxplot(
                data,
                orientation="horizontal",
                whis=(1, 99),
                showfliers=False,
                patch_artist=True,
                medianprops={"color": "#111111", "linewidth": 1.5},
            )
            for patch, label in zip(box["boxes"], labels, strict=True):
                source = label.rsplit(": ", 1)[-1] if ": " in label else RepairSource.REPLAN
                patch.set_facecolor(SOURCE_COLOURS.get(source, "#999999"))
                patch.set_alpha(0.8)
            ax.set_yticks(range(1, len(labels) + 1), [f"{k} (n={len(groups[k])})" for k in labels])
            ax.set_xscale("log")
            ax.set_xlabel("repair latency (µs, log scale)")
        fig.suptitle(
            "Repair latency per strategy and repair kind, clearance weight 0\n"
            "box: quartiles and median; whiskers: 1st to 99th percentile",
            fontsize=11,
        )
        return _save(fig, path)


def figure_latency_vs_size(rows: Sequence[Row], path: Path) -> Path:
    """Median repair latency (with the 99th percentile as a bar) against maze size, for replans
    of the replanning robot and table hits of the replacing robot."""
    series: dict[str, dict[int, list[float]]] = {
        "replan (replanning robot)": defaultdict(list),
        "table hit (replacing robot)": defaultdict(list),
    }
    names: dict[int, set[str]] = defaultdict(set)
    for row in rows:
        if _weight(row) != 0:
            continue
        cells = row.get("maze_free_cells")
        if not isinstance(cells, int):
            continue
        for source, latency in repairs_of(row):
            if is_reference_replan(row) and source == RepairSource.REPLAN:
                series["replan (replanning robot)"][cells].append(latency / 1000)
            elif (
                row.get("strategy") == StrategyName.REPLACEMENT
                and source == RepairSource.REPLACEMENT
            ):
                series["table hit (replacing robot)"][cells].append(latency / 1000)
            else:
                continue
            names[cells].add(str(row.get("maze")))
    with _figure(7.0, 4.8) as (fig, (ax,)):
        for (label, by_size), colour in zip(series.items(), ("#E69F00", "#009E73"), strict=True):
            sizes = sorted(by_size)
            if not sizes:
                continue
            med = np.array([lower_median(by_size[s]) for s in sizes], dtype=float)
            p99 = np.array([percentile(by_size[s], 0.99) for s in sizes], dtype=float)
            ax.errorbar(
                sizes,
                med,
                yerr=[np.zeros_like(med), p99 - med],
                marker="o",
                color=colour,
                capsize=4,
                label=f"{label}: median, bar to p99",
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("maze size (free cells, log scale)")
        ax.set_ylabel("repair latency (µs, log scale)")
        sizes = sorted(names)
        ax.set_xticks(sizes, [f"{c}\n" + "\n".join(sorted(names[c])) for c in sizes], fontsize=8)
        ax.minorticks_off()
        if sizes:
            ax.set_xlim(sizes[0] / 1.4, sizes[-1] * 1.4)
        ax.set_title("How repair latency grows with maze size")
        if ax.get_legend_handles_labels()[0]:
            fig.legend(loc="outside lower center", fontsize=8, ncols=2)
        return _save(fig, path)


# --- clearance -----------------------------------------------------------------------------------


def figure_clearance(rows: Sequence[Row], path: Path) -> Path | None:
    """Share of faulty encounters resolved by replacement, and mean extra ticks, against the
    clearance weight, one line per table and recursion mode. ``None`` (nothing written) when no
    replacement variant ran at two weights or more: there would be nothing to draw."""
    groups: dict[str, dict[Fraction, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        if row.get("strategy") == StrategyName.REPLACEMENT:
            groups[str(row.get("variant"))][_weight(row)].append(row)
    groups = {k: v for k, v in groups.items() if len(v) > 1}
    if not groups:
        return None
    with _figure(10.0, 4.0, ncols=2) as (fig, (left, right)):
        weights = sorted({w for g in groups.values() for w in g})
        positions = {w: i for i, w in enumerate(weights)}
        for (label, by_weight), colour in zip(sorted(groups.items()), OKABE_ITO, strict=False):
            ws = sorted(by_weight)
            xs = [positions[w] for w in ws]
            shares, extra = [], []
            for w in ws:
                enc = sum(float(r.get("faulty_encounters") or 0) for r in by_weight[w])
                rep = sum(float(r.get("replacements") or 0) for r in by_weight[w])
                shares.append(100 * rep / enc if enc else math.nan)
                ticks = [
                    float(v)
                    for r in by_weight[w]
                    if isinstance(v := r.get("extra_ticks"), int | float)
                ]
                extra.append(sum(ticks) / len(ticks) if ticks else math.nan)
            left.plot(xs, shares, marker="o", color=colour, label=label)
            right.plot(xs, extra, marker="o", color=colour, label=label)
        for ax in (left, right):
            ax.set_xticks(range(len(weights)), [str(w) for w in weights])
            ax.set_xlabel("clearance weight")
        left.set_ylabel("encounters resolved by replacement (%)")
        left.set_title("Replacement success vs clearance weight")
        right.set_ylabel("mean extra ticks vs fault-free plan")
        right.set_title("Price paid in execution time")
        # Below the axes, never on top of a data point.
        fig.legend(*left.get_legend_handles_labels(), loc="outside lower center", ncols=2)
        return _save(fig, path)


# --- heat map ----------------------------------------------------------------------------------


def heatmap_variant(rows: Sequence[Row]) -> str | None:
    """The variant drawn in the heat map: the hand-written table without recursion if present,
    else the first replacement variant, else the first variant (all at weight 0)."""
    variants = sorted({str(r.get("variant")) for r in rows if _weight(r) == 0})
    for wanted in ("replacement[handwritten,flat]", "replacement[handwritten,guarded]"):
        if wanted in variants:
            return wanted
    replacing = [v for v in variants if v.startswith(StrategyName.REPLACEMENT)]
    chosen = replacing or variants
    return chosen[0] if chosen else None


def figure_heatmap(rows: Sequence[Row], path: Path, variant: str | None = None) -> Path:
    """Fault set x maze: share of encounters resolved locally and mean extra ticks."""
    variant = variant or heatmap_variant(rows)
    chosen = [r for r in rows if str(r.get("variant")) == variant and _weight(r) == 0]
    mazes = sorted({str(r.get("maze")) for r in chosen}, key=lambda m: (_first_int(chosen, m), m))
    faults = sorted({str(r.get("faults")) for r in chosen}, key=lambda f: (f.count(","), f))
    share = np.full((len(faults), len(mazes)), np.nan)
    extra = np.full((len(faults), len(mazes)), np.nan)
    for i, f in enumerate(faults):
        for j, m in enumerate(mazes):
            cell = [r for r in chosen if r.get("faults") == f and r.get("maze") == m]
            enc = sum(float(r.get("faulty_encounters") or 0) for r in cell)
            res = sum(
                float(r.get("replacements") or 0) + float(r.get("lookaheads") or 0) for r in cell
            )
            if enc:
                share[i, j] = 100 * res / enc
            ticks = [float(v) for r in cell if isinstance(v := r.get("extra_ticks"), int | float)]
            if ticks:
                extra[i, j] = sum(ticks) / len(ticks)
    numbers = len(faults) <= HEATMAP_NUMBERED_ROWS
    row_height = 0.32 if numbers else 0.13
    with _figure(
        3.0 + 1.35 * max(2, len(mazes)) * 2, 1.6 + row_height * max(4, len(faults)), ncols=2
    ) as (fig, (left, right)):
        _heat(
            fig,
            left,
            share,
            faults,
            mazes,
            "encounters resolved locally (%)",
            "viridis",
            (0, 100),
            "{:.0f}" if numbers else None,
        )
        _heat(
            fig,
            right,
            extra,
            faults,
            mazes,
            "mean extra ticks vs fault-free plan",
            "magma_r",
            None,
            "{:.1f}" if numbers else None,
        )
        right.set_yticks(range(len(faults)), [""] * len(faults))
        fig.suptitle(f"{variant}, clearance weight 0 (grey: no faulty encounter)")
        return _save(fig, path)


HEATMAP_NUMBERED_ROWS = 30
"""Up to this many fault sets the heat map prints each cell's value; with more (the 78 fault sets
of the full study) the rows are drawn thinner, with smaller labels and colour alone, so the
figure stays a readable size."""


def _first_int(rows: Sequence[Row], maze: str) -> int:
    for r in rows:
        if r.get("maze") == maze and isinstance(v := r.get("maze_free_cells"), int):
            return v
    return 0


def _heat(
    fig: Any,
    ax: Any,
    data: Any,
    faults: list[str],
    mazes: list[str],
    label: str,
    cmap_name: str,
    limits: tuple[float, float] | None,
    fmt: str | None,
) -> None:
    mpl = matplotlib()
    cmap = mpl.colormaps[cmap_name].with_extremes(bad="#cccccc")
    finite = data[np.isfinite(data)]
    lo, hi = (
        limits
        if limits
        else ((float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0))
    )
    if hi <= lo:
        hi = lo + 1
    image = ax.imshow(np.ma.masked_invalid(data), cmap=cmap, vmin=lo, vmax=hi, aspect="auto")
    ax.grid(False)
    ax.set_xticks(range(len(mazes)), mazes, rotation=20, ha="right")
    ax.set_yticks(range(len(faults)), faults, fontsize=None if fmt is not None else 6)
    fig.colorbar(image, ax=ax, label=label, shrink=0.9)
    if fmt is None:
        return
    for (i, j), value in np.ndenumerate(data):
        if math.isfinite(value):
            r, g, b, _ = cmap((value - lo) / (hi - lo))
            light = 0.299 * r + 0.587 * g + 0.114 * b > 0.5
            ax.text(
                j,
                i,
                fmt.format(value),
                ha="center",
                va="center",
                fontsize=7,
                color="#111111" if light else "white",
            )
        else:
            ax.text(j, i, "-", ha="center", va="center", fontsize=7, color="#555555")


# --- one mission ---------------------------------------------------------------------------------


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


def picture_from_trace(trace: Any) -> MissionPicture:
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


def draw_background(ax: Any, picture: MissionPicture) -> None:
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


def draw_steps(ax: Any, picture: MissionPicture, first: int, stop: int) -> None:
    """Executed steps ``first .. stop - 1``, coloured by source, and one X per repair made
    before them (coloured by what resolved it; red when it failed)."""
    if first >= stop and first > 0:
        return  # nothing new since the previous call (an animation's held last frame)
    maze = picture.maze
    width = max(1.8, 90 / max(maze.width, maze.height))
    for start, end, source in picture.steps[first:stop]:
        colour = SOURCE_COLOURS.get(source, "#000000")
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
                color=SOURCE_COLOURS.get(source, "#D55E00"),
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


def draw_mission(ax: Any, picture: MissionPicture) -> None:
    """The whole mission: maze, initial plan, every executed step, start and goal."""
    draw_background(ax, picture)
    draw_steps(ax, picture, 0, len(picture.steps))


def mission_legend(fig: Any, picture: MissionPicture, *, with_robot: bool = False) -> None:
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
                Line2D([], [], color=SOURCE_COLOURS[source], marker="x", linestyle="", label=label)
            )
        elif source in used:
            handles.append(Line2D([], [], color=SOURCE_COLOURS[source], linewidth=3, label=label))
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


def fit_title(fig: Any, ax: Any, text: str, *, fontsize: float = 9, smallest: float = 6.5) -> Any:
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
        size = title.get_fontsize()
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
    with _figure(size + 2.6, size * picture.maze.height / picture.maze.width + 0.8) as (fig, (ax,)):
        draw_mission(ax, picture)
        mission_legend(fig, picture)
        fit_title(fig, ax, picture.title)
        return _save(fig, path)


# --- scale -------------------------------------------------------------------------------------


def figure_crossover(results: Sequence[Crossover], path: Path) -> Path:
    """Per maze, the median paired ratio of repair compute (replacing / replanning robot) with its
    95% interval against the maze side, log-log; the fitted line, the 1/10 threshold and the
    crossover side with its interval, one colour per replacement variant."""
    colours = ("#009E73", "#0072B2", "#D55E00", "#CC79A7", "#E69F00")
    with _figure(7.0, 4.8) as (fig, (ax,)):
        sides: list[float] = []
        for result, colour in zip(results, colours, strict=False):
            points = [m for m in result.mazes if m.ratio is not None]
            if not points:
                continue
            x = np.array([m.side for m in points])
            mid = np.array([m.ratio.estimate for m in points if m.ratio is not None])
            low = np.array([m.ratio.low for m in points if m.ratio is not None])
            high = np.array([m.ratio.high for m in points if m.ratio is not None])
            sides += list(x)
            ax.errorbar(
                x,
                mid,
                yerr=[mid - low, high - mid],
                fmt="o",
                color=colour,
                capsize=3,
                label=f"{result.variant}: median ratio, 95% interval",
            )
            if result.slope is not None and result.intercept is not None:
                ends = [min(x), max(x)]
                if result.side is not None and math.isfinite(result.side.estimate):
                    ends[1] = max(ends[1], result.side.estimate)
                line = np.geomspace(ends[0], ends[1], 50)
                ax.plot(line, np.exp(result.intercept) * line**result.slope, color=colour, lw=1)
            if result.side is not None and math.isfinite(result.side.estimate):
                ax.axvline(result.side.estimate, color=colour, ls="--", lw=1)
                if math.isfinite(result.side.high):
                    ax.axvspan(result.side.low, result.side.high, color=colour, alpha=0.12)
                sides.append(result.side.estimate)
        ax.axhline(NEGLIGIBLE, color="#333333", ls=":", lw=1, label=f"1/10 ({NEGLIGIBLE:g})")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("maze side (square root of the cells, log scale)")
        ax.set_ylabel("repair compute per mission, replacing / replanning")
        ax.set_title("Where replacement's repair compute falls below 1/10 of replanning")
        if ax.get_legend_handles_labels()[0]:
            fig.legend(loc="outside lower center", fontsize=8, ncols=1)
        return _save(fig, path)


# --- baselines -----------------------------------------------------------------------------------


def figure_baselines(rows: Sequence[Row], path: Path) -> Path:
    """Repair latency at the first faulty action (left) and repair time per mission (right) by
    strategy variant and maze (mazes by size, left to right): median with its 95% bootstrap
    interval, log scale (:func:`comparison.per_maze`)."""
    from selfrepair.experiment.comparison import FIRST_REPAIR, REPAIR_COMPUTE, per_maze

    panels = (
        (per_maze(rows, FIRST_REPAIR), "first repair latency (ms, log scale)"),
        (per_maze(rows, REPAIR_COMPUTE), "repair time per mission (ms, log scale)"),
    )
    labels = list(dict.fromkeys(m.label for cells, _ in panels for m in cells))
    markers = "osD^v<>Ph"
    colours = [c for c in OKABE_ITO if c != "#F0E442"] + ["#999999"]  # yellow is too pale
    with _figure(12.0, 5.0, ncols=2) as (fig, axes):
        for ax, (cells, ylabel) in zip(axes, panels, strict=True):
            mazes = list(dict.fromkeys((m.maze, m.free_cells) for m in cells))
            position = {maze: i for i, (maze, _) in enumerate(mazes)}
            width = 0.7 / max(1, len(labels))
            for k, label in enumerate(labels):
                mine = [m for m in cells if m.label == label]
                if not mine:
                    continue
                x = [position[m.maze] - 0.35 + width * (k + 0.5) for m in mine]
                mid = np.array([m.ms.estimate for m in mine])
                low = np.array([m.ms.low for m in mine])
                high = np.array([m.ms.high for m in mine])
                ax.errorbar(
                    x,
                    mid,
                    yerr=[mid - low, high - mid],
                    fmt=markers[k % len(markers)],
                    color=colours[k % len(colours)],
                    capsize=3,
                    label=label if ax is axes[0] else None,
                )
            ax.set_yscale("log")
            ax.set_xticks(range(len(mazes)), [f"{maze}\n{free} free cells" for maze, free in mazes])
            ax.set_ylabel(ylabel)
        fig.suptitle(
            "Repair latency by strategy and maze size: median and 95% bootstrap interval "
            "over missions that met a fault"
        )
        if labels:
            fig.legend(loc="outside lower center", fontsize=8, ncols=3)
        else:
            axes[0].text(0.5, 0.5, "no repairs", ha="center", transform=axes[0].transAxes)
        return _save(fig, path)
