"""The experiment report: ``report.md`` with the summary table, the findings and PNG figures.

:func:`write_report` reads every row of a results database and writes into a directory:

* ``report.md`` - setup, per-strategy table, the three findings, figures with captions;
* ``latency.png``, ``latency-vs-size.png``, ``clearance.png``, ``heatmap.png`` - see
  :mod:`selfrepair.experiment.plots`;
* ``mission.jsonl``, ``mission.png``, ``mission.gif`` - one telling mission, run again from its
  stored configuration (results are deterministic), with its trace, picture and animation.

A database of a team experiment gets the team report instead
(:func:`selfrepair.experiment.teams.write_team_report`). The rows are read and checked by
:mod:`.reportrows`, the mission is chosen and run again by :mod:`.reportmission` (this module
re-exports their public names).
"""

from __future__ import annotations

import json
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from selfrepair.errors import InputError
from selfrepair.experiment.comparison import baseline_tables, has_baselines
from selfrepair.experiment.diagnosis_findings import diagnosis_findings
from selfrepair.experiment.dynamic_findings import dynamic_findings
from selfrepair.experiment.findings import (
    Finding,
    Row,
    StrategySummary,
    check_findings,
    reference_note,
    summarize,
)
from selfrepair.experiment.reportmission import (
    choose_mission,
    mission_files,
    pick_mission,
    rerun_mission,
)
from selfrepair.experiment.reportrows import check_rows, load_rows, read_results
from selfrepair.experiment.summary import fault_set_bite
from selfrepair.experiment.tolerance_findings import tolerance_findings
from selfrepair.textio import markdown_table

__all__ = [
    "all_findings",
    "baselines_section",
    "choose_mission",
    "counted",
    "markdown_table",
    "pick_mission",
    "read_results",
    "rerun_mission",
    "write_report",
]


def write_report(db: str | Path, out: str | Path, *, mission_key: str | None = None) -> list[Path]:
    """Write the report for every row in ``db`` into directory ``out``; returns the files written.

    ``mission_key`` (a key or a unique key prefix) picks the mission to draw; by default
    :func:`choose_mission` picks one.
    """
    from selfrepair.experiment import plots

    if not str(out).strip():
        raise InputError("expected a directory to write the report into, got an empty path")
    from selfrepair.experiment.teams import is_team_rows, write_team_report

    columns, rows = load_rows(db)
    out_dir = Path(out)
    if is_team_rows(rows):
        out_dir.mkdir(parents=True, exist_ok=True)
        return write_team_report(rows, out_dir, str(db), mission_key=mission_key)
    rows = check_rows(columns, rows, str(db))
    out_dir.mkdir(parents=True, exist_ok=True)
    clearance = plots.figure_clearance(rows, out_dir / "clearance.png")
    if clearance is None:  # one clearance weight: no figure (and no stale one from before)
        (out_dir / "clearance.png").unlink(missing_ok=True)
    written = [
        plots.figure_latency(rows, out_dir / "latency.png"),
        plots.figure_latency_vs_size(rows, out_dir / "latency-vs-size.png"),
        *([clearance] if clearance is not None else []),
        plots.figure_heatmap(rows, out_dir / "heatmap.png"),
    ]
    baselines = has_baselines(rows)
    if baselines:
        written.append(plots.figure_baselines(rows, out_dir / "baselines.png"))
    if mission_key is None:
        chosen = choose_mission(rows)
    else:
        chosen = pick_mission(rows, mission_key, str(db))
    written += mission_files(chosen, out_dir, str(db))
    report = out_dir / "report.md"
    report.write_text(
        render_markdown(
            rows,
            summarize(rows),
            all_findings(rows),
            chosen,
            str(db),
            heatmap_variant=plots.heatmap_variant(rows),
            clearance=clearance is not None,
        )
        + (baselines_section(rows, "baselines.png") if baselines else ""),
        encoding="utf-8",
    )
    return [report, *written]


def counted(value: object, noun: str) -> str:
    """``"1 replan"``, ``"13 replans"`` (``value`` as stored: a number, or ``None`` for 0)."""
    number = int(str(value or 0))
    return f"{number} {noun}" if number == 1 else f"{number} {noun}s"


def all_findings(rows: Sequence[Row]) -> list[Finding]:
    """Every finding the rows bear on, in the order report and command print them: the
    original study's, then plan tolerance's, the changing world's and diagnosis's."""
    return [
        *check_findings(rows),
        *tolerance_findings(rows),
        *dynamic_findings(rows),
        *diagnosis_findings(rows),
    ]


def baselines_section(rows: Sequence[Row], figure: str | None = None) -> str:
    """The section on the baselines from neighbouring fields (:mod:`.comparison`): the table on
    the missions every strategy ran, repair time by maze, and the figure (``figure``: its file
    name, when drawn)."""
    tables = baseline_tables(rows)
    parts = [
        "",
        "## Baselines: D* Lite, LPG-adapt and A* replanning",
        "",
        f"The same missions for every strategy ({tables.missions} each, on "
        f"{', '.join(tables.mazes) or 'no maze'}). Medians with 95% bootstrap intervals over "
        "missions; *ticks over A\\**: mean of the differences paired with the A* replanner. "
        "Definitions in docs/baselines.md.",
        "",
        markdown_table(*tables.comparison),
        "",
        "Repair latency at the first faulty action (ms) by maze, over every mission that met a "
        "fault:",
        "",
        markdown_table(*tables.first_repair),
        "",
        "Repair time per mission (ms, all its repairs added up) by maze:",
        "",
        markdown_table(*tables.repair_compute),
        "",
    ]
    if figure is not None:
        parts += [
            f"![Repair latency by strategy and maze size]({figure})",
            "",
            "*Repair latency at the first faulty action (left) and repair time per mission "
            "(right) by strategy and maze, median with 95% bootstrap interval, log scale.*",
            "",
        ]
    return "\n".join(parts)


