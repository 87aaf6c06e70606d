"""The team experiment report: ``report.md`` with the per-strategy table, the delivered share
per fault case, figures (matplotlib, extra ``viz``) and one mission's frame and animation.

:func:`write_team_figures` draws from stored rows; :func:`render_team_markdown` writes the text.
The experiment layer (:func:`selfrepair.experiment.teams.write_team_report`) reads the store,
runs the chosen mission again and calls these.
"""

from __future__ import annotations

import inspect
import json
import time
from collections import defaultdict
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from selfrepair.optional import matplotlib
from selfrepair.team.summary import TeamSummary, by_fault_case, summarize_team
from selfrepair.textio import markdown_table

__all__ = ["render_team_markdown", "write_team_figures"]

Row = Mapping[str, object]
_COLOURS = ("#0072B2", "#56B4E9", "#E69F00", "#D55E00", "#009E73", "#CC79A7")
_STYLE = {
    "figure.facecolor": "white",
    "axes.facecolor": "white",
    "savefig.facecolor": "white",
    "axes.grid": True,
    "grid.color": "#d9d9d9",
    "font.size": 9,
}


def write_team_figures(rows: Sequence[Row], out_dir: Path) -> list[Path]:
    """``team-latency.png`` (repair latency per strategy) and ``team-size.png`` (tasks
    delivered and makespan against team size, per strategy)."""
    mpl = matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    variants = [s.variant for s in summarize_team(rows)]
    latency_path, size_path = out_dir / "team-latency.png", out_dir / "team-size.png"
    with mpl.rc_context(_STYLE):
        fig = Figure(figsize=(7.0, 3.6), dpi=110, layout="constrained")
        ax = fig.subplots()
        data = []
        for variant in variants:
            values: list[float] = []
            for row in rows:
                if row.get("variant") == variant and isinstance(
                    row.get("repair_latencies_ns"), str
                ):
                    values += [v / 1000 for v in json.loads(str(row["repair_latencies_ns"]))]
            data.append(values or [float("nan")])
        params = inspect.signature(ax.boxplot).parameters  # matplotlib 3.8 to 3.11 and later
        options: dict[str, Any] = {"showfliers": True}
        if "orientation" in params:
            options["orientation"] = "horizontal"
        else:
            options["vert"] = False
        options["tick_labels" if "tick_labels" in params else "labels"] = variants
        ax.boxplot(data, **options)
        ax.set_xscale("log")
        ax.set_xlabel("repair latency (µs, log scale): incident to every changed robot placed")
        FigureCanvasAgg(fig).print_png(str(latency_path))  # type: ignore[no-untyped-call]

        fig = Figure(figsize=(8.0, 3.4), dpi=110, layout="constrained")
        left, right = fig.subplots(1, 2)
        for i, variant in enumerate(variants):
            delivered: dict[int, list[float]] = defaultdict(list)
            ratio: dict[int, list[float]] = defaultdict(list)
            for row in rows:
                if row.get("variant") != variant:
                    continue
                size = int(str(row.get("team_size")))
                delivered[size].append(float(str(row.get("delivered_share"))))
                if isinstance(row.get("makespan_ratio"), float):
                    ratio[size].append(float(str(row["makespan_ratio"])))
            sizes = sorted(delivered)
            colour = _COLOURS[i % len(_COLOURS)]
            left.plot(sizes, [100 * sum(delivered[s]) / len(delivered[s]) for s in sizes],
                      marker="o", color=colour, label=variant)  # fmt: skip
            have = [s for s in sizes if ratio[s]]
            right.plot(have, [sorted(ratio[s])[len(ratio[s]) // 2] for s in have], marker="o",
                       color=colour, label=variant)  # fmt: skip
        left.set_xlabel("robots")
        left.set_ylabel("tasks delivered (%)")
        right.set_xlabel("robots")
        right.set_ylabel("makespan / fault-free (median)")
        left.legend(fontsize=7)
        FigureCanvasAgg(fig).print_png(str(size_path))  # type: ignore[no-untyped-call]
    return [latency_path, size_path]


def render_team_markdown(rows: Sequence[Row], source: str, chosen: Row, mission_note: str) -> str:
    """The text of the team ``report.md``."""
    summaries = summarize_team(rows)
    cases, variants, shares = by_fault_case(rows)
    seconds = sum(float(str(r.get("worker_seconds") or 0)) for r in rows)
    sizes = sorted({int(str(r.get("team_size"))) for r in rows})
    parts = [
        "# Team missions: experiment report",
        "",
        f"Generated {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} from `{source}`: "
        f"{len(rows)} team missions, teams of {', '.join(map(str, sizes))} robots, "
        f"{len(cases)} fault cases; {seconds:.0f} s of worker time.",
        "",
        "## Per strategy",
        "",
        "*tasks delivered*: over all missions. *makespan / fault-free*: median over missions that "
        "delivered every task, against the same scenario run without faults. *repair latency*: "
        "from the incident until every robot whose plan changed has its next drive placed in "
        "time (µs, all repairs; wall clock). *repair CPU*: the processor time of the same "
        "stretch, which other load on a shared machine does not inflate. *robots disturbed*: "
        "teammates whose plans a repair changed. "
        "*messages*: robot-to-robot notifications per mission (fault broadcasts, requests and "
        "acknowledgements, new plans). *drive plannings / repair*: drives planned inside the "
        "repair latency.",
        "",
        markdown_table(TeamSummary.HEADERS, [s.cells() for s in summaries]),
        "",
        "## Tasks delivered per fault case",
        "",
        markdown_table(
            ["fault case", *variants],
            [
                [case] + [f"{100 * shares.get((case, v), 0.0):.1f}%" for v in variants]
                for case in cases
            ],
        ),
        "",
        "## Figures",
        "",
        "![Repair latency per strategy](team-latency.png)",
        "",
        "![Delivered and makespan against team size](team-size.png)",
        "",
        "![One mission](mission.png)",
        "",
        f"*Mission `{str(chosen['key'])[:12]}`: {mission_note}. Animation: "
        "[mission.gif](mission.gif); trace: [mission.jsonl](mission.jsonl) (`selfrepair team "
        "replay mission.jsonl`).*",
        "",
    ]
    return "\n".join(parts)
