"""Commands about the robot model: ``selfrepair actions``."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from selfrepair import robot
from selfrepair.cli._app import app, console, echo_json


def action_rows() -> list[dict[str, object]]:
    """One row per action: code, side drives, motion and exact duration (as text)."""
    return [
        {
            "action": a.code,
            "l": a.left,
            "r": a.right,
            "motion": a.motion.name,
            "kind": a.motion.kind.value,
            "duration": str(a.duration),
        }
        for a in robot.ACTIONS
    ]


@app.command()
def actions(
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON rows instead of a table.")] = False,
) -> int:
    """Print the 81 actions: wheel code, side drives l and r, motion and duration in ticks."""
    rows = action_rows()
    if as_json:
        echo_json(rows)
        return 0
    table = Table(title="The 81 actions of the four-wheel robot")
    for column in ("action", "l", "r", "motion", "duration"):
        table.add_column(column, justify="right" if column in ("l", "r", "duration") else "left")
    for row in rows:
        table.add_row(*(str(row[c]) for c in ("action", "l", "r", "motion", "duration")))
    console().print(table)
    return 0
