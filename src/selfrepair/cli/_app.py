"""The Typer application object and the helpers every command module shares.

Command modules register themselves on :data:`app` (or on one of its groups) at import time;
:mod:`selfrepair.cli` imports them all. Commands return an ``int`` exit code (0 unless stated) and
raise :class:`selfrepair.errors.SelfRepairError` for bad input: :func:`selfrepair.cli.main` turns
that into one line on stderr and exit code 2.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console

app = typer.Typer(
    name="selfrepair",
    help="Self-repairing robot plans: replacement tables versus replanning from scratch.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
maze_app = typer.Typer(help="Show and generate mazes.", no_args_is_help=True)
table_app = typer.Typer(
    help="Replacement tables: show, check, generate, coverage.", no_args_is_help=True
)
app.add_typer(maze_app, name="maze")
app.add_typer(table_app, name="table")


@app.callback()
def _global_options(
    plugin: Annotated[
        list[Path] | None,
        typer.Option(
            "--plugin",
            help="A Python file that registers a robot domain (repeatable); see docs/extending.md.",
        ),
    ] = None,
) -> None:
    """Self-repairing robot plans: replacement tables versus replanning from scratch."""
    if plugin:
        from selfrepair.robots.registry import load_plugin

        for path in plugin:
            load_plugin(path)


def console() -> Console:
    """A rich console on the current stdout (looked up per call so tests can capture it)."""
    return Console(file=sys.stdout, soft_wrap=True, highlight=False)


def echo(text: str = "") -> None:
    """Print plain text to stdout."""
    sys.stdout.write(text + "\n")


def echo_json(data: Any) -> None:
    """Print ``data`` as indented, valid JSON to stdout (never ``NaN`` or ``Infinity``: a
    non-finite number is a bug and raises ``ValueError`` instead of printing invalid JSON)."""
    sys.stdout.write(json.dumps(data, indent=2, allow_nan=False) + "\n")


# --- limits: one flag per limit of selfrepair.limits, the same on every command ----------------
# A command declares ``max_cells: MaxCells = MAX_CELLS`` and so on; --help shows the default.

MaxCells = Annotated[
    int,
    typer.Option(
        "--max-cells",
        min=1,
        help="Refuse a maze (file, map or generated) of more cells than this.",
    ),
]
MaxMissions = Annotated[
    int,
    typer.Option(
        "--max-missions", min=1, help="Refuse an experiment of more missions than this."
    ),
]
MaxTableBytes = Annotated[
    int,
    typer.Option(
        "--max-table-bytes", min=1, help="Refuse a table file larger than this, unread."
    ),
]
MaxTableCandidates = Annotated[
    int,
    typer.Option(
        "--max-table-candidates",
        min=1,
        help="Refuse a table of more candidates than this, before re-simulating any.",
    ),
]