def render_markdown(
    rows: Sequence[Row],
    summaries: Sequence[StrategySummary],
    findings: Sequence[Finding],
    chosen: Row,
    source: str,
    *,
    heatmap_variant: str | None,
    clearance: bool = True,
) -> str:
    """The text of ``report.md`` (``clearance``: whether the clearance figure was drawn; it is
    not when the sweep has a single clearance weight)."""
    experiments = Counter(str(r["experiment"]) for r in rows)
    versions = sorted({str(r["version"]) for r in rows})
    mazes = sorted({str(r["maze"]) for r in rows})
    faults = sorted({str(r["faults"]) for r in rows})
    seconds = sum(float(r.get("worker_seconds") or 0) for r in rows)
    config = json.loads(str(chosen["config"]))
    parts = [
        "# Replacement versus replanning: experiment report",
        "",
        f"Generated {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())} from `{source}`: "
        f"{len(rows)} missions ("
        + ", ".join(f"{n} in `{e}`" for e, n in sorted(experiments.items()))
        + f"), selfrepair {', '.join(versions)}; {len(mazes)} mazes, {len(faults)} fault sets; "
        f"{seconds:.0f} s of worker time.",
        "",
        "## Per strategy",
        "",
        "Mission-level figures first; intervals are 95% bootstrap intervals over missions. "
        "*met a fault*: missions that met at least one faulty action. *no replan*: of those, the "
        "ones that reached the goal without any full replan. *resolved locally (per "
        "encounter)*: faulty encounters repaired by a table replacement or a lookahead window. "
        "*ticks over optimum*: ticks taken minus the fault-free optimum at clearance weight 0 on "
        "the same route, mean over reached missions. *plan distance*: plan stability (Fox et al. "
        "2006) between initial and executed plan, as ground actions and by motion class. "
        "*repair compute/mission*: every repair's time added up, median over missions that met a "
        "fault (µs). *first repair cold/warm*: the first repair of a mission with the process's "
        "caches emptied, and the same repair warm (µs). *repair latency*: over all repairs, "
        "pooled. `w=` is the clearance weight (0 when absent).",
        "",
        markdown_table(StrategySummary.HEADERS, [s.cells() for s in summaries]),
        "",
        "### Fault sets",
        "",
        markdown_table(
            ("fault set", "missions", "met a faulty action", "variant replan: met"),
            [
                (
                    b.faults or "(none)",
                    str(b.missions),
                    str(b.met),
                    f"{b.replan_met}/{b.replan_missions}",
                )
                for b in fault_set_bite(rows)
            ],
        ),
        "",
        "## The original study's findings on these results",
        "",
    ]
    note = reference_note(rows)
    if note is not None:
        parts += [f"*{note}*", ""]
    for f in findings:
        if not f.applies:  # left out, with the one line saying why
            parts += [f"*{f.headline}*", ""]
            continue
        parts.append(
            f"**Finding {f.number}: {f.verdict.upper()}.** {f.claim[:1].upper()}{f.claim[1:]}."
        )
        parts.append("")
        parts.append(f.evidence)
        parts.append("")
    parts += [
        "",
        "## Figures",
        "",
        "![Repair latency distributions](latency.png)",
        "",
        "*Repair latency per strategy at clearance weight 0, log scale. For the table-based "
        "strategies the repairs are split by what resolved them (table hit, lookahead window or "
        "fallback replan).*",
        "",
        "![Latency versus maze size](latency-vs-size.png)",
        "",
        "*Median repair latency (bar up to the 99th percentile) against maze size: replans of "
        "the A* replanner (variant replan) versus table hits of the replacing robot.*",
        "",
        *(
            [
                "![Replacement success versus clearance weight](clearance.png)",
                "",
                "*Left: share of faulty encounters resolved by a table replacement for each "
                "clearance weight. Right: what keeping away from walls costs in execution time.*",
                "",
            ]
            if clearance
            else []
        ),
        "![Fault set by maze](heatmap.png)",
        "",
        f"*{heatmap_variant}: share of encounters resolved locally (left) and mean extra ticks "
        "(right) per fault set and maze.*",
        "",
        "![One mission](mission.png)",
        "",
        f"*Mission `{str(chosen['key'])[:12]}`: maze {chosen['maze']}, route {chosen['route']}, "
        f"faults {config['faults'] or 'none'}, {chosen['variant']}, clearance weight "
        f"{chosen['clearance_weight']}; "
        f"{counted(chosen.get('replacements'), 'table replacement')}, "
        f"{counted(chosen.get('replans'), 'replan')}. Dark dashes: the initial plan (drawn over "
        "the executed path); coloured: executed steps by source (dots: turns in place); an X "
        "for each repair, coloured by what resolved it. Animation: [mission.gif](mission.gif); "
        "trace: [mission.jsonl](mission.jsonl) (`selfrepair replay mission.jsonl`).*",
        "",
    ]
    return "\n".join(parts)
