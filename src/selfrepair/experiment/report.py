"""The experiment report: ``report.md`` with the summary table, the findings and PNG figures.

:func:`write_report` reads every row of a results database and writes into a directory:

* ``report.md`` - setup, per-strategy table, the three findings, figures with captions;
* ``latency.png``, ``latency-vs-size.png``, ``clearance.png``, ``heatmap.png`` - see
  :mod:`selfrepair.experiment.plots`;
* ``mission.jsonl``, ``mission.png``, ``mission.gif`` - one telling mission, run again from its
  stored configuration (results are deterministic), with its trace, picture and animation.

A database of a team experiment gets the team report instead
(:func:`selfrepair.experiment.teams.write_team_report`).
"""

from __future__ import annotations

import json
import math
import re
import time
from collections import Counter
from collections.abc import Callable, Sequence
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING

from selfrepair.errors import InputError, SelfRepairError
from selfrepair.experiment.comparison import (
    FIRST_REPAIR,
    REPAIR_COMPUTE,
    BaselineLine,
    common_rows,
    compare_baselines,
    has_baselines,
    maze_table,
)
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
from selfrepair.experiment.keys import Mission
from selfrepair.experiment.store import ResultStore
from selfrepair.experiment.summary import fault_set_bite
from selfrepair.experiment.tolerance_findings import tolerance_findings

if TYPE_CHECKING:
    from selfrepair.execution.result import MissionResult

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

_TEXT = ("key", "experiment", "version", "config", "maze", "route", "faults", "variant", "strategy")
"""Columns the report reads as text: each must be there, and hold text in every row."""
_OPTIONAL_TEXT = ("table", "recursion", "finished_at")
_NUMBERS = (
    "worker_seconds",
    "reached",
    "replacements",
    "replans",
    "lookaheads",
    "faulty_encounters",
    "repair_count",
    "compute_per_action_ns",
    "extra_ticks",
    "maze_free_cells",
    "maze_width",
    "plan_distance",
)
"""Columns the report reads as numbers: numbers of magnitude at most :data:`_LARGEST` or empty,
when the column is there."""
_LARGEST = 1e18
"""Larger than any count or time in nanoseconds a mission can have; sums of such numbers over
any number of rows stay finite."""
_EXACT = re.compile(r"^-?[0-9]{1,18}(?:/[1-9][0-9]{0,17}|\.[0-9]{1,18})?$")
"""A clearance weight as stored: an integer, a decimal or a fraction (``1/2``)."""
_NUMBER_LISTS = ("repair_latencies_ns",)
_TEXT_LISTS = ("repair_sources",)


def read_results(db: str | Path) -> list[Row]:
    """Every row of the results database ``db``, checked for what the report reads from it.

    A file that is not a readable results database, a missing column, or a value of the wrong
    kind (text where a number belongs, a ``config`` that is not a JSON object, ...) is an
    :class:`~selfrepair.errors.InputError` naming the file and, for a value, the mission's key
    and the column. The database is never changed (it may lie in a read-only directory).
    """
    columns, rows = _load(db)
    return _checked(columns, rows, str(db))


def _load(db: str | Path) -> tuple[set[str], list[Row]]:
    with ResultStore(db, read_only=True) as store:  # a report never changes its input
        return set(store.columns), store.rows()


def _checked(columns: set[str], rows: list[Row], source: str) -> list[Row]:
    missing = [c for c in (*_TEXT, "seed", "clearance_weight") if c not in columns]
    if missing:
        raise InputError(
            "expected a results database of `selfrepair experiment`: table 'missions' has no "
            "column " + ", ".join(repr(c) for c in missing),
            source=source,
        )
    if not rows:
        raise InputError("expected a results database with at least one mission", source=source)
    for row in rows:
        _check_row(row, source)
    return rows


def _check_row(row: Row, source: str) -> None:
    key = row.get("key")
    where = f"mission {str(key)[:12]!r}" if isinstance(key, str) else "a mission"

    def bad(column: str, expected: str) -> InputError:
        value = repr(row.get(column))
        shown = value if len(value) <= 40 else value[:37] + "..."
        return InputError(
            f"{where}: column {column!r}: expected {expected}, got {shown}", source=source
        )

    for column in _TEXT:
        if not isinstance(row.get(column), str):
            raise bad(column, "text")
    for column in _OPTIONAL_TEXT:
        if row.get(column) is not None and not isinstance(row.get(column), str):
            raise bad(column, "text")
    if not isinstance(row.get("seed"), int):
        raise bad("seed", "an integer")
    for column in _NUMBERS:
        if not _is_number_or_none(row.get(column)):
            raise bad(column, f"a number of magnitude at most {_LARGEST:g}")
    if not _is_fraction(row.get("clearance_weight")):
        raise bad("clearance_weight", "an exact number such as 1/2")
    for column in _NUMBER_LISTS:
        if not _is_json_list(row.get(column), _is_number):
            raise bad(column, "a JSON list of numbers")
    for column in _TEXT_LISTS:
        if not _is_json_list(row.get(column), lambda v: isinstance(v, str)):
            raise bad(column, "a JSON list of texts")
    try:
        config = json.loads(str(row["config"]))
    except ValueError:
        config = None
    if not isinstance(config, dict) or not isinstance(config.get("faults"), str):
        raise bad("config", "the mission's configuration as a JSON object")


def _is_number(value: object) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(value)
        and abs(value) <= _LARGEST
    )


def _is_number_or_none(value: object) -> bool:
    return value is None or _is_number(value)


def _is_fraction(value: object) -> bool:
    if value is None or value == "" or _is_number(value):
        return True
    # exact decimals or fractions of bounded length only: Fraction("1e999999999") would build
    # a billion-digit integer
    text = str(value)
    return bool(_EXACT.match(text))


