"""``selfrepair view``: write a mission as one self-contained HTML page (no server, no network).

``selfrepair view TRACE -o mission.html`` views a trace written by ``run --trace`` (a team trace of
``team run --trace`` gets the team page: every robot, item, held cell, incident and repair on one
timeline);
``selfrepair view RESULTS.sqlite --key K -o mission.html`` re-runs the stored mission whose key
starts with ``K`` and views it. Bad input (a missing file, a file that is neither, an unknown or
ambiguous key) is one line on stderr and exit code 2 (see :func:`selfrepair.cli.main`).
"""

from pathlib import Path
from typing import Annotated

import typer

from selfrepair.cli._app import MaxTraceBytes, app, echo, limit_option, option
from selfrepair.errors import InputError
from selfrepair.limits import MAX_TRACE_BYTES

__all__ = ["VIEW_STEPS_DEFAULT", "view"]

VIEW_STEPS_DEFAULT = 50_000
"""Default of ``--max-steps``: :data:`selfrepair.experiment.viewer.MAX_VIEW_STEPS` (a test keeps
them equal; the CLI does not import the viewer to start)."""

_SQLITE_MAGIC = b"SQLite format 3\x00"


def _is_sqlite(path: Path) -> bool:
    with path.open("rb") as handle:
        return handle.read(len(_SQLITE_MAGIC)) == _SQLITE_MAGIC


@app.command()
def view(
    source: Annotated[
        Path,
        typer.Argument(
            metavar="SOURCE",
            help="A trace (run --trace, team run --trace) or a results database (with --key).",
        ),
    ],
    out: Annotated[Path, typer.Option("--out", "-o", metavar="FILE", help="HTML file to write.")],
    key: Annotated[
        str | None,
        option("--key", "KEY", "Key (or unique key prefix) of a mission in the database."),
    ] = None,
    max_steps: Annotated[
        int, limit_option("--max-steps", "Refuse missions with more steps.")
    ] = VIEW_STEPS_DEFAULT,
    max_trace_bytes: MaxTraceBytes = MAX_TRACE_BYTES,
    tolerance: Annotated[
        int,
        option(
            "--tolerance",
            "K",
            "Heat strip of the initial plan's tolerance of every set of 1 to K faults "
            "(replacement missions; 0: none).",
            min=0,
            max=3,
        ),
    ] = 1,
) -> int:
    """Write a mission as a self-contained HTML page.

    The page replays the mission: maze, plan, path, faults and repairs; for a team trace every
    robot, item, held cell, incident and repair on one timeline.
    """
    from selfrepair.experiment.viewer import view_results, view_trace

    if not source.is_file():
        raise InputError("expected a trace file or a results database", source=str(source))
    if _is_sqlite(source):
        if key is None:
            raise InputError(
                "a results database holds many missions: choose one with --key", source=str(source)
            )
        if not key:
            raise InputError("expected a non-empty mission key or key prefix", source="--key")
        written = view_results(source, key, out, max_steps=max_steps, tolerance=tolerance)
    else:
        if key is not None:
            raise InputError(
                "--key chooses a mission in a results database, but this is not one",
                source=str(source),
            )
        written = view_trace(
            source, out, max_steps=max_steps, max_trace_bytes=max_trace_bytes,
            tolerance=tolerance,
        )  # fmt: skip
    echo(f"wrote {written}")
    return 0
