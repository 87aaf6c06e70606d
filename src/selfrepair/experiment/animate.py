"""Animate a mission trace as a GIF (matplotlib animation, Pillow writer; extra ``viz``).

A team trace (:mod:`selfrepair.team.trace`) is drawn by
:func:`selfrepair.team.draw.animate_team_trace`.

Each frame shows the maze, the initial plan (dark dashes, over the executed path), the steps
executed so far coloured by where their action came from (plan, table replacement, lookahead,
replan, failed attempt), an X for each repair, the robot as a triangle pointing along its
heading, and the step, its source and the faults known at that moment in the title. The last
frame is held for a second.

Frames are drawn incrementally (the maze and plan once, then only the new steps), and long
traces are subsampled to at most ``max_frames`` frames; every step is still drawn. The GIF writer
merges identical consecutive frames (the held last frame becomes one longer frame), so
:func:`animate_trace` counts the frames in the file it wrote. ``on_frame(done, total)`` is called
after each frame is drawn, for a progress bar.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from selfrepair.errors import TraceError
from selfrepair.limits import MAX_TRACE_BYTES

__all__ = ["MAX_FRAMES", "animate_trace", "gif_frames"]

MAX_FRAMES = 120
"""Default bound on the number of frames (before the held last frame)."""


def animate_trace(
    trace: str | Path,
    out: str | Path,
    *,
    fps: int = 4,
    max_frames: int = MAX_FRAMES,
    on_frame: Callable[[int, int], None] | None = None,
    max_trace_bytes: int | None = MAX_TRACE_BYTES,
) -> int:
    """Write a GIF of the mission in ``trace`` to ``out``; returns the number of frames in the
    file written. A trace file over ``max_trace_bytes`` is refused unread."""
    from selfrepair.execution.trace import read_trace, replay
    from selfrepair.experiment import figstyle, missionplot
    from selfrepair.optional import matplotlib
    from selfrepair.team.trace import is_team_trace

    if is_team_trace(trace):  # several robots: one colour each, items drawn
        from selfrepair.team.draw import animate_team_trace

        return animate_team_trace(
            trace, out, fps=fps, max_frames=max_frames, max_trace_bytes=max_trace_bytes
        )
    if not str(out).lower().endswith(".gif"):
        raise TraceError("expected an output file ending in .gif", source=str(out))
    mpl = matplotlib()
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    parsed = read_trace(trace, max_trace_bytes=max_trace_bytes)
    check = replay(parsed)  # draw only what the robot model says happened
    if not check.ok:
        raise TraceError(f"the trace does not replay: {check}", source=str(trace))
    picture = missionplot.picture_from_trace(parsed)
    total = len(picture.steps)
    stride = max(1, -(-total // max(1, max_frames)))
    frames = [*range(0, total + 1, stride)]
    if frames[-1] != total:
        frames.append(total)
    frames += [total] * fps
    known = [",".join(sorted(str(f) for f in s.known)) or "none" for s in parsed.steps]
    maze = picture.maze
    headline = picture.title.splitlines()[0]
    with mpl.rc_context(figstyle.STYLE):
        size = 6.0 * min(1.0, max(0.6, maze.width / 40))
        fig = Figure(
            figsize=(size + 2.4, size * maze.height / maze.width + 0.9),
            dpi=80,
            layout="constrained",
        )
        ax = fig.subplots()
        missionplot.draw_background(ax, picture)
        missionplot.mission_legend(fig, picture, with_robot=True)
        (robot,) = ax.plot(
            [picture.start.x],
            [picture.start.y],
            linestyle="",
            marker=missionplot.robot_marker(picture.start),
            color="#D55E00",
            markeredgecolor="#111111",
            markersize=10,
            zorder=8,
        )
        title = ax.set_title(f"{headline}\nstart", fontsize=8)
        FigureCanvasAgg(fig).draw()  # type: ignore[no-untyped-call]  # lay out once, then keep the layout fixed for speed
        fig.set_layout_engine("none")
        drawn = [0]

        def draw(upto: int) -> list[Any]:  # matplotlib artists (matplotlib is untyped)
            missionplot.draw_steps(ax, picture, drawn[0], upto)
            drawn[0] = max(drawn[0], upto)
            if upto > 0:
                pose = picture.steps[upto - 1][1]
                robot.set_data([pose.x], [pose.y])
                robot.set_marker(missionplot.robot_marker(pose))  # type: ignore[arg-type]
                source = picture.steps[upto - 1][2]
                title.set_text(
                    f"{headline}\nstep {upto}/{total}: {source}; known faults {known[upto - 1]}"
                )
            return []

        animation = FuncAnimation(fig, draw, frames=frames, blit=False, repeat=False)
        animation.save(
            str(out),
            writer=PillowWriter(fps=fps),
            savefig_kwargs={"facecolor": "white"},
            progress_callback=(
                None if on_frame is None else lambda done, total: on_frame(done + 1, total)
            ),
        )
    return gif_frames(out)


def gif_frames(path: str | Path) -> int:
    """The number of frames in the GIF file ``path``."""
    from PIL import Image

    with Image.open(path) as image:
        return int(getattr(image, "n_frames", 1))
