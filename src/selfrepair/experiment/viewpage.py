"""The viewer's page machinery, shared by the mission page and the team page: the drawing
helpers every payload uses (poses, wall runs) and :func:`render_html`, which puts a payload, the
page template (``page.html``, with the page's own panel), its CSS and its script (the shared
``common.js``, then the page's own) into one HTML file that needs no server and no network:
everything is inline, and the page's content security policy forbids loading anything. The
files are package data in ``selfrepair/data/viewer/``.
"""

from __future__ import annotations

import html
import json
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Protocol, TypeVar

from selfrepair.errors import InputError, ProblemError, TraceError
from selfrepair.geometry import Pose
from selfrepair.textio import JSONObject
from selfrepair.world.maze import Maze

__all__ = [
    "PAGES",
    "Page",
    "check_viewable",
    "pose_json",
    "render_html",
    "wall_runs",
    "write_page",
]


@dataclass(frozen=True, slots=True)
class Page:
    """What one kind of page puts into the shared template (``page.html``; the CSS,
    ``viewer.css``, and the script ``common.js`` are shared too): its script, its side panel,
    what one frame is called, and the labels of its map and timeline."""

    script: str
    panel: str
    unit: str
    map_label: str
    timeline_title: str
    timeline_label: str
    strip: str = ""
    """A fragment shown above the timeline (the mission page's plan-tolerance strip), or none."""
    before: tuple[str, ...] = ()
    """Scripts of the page's own panels, run after ``common.js`` and before ``script`` (the
    mission page's diagnosis panel)."""


PAGES = {
    "mission": Page(
        "viewer.js",
        "mission-panel.html",
        "step",
        "maze and robot",
        "Faults over the mission",
        "fault timeline",
        "mission-strip.html",
        ("diagnosis.js",),
    ),
    "team": Page(
        "team.js",
        "team-panel.html",
        "instant",
        "maze, robots and items",
        "Timeline: robots, acts, incidents, repairs and team faults",
        "team timeline",
    ),
}
"""The pages, by the name :func:`render_html` takes."""


class Replayed(Protocol):
    """What a replay of a trace reports: whether the trace replayed (and, as text, why not)."""

    @property
    def ok(self) -> bool: ...


_R = TypeVar("_R", bound=Replayed)


def check_viewable(
    trace: str, size: int, unit: str, *, max_steps: int, source: str, replay: Callable[[], _R]
) -> _R:
    """The report of ``replay``, or a :class:`TraceError` unless the viewer can show ``trace``
    (``"the trace"``, ``"the team trace"``): at most ``max_steps`` of its ``size`` frames
    (``unit``: what they are), and it replays (the page draws only what the robot model says
    happened)."""
    if size > max_steps:
        raise TraceError(
            f"{trace} has {size} {unit}, more than the viewer's limit of {max_steps} (raise it "
            "with --max-steps)",
            source=source,
        )
    check = replay()
    if not check.ok:
        raise TraceError(f"{trace} does not replay: {check}", source=source)
    return check


def pose_json(pose: Pose) -> JSONObject:
    """A pose for drawing: cell, heading name, unit heading vector and angle (degrees clockwise
    from north, screen up being north)."""
    dx, dy = pose.heading.vector
    return {
        "x": pose.x,
        "y": pose.y,
        "heading": pose.heading.name,
        "dx": dx,
        "dy": dy,
        "angle": 90 * pose.heading.value,
    }


def wall_runs(maze: Maze) -> list[list[int]]:
    """The walls as horizontal runs ``[x, y, length]`` (compact, and one SVG path to draw)."""
    runs: list[list[int]] = []
    for y in range(maze.height):
        row = maze.walls[y]
        x = 0
        while x < maze.width:
            if row[x]:
                start = x
                while x < maze.width and row[x]:
                    x += 1
                runs.append([start, y, x - start])
            else:
                x += 1
    return runs


_PLACEHOLDER = re.compile(
    r"\{\{(TITLE|STYLE|SCRIPT|DATA|PANEL|UNIT|MAP_LABEL|TIMELINE_TITLE|TIMELINE_LABEL|STRIP)\}\}"
)


def _asset(name: str) -> str:
    return resources.files("selfrepair").joinpath("data", "viewer", name).read_text("utf-8")


def _script_safe_json(payload: Mapping[str, Any]) -> str:
    """JSON that cannot end the ``<script>`` element it sits in (``<``, ``>``, ``&`` escaped)."""
    text = json.dumps(payload, separators=(",", ":"), ensure_ascii=True, allow_nan=False)
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def render_html(payload: Mapping[str, Any], *, page: str = "mission") -> str:
    """The self-contained ``page`` (a key of :data:`PAGES`) for ``payload``: template, CSS,
    script and data, all inline."""
    chosen = PAGES[page]
    parts = {
        "TITLE": html.escape(str(payload.get("title", "mission"))),
        "STYLE": _asset("viewer.css"),
        "SCRIPT": "\n".join(_asset(name) for name in ("common.js", *chosen.before, chosen.script)),
        "DATA": _script_safe_json(payload),
        "PANEL": _asset(chosen.panel),
        "UNIT": chosen.unit,
        "MAP_LABEL": chosen.map_label,
        "TIMELINE_TITLE": chosen.timeline_title,
        "TIMELINE_LABEL": chosen.timeline_label,
        "STRIP": _asset(chosen.strip) if chosen.strip else "",
    }
    for name in ("STYLE", "SCRIPT"):
        if re.search(r"</(style|script)", parts[name], re.IGNORECASE):
            raise ProblemError(f"viewer {name.lower()} asset must not close its element")
    # one pass: text put in is never scanned for placeholders again
    return _PLACEHOLDER.sub(lambda m: parts[m.group(1)], _asset("page.html"))


def write_page(payload: Mapping[str, Any], out: str | Path, *, page: str = "mission") -> Path:
    """Write the ``page`` of ``payload`` to ``out`` (an ``.html`` file); returns ``out``."""
    out = Path(out)
    if out.suffix.lower() not in (".html", ".htm"):
        raise InputError("expected an output file ending in .html", source=str(out))
    out.write_text(render_html(payload, page=page), encoding="utf-8")
    return out
