"""Pictures of team traces: one frame as a PNG, or the whole mission as a GIF (matplotlib and
Pillow, extra ``viz``).

A frame shows the maze, every robot in its own colour (a triangle pointing along its heading,
its trail so far as a thin line, a red cross over it while it is immobilised, a red ring while
its gripper is broken), every item (a small square: grey and labelled on the floor, in its
carrier's colour while carried, light green once delivered) with its drop-off cell (a hollow
square), and the cells blocked at that moment (red). The title gives the strategy, the tick
and the latest incident or repair.
Only traces that re-simulate (:func:`~selfrepair.team.trace.replay_team`) are drawn.

Plotting stays here, out of the engine; the module is imported only by the commands that draw.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from selfrepair.errors import TraceError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.limits import MAX_TRACE_BYTES
from selfrepair.optional import matplotlib
from selfrepair.team.model import ActionKind, TeamFaultKind
from selfrepair.team.trace import TeamTrace, read_team_trace, replay_team

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["ROBOT_COLOURS", "animate_team_trace", "draw_team_frame"]

ROBOT_COLOURS = (
    "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#F0E442", "#000000",
)  # fmt: skip
"""Okabe-Ito colours, one per robot (cycled beyond eight)."""
_WALL = "#3b3b3b"
_BLOCKED = "#d7301f"
_FLOOR_ITEM = "#7f7f7f"
_DELIVERED = "#b8e186"
_STYLE = {
    "figure.facecolor": "white",
    "axes.facecolor": "white",
    "savefig.facecolor": "white",
    "text.color": "#111111",
    "font.size": 9,
}
_MARKERS = {Heading.N: "^", Heading.E: ">", Heading.S: "v", Heading.W: "<"}



def _open(
    path: str | Path, out: str | Path, suffix: str, max_trace_bytes: int | None
) -> tuple[ModuleType, TeamTrace]:
    """Refuse an ``out`` not ending in ``suffix``, then load matplotlib and the trace at
    ``path``, which must re-simulate (what drawing a frame and animating both start with)."""
    if not str(out).lower().endswith(suffix):
        raise TraceError(f"expected an output file ending in {suffix}", source=str(out))
    mpl = matplotlib()
    trace = read_team_trace(path, max_trace_bytes=max_trace_bytes)
    report = replay_team(trace)
    if not report.ok:
        raise TraceError(f"the trace does not re-simulate: {report}", source=str(path))
    return mpl, trace


@dataclass(frozen=True, slots=True)
class _Moment:
    """What a frame shows at one unit of time."""

    poses: dict[str, tuple[float, float, Heading]]
    trails: dict[str, list[Cell]]
    items: dict[str, tuple[Cell, str]]
    delivered: set[str]
    blocked: set[Cell]
    immobile: set[str]
    no_gripper: set[str]
    caption: str


def _moment(trace: TeamTrace, t: int) -> _Moment:
    scenario = trace.scenario
    poses: dict[str, tuple[float, float, Heading]] = {}
    trails: dict[str, list[Cell]] = {}
    cells: dict[str, Cell] = {}
    for robot in scenario.robots:
        pose: Pose = robot.start
        trail = [robot.start.cell]
        x, y = float(pose.x), float(pose.y)
        for m in trace.moves:
            if m.robot != robot.name or m.start > t:
                continue
            if m.end <= t:
                pose = m.after
                x, y = float(pose.x), float(pose.y)
                trail.append(pose.cell)
            else:
                share = (t - m.start) / (m.end - m.start)
                x = m.before.x + share * (m.after.x - m.before.x)
                y = m.before.y + share * (m.after.y - m.before.y)
                pose = m.before
        poses[robot.name] = (x, y, pose.heading)
        trails[robot.name] = trail
        cells[robot.name] = pose.cell
    items = {task.item: (task.pickup, "") for task in scenario.tasks}
    delivered: set[str] = set()
    for act in trace.acts:
        if act.end > t:
            continue
        a = act.action
        if a.kind is ActionKind.PICK:
            items[a.item] = (act.cells[0], a.robot)
        elif a.kind is ActionKind.HANDOVER:
            items[a.item] = (act.cells[1], a.taker)
        else:
            items[a.item] = (act.cells[0], "")
            if act.cells[0] == scenario.task(a.item).dropoff:
                delivered.add(a.item)
    items = {i: (cells[h] if h else c, h) for i, (c, h) in items.items()}
    blocked: set[Cell] = set()
    immobile: set[str] = set()
    no_gripper: set[str] = set()
    active: dict[int, bool] = {}
    for f in trace.faults:
        if f.at <= t:
            active[f.index] = f.active
    for index, on in active.items():
        fault = scenario.faults[index]
        if not on:
            continue
        if fault.kind is TeamFaultKind.BLOCKED:
            blocked.update(fault.cells)
        elif fault.kind is TeamFaultKind.IMMOBILISED:
            immobile.add(fault.robot)
        elif fault.kind is TeamFaultKind.GRIPPER:
            no_gripper.add(fault.robot)
    return _Moment(
        poses, trails, items, delivered, blocked, immobile, no_gripper, _caption(trace, t)
    )


def _caption(trace: TeamTrace, t: int) -> str:
    latest = ""
    for line in trace.other:
        at = line.get("at")
        if not isinstance(at, int) or at > t:
            continue
        if line.get("type") == "incident":
            latest = f"incident: {line.get('robot')} {line.get('kind')} at {line.get('action')}"
        elif line.get("type") == "repair":
            how = line.get("candidate") or line.get("source")
            helper = f" with {line.get('helper')}" if line.get("helper") else ""
            latest = f"repair: {how}{helper} ({line.get('outcome')})"
    return latest


def _draw(ax: Axes, trace: TeamTrace, moment: _Moment, t: int) -> None:
    import numpy as np
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Rectangle

    scenario = trace.scenario
    maze = scenario.maze
    ax.clear()
    ax.imshow(
        np.asarray(maze.walls, dtype=float), cmap=ListedColormap(["white", _WALL]),
        interpolation="nearest", vmin=0, vmax=1,
    )  # fmt: skip
    for bx, by in moment.blocked:
        ax.add_patch(Rectangle((bx - 0.5, by - 0.5), 1, 1, color=_BLOCKED, alpha=0.8, zorder=2))
    colour = {r.name: ROBOT_COLOURS[i % len(ROBOT_COLOURS)] for i, r in enumerate(scenario.robots)}
    for task in scenario.tasks:
        tx, ty = task.dropoff
        ax.add_patch(
            Rectangle((tx - 0.35, ty - 0.35), 0.7, 0.7, fill=False, edgecolor="#555555", lw=1.0,
                      zorder=3)
        )  # fmt: skip
    for name, trail in moment.trails.items():
        xs, ys = zip(*trail, strict=True)
        ax.plot(xs, ys, color=colour[name], lw=1.2, alpha=0.55, zorder=4)
    for item, ((ix, iy), holder) in moment.items.items():
        fill = _DELIVERED if item in moment.delivered else colour.get(holder, _FLOOR_ITEM)
        dx, dy = (0.28, -0.28) if holder else (0.0, 0.0)
        ax.add_patch(
            Rectangle((ix + dx - 0.18, iy + dy - 0.18), 0.36, 0.36, facecolor=fill,
                      edgecolor="#111111", lw=0.6, zorder=7)
        )  # fmt: skip
        if not holder:
            ax.annotate(item, (ix, iy), xytext=(-4, -11), textcoords="offset points", fontsize=6,
                        color="#444444", zorder=8)  # fmt: skip
    for name, (x, y, heading) in moment.poses.items():
        ax.plot([x], [y], marker=_MARKERS[heading], color=colour[name], markersize=9,
                markeredgecolor="#111111", linestyle="", zorder=6)  # fmt: skip
        ax.annotate(name, (x, y), xytext=(5, 5), textcoords="offset points", fontsize=7, zorder=8)
        if name in moment.immobile:
            ax.plot([x], [y], marker="x", color=_BLOCKED, markersize=12, mew=2.2, zorder=9)
        if name in moment.no_gripper:
            ax.plot([x], [y], marker="o", fillstyle="none", color=_BLOCKED, markersize=13, zorder=9)
    ax.set_xlim(-0.5, maze.width - 0.5)
    ax.set_ylim(maze.height - 0.5, -0.5)
    ax.set_xticks([])
    ax.set_yticks([])
    done = len(moment.delivered)
    title = (
        f"{scenario.name}: {trace.options.label}, tick {t / trace.scale:.1f}, "
        f"{done}/{len(scenario.tasks)} delivered"
    )
    ax.set_title(title + (f"\n{moment.caption}" if moment.caption else "\n "), fontsize=8)


def _default_tick(trace: TeamTrace) -> int:
    handovers = [a.start for a in trace.acts if a.action.kind is ActionKind.HANDOVER]
    if handovers:
        return min(handovers) + 1
    repairs = [int(line["at"]) for line in trace.other if line.get("type") == "repair"]
    if repairs:
        return min(repairs) + 1
    return max((m.end for m in trace.moves), default=0)


def draw_team_frame(
    trace_path: str | Path,
    out: str | Path,
    *,
    tick: float | None = None,
    max_trace_bytes: int | None = MAX_TRACE_BYTES,
) -> Path:
    """Draw one moment of a team trace (default: the first handover, else the first repair)."""
    mpl, trace = _open(trace_path, out, ".png", max_trace_bytes)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    t = _default_tick(trace) if tick is None else round(tick * trace.scale)
    if t < 0:
        raise TraceError(f"expected a tick >= 0, got {tick}", source=str(trace_path))
    maze = trace.scenario.maze
    with mpl.rc_context(_STYLE):
        fig = Figure(figsize=(6.4, 6.4 * maze.height / maze.width + 0.5), dpi=100)
        ax = fig.subplots()
        _draw(ax, trace, _moment(trace, t), t)
        fig.tight_layout()
        FigureCanvasAgg(fig).print_png(str(out))  # type: ignore[no-untyped-call]
    return Path(out)


def animate_team_trace(
    trace_path: str | Path,
    out: str | Path,
    *,
    fps: int = 4,
    max_frames: int = 120,
    max_trace_bytes: int | None = MAX_TRACE_BYTES,
) -> int:
    """Write a GIF of a team trace; returns the number of frames (the last one held)."""
    mpl, trace = _open(trace_path, out, ".gif", max_trace_bytes)
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.figure import Figure

    end = max([m.end for m in trace.moves] + [a.end for a in trace.acts] + [1])
    step = max(trace.scale, -(-end // max(1, max_frames)))
    frames = [*range(0, end + 1, step)]
    if frames[-1] != end:
        frames.append(end)
    frames += [end] * fps
    maze = trace.scenario.maze
    with mpl.rc_context(_STYLE):
        fig = Figure(figsize=(5.6, 5.6 * maze.height / maze.width + 0.5), dpi=80)
        ax = fig.subplots()

        def draw(t: int) -> list[Any]:  # matplotlib artists (none: blit is off)
            _draw(ax, trace, _moment(trace, t), t)
            return []

        animation = FuncAnimation(fig, draw, frames=frames, blit=False, repeat=False)
        animation.save(
            str(out), writer=PillowWriter(fps=fps), savefig_kwargs={"facecolor": "white"}
        )
    return len(frames)
