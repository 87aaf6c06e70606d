"""The four-wheel robot's reference tables as rows and Markdown, as ``docs/robot.md`` shows them.

``selfrepair actions`` prints :func:`action_rows`; the docs embed the Markdown tables between
``BEGIN generated`` / ``END generated`` markers, and a test keeps both equal to these functions.
"""

from __future__ import annotations

from selfrepair.robots import four_wheel

__all__ = [
    "ACTION_COLUMNS",
    "action_rows",
    "markdown_action_table",
    "markdown_double_fault_summary",
    "markdown_single_fault_table",
]

ACTION_COLUMNS = ("action", "l", "r", "motion", "duration")
"""The columns of the action table (``kind`` is only in the JSON rows)."""


def action_rows() -> list[dict[str, object]]:
    """One row per action: code, side drives, motion, kind and exact duration (as text)."""
    return [
        {
            "action": a.code,
            "l": a.left,
            "r": a.right,
            "motion": a.motion.name,
            "kind": a.motion.kind.value,
            "duration": str(a.duration),
        }
        for a in four_wheel.ACTIONS
    ]


def markdown_action_table() -> str:
    """The 81-row action table as Markdown, as ``docs/robot.md`` shows it (a test compares)."""
    lines = ["| " + " | ".join(ACTION_COLUMNS) + " |", "|---|---:|---:|---|---:|"]
    lines += [
        "| " + " | ".join(str(row[c]) for c in ACTION_COLUMNS) + " |" for row in action_rows()
    ]
    return "\n".join(lines) + "\n"


def markdown_single_fault_table() -> str:
    """Per single fault: the motions it removes and those it slows (fastest duration before and
    after), as Markdown. ``docs/robot.md`` shows it and a test keeps the two equal."""
    healthy = {m: a.duration for m, a in four_wheel.fastest_by_motion().items()}
    lines = [
        "| fault | actions left | motions lost | motions slowed (ticks) |",
        "|---|---:|---|---|",
    ]
    for fault in four_wheel.SINGLE_FAULTS:
        best = four_wheel.fastest_by_motion([fault])
        left = sum(four_wheel.available(a, [fault]) for a in four_wheel.ACTIONS)
        lost = [m.name for m in four_wheel.MOTIONS if m not in best]
        slowed = [
            f"{m.name} {healthy[m]} → {best[m].duration}"
            for m in four_wheel.MOTIONS
            if m in best and best[m].duration > healthy[m]
        ]
        lines.append(
            f"| {fault} | {left} | {', '.join(lost) or '–'} | {', '.join(slowed) or '–'} |"
        )
    return "\n".join(lines) + "\n"


def markdown_double_fault_summary() -> str:
    """The 66 double faults grouped by the motions they remove, as Markdown (in the docs)."""
    groups: dict[tuple[str, ...], list[str]] = {}
    for pair in four_wheel.DOUBLE_FAULTS:
        best = four_wheel.fastest_by_motion(pair)
        lost = tuple(m.name for m in four_wheel.MOTIONS if m not in best)
        groups.setdefault(lost, []).append(four_wheel.format_faults(pair))
    lines = ["| motions lost | double faults | for example |", "|---|---:|---|"]
    for lost, pairs in sorted(groups.items(), key=lambda kv: (len(kv[0]), kv[0])):
        lines.append(f"| {', '.join(lost) or '–'} | {len(pairs)} | {min(pairs)} |")
    return "\n".join(lines) + "\n"