def _is_json_list(value: object, item: Callable[[object], bool]) -> bool:
    if value is None or value == "":
        return True
    try:
        data = json.loads(str(value))
    except (ValueError, RecursionError):
        return False
    return isinstance(data, list) and all(item(v) for v in data)


def write_report(db: str | Path, out: str | Path, *, mission_key: str | None = None) -> list[Path]:
    """Write the report for every row in ``db`` into directory ``out``; returns the files written.

    ``mission_key`` (a key or a unique key prefix) picks the mission to draw; by default
    :func:`choose_mission` picks one.
    """
    from selfrepair.experiment import plots

    if not str(out).strip():
        raise InputError("expected a directory to write the report into, got an empty path")
    from selfrepair.experiment.teams import is_team_rows, write_team_report

    columns, rows = _load(db)
    out_dir = Path(out)
    if is_team_rows(rows):
        out_dir.mkdir(parents=True, exist_ok=True)
        return write_team_report(rows, out_dir, str(db), mission_key=mission_key)
    rows = _checked(columns, rows, str(db))
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
    mission_files = _mission_files(chosen, out_dir, str(db))
    written += mission_files
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


def pick_mission(rows: Sequence[Row], key_prefix: str, source: str) -> Row:
    """The row whose key starts with ``key_prefix``; none or several is an
    :class:`~selfrepair.errors.InputError` naming ``source`` (the results database)."""
    hits = [r for r in rows if key_prefix and str(r["key"]).startswith(key_prefix)]
    if len(hits) != 1:
        examples = ", ".join(str(r["key"])[:12] for r in hits[:3])
        raise InputError(
            f"expected the mission key prefix to match exactly one stored mission, {len(hits)} "
            f"match {key_prefix!r}" + (f" (e.g. {examples}); give more characters" if hits else ""),
            source=source,
        )
    return hits[0]


def choose_mission(rows: Sequence[Row]) -> Row:
    """A telling mission to draw: reached, repaired by the table at least once, on a small maze,
    preferring the hand-written table, a mission that also replanned, and many replacements."""

    def score(row: Row) -> tuple[object, ...]:
        replacements = int(row.get("replacements") or 0)
        replans = int(row.get("replans") or 0)
        width = int(row.get("maze_width") or 999)
        return (
            row.get("reached") == 1,
            replacements > 0,
            width <= 32,
            row.get("table") == "handwritten",
            replans > 0 and replacements > 0,
            Fraction(str(row.get("clearance_weight") or "0")) == 0,
            min(replacements, 12),
            -width,
            str(row["key"]),
        )

    return max(rows, key=score)


def rerun_mission(row: Row, source: str = "<results database>") -> MissionResult:
    """Run a stored mission again from its canonical configuration (results are deterministic,
    so this gives its steps and repairs; the timings are new). A configuration this version
    cannot run is an :class:`~selfrepair.errors.InputError` naming ``source``."""
    from selfrepair.execution.executor import run_mission
    from selfrepair.experiment.missions import to_spec

    mission = Mission(
        str(row["key"]), str(row["experiment"]), int(row["seed"] or 0), str(row["config"]), ()
    )
    try:
        spec = to_spec(mission)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, SelfRepairError):
            raise
        raise InputError(
            f"mission {mission.key[:12]!r}: its stored configuration cannot be run again "
            f"({type(exc).__name__}: {exc})",
            source=source,
        ) from None
    return run_mission(spec)


def _mission_files(row: Row, out_dir: Path, source: str) -> list[Path]:
    """Run the chosen mission again, write its trace, picture and GIF."""
    from selfrepair.execution.trace import read_trace, write_trace
    from selfrepair.experiment import missionplot
    from selfrepair.experiment.animate import animate_trace

    result = rerun_mission(row, source)
    trace_path = out_dir / "mission.jsonl"
    write_trace(result, trace_path)
    picture = missionplot.picture_from_trace(read_trace(trace_path))
    png = missionplot.figure_mission(picture, out_dir / "mission.png")
    gif = out_dir / "mission.gif"
    animate_trace(trace_path, gif, max_frames=60)
    return [trace_path, png, gif]


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
    lines = compare_baselines(rows)
    mazes = sorted({str(r.get("maze")) for r in common_rows(rows)})
    parts = [
        "",
        "## Baselines: D* Lite, LPG-adapt and A* replanning",
        "",
        f"The same missions for every strategy ({lines[0].missions if lines else 0} each, on "
        f"{', '.join(mazes) or 'no maze'}). Medians with 95% bootstrap intervals over missions; "
        "*ticks over A\\**: mean of the differences paired with the A* replanner. Definitions in "
        "docs/baselines.md.",
        "",
        markdown_table(BaselineLine.HEADERS, [line.cells() for line in lines]),
        "",
        "Repair latency at the first faulty action (ms) by maze, over every mission that met a "
        "fault:",
        "",
        markdown_table(*maze_table(rows, FIRST_REPAIR)),
        "",
        "Repair time per mission (ms, all its repairs added up) by maze:",
        "",
        markdown_table(*maze_table(rows, REPAIR_COMPUTE)),
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


def markdown_table(headers: Sequence[str], body: Sequence[Sequence[str]]) -> str:
    """A GitHub-flavoured Markdown table (first column left-aligned, the rest right-aligned)."""
    lines = ["| " + " | ".join(headers) + " |"]
    lines.append("|" + "|".join([":---"] + ["---:"] * (len(headers) - 1)) + "|")
    lines += ["| " + " | ".join(cells) + " |" for cells in body]
    return "\n".join(lines)


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
