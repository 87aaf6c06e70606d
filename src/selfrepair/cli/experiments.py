"""Experiment commands: ``selfrepair experiment``, ``selfrepair report``, ``selfrepair animate``."""

import sys
from collections.abc import Sequence
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from selfrepair.cli._app import (
    MaxCells,
    MaxFileBytes,
    MaxMissions,
    MaxTraceBytes,
    app,
    echo,
    option,
)
from selfrepair.cli._inputs import TraceArg
from selfrepair.cli._printing import (
    print_baselines,
    print_crossover,
    print_fault_sets,
    print_findings,
    print_summary,
)
from selfrepair.cli._progress import frames_progress, mission_progress
from selfrepair.errors import InputError, ProblemError
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES, MAX_MISSIONS, MAX_TRACE_BYTES

if TYPE_CHECKING:

    from selfrepair.experiment.backends import MissionFunction
    from selfrepair.experiment.keys import Mission
    from selfrepair.experiment.store import Value

__all__ = [
    "animate",
    "experiment",
    "print_baselines",
    "print_fault_sets",
    "print_findings",
    "print_summary",
    "report",
]


def resolve_experiment(spec: str) -> Path:
    """A bundled experiment name (``paper``, ``scale``, ``baselines``, ``full``, ``team``,
    ``dynamic``, ``diagnosis``, ...) or a path to a TOML file."""
    from importlib import resources

    folder = resources.files("selfrepair").joinpath("data", "experiments")
    bundled = folder.joinpath(f"{spec}.toml")
    if "/" not in spec and not spec.endswith(".toml") and bundled.is_file():
        return Path(str(bundled))
    return Path(spec)


def _check_options(backend: str, jobs: int, scheduler: str | None) -> None:
    """The runner's checks, worded with the flags (the library names none)."""
    from selfrepair.experiment.backends import BACKENDS

    if backend not in BACKENDS:
        raise InputError(
            f"expected one of {', '.join(BACKENDS)}, got {backend!r}", source="--backend"
        )
    if jobs < 1 and jobs != -1:
        raise InputError(
            f"expected a positive number of workers or -1 (all cores), got {jobs}", source="--jobs"
        )
    if backend == "dask" and not scheduler:
        raise InputError(
            "expected --scheduler ADDRESS (e.g. tcp://host:8786) with --backend dask",
            source="--scheduler",
        )


@app.command()
def experiment(
    config: Annotated[
        str,
        typer.Argument(
            metavar="CONFIG",
            help="Bundled experiment (paper, scale, baselines, full, team, dynamic, diagnosis, "
            "...) or "
            "FILE.toml.",
        ),
    ],
    db: Annotated[
        Path | None, option("--db", "FILE", "Results database (default: results/NAME.sqlite).")
    ] = None,
    jobs: Annotated[
        int,
        typer.Option("--jobs", "-j", metavar="N", help="Local worker processes (-1: all cores)."),
    ] = -1,
    backend: Annotated[
        str, option("--backend", "NAME", "Where to run: local, dask or ray.")
    ] = "local",
    scheduler: Annotated[
        str | None,
        option("--scheduler", "ADDRESS", "Dask scheduler address (with --backend dask)."),
    ] = None,
    address: Annotated[
        str | None,
        option(
            "--address",
            "ADDRESS",
            "Ray cluster address (with --backend ray; default: start a local Ray).",
        ),
    ] = None,
    export_csv: Annotated[
        Path | None, option("--export-csv", "FILE", "Also write every row to a CSV file.")
    ] = None,
    export_parquet: Annotated[
        Path | None,
        option("--export-parquet", "FILE", "Also write a Parquet file (needs pyarrow)."),
    ] = None,
    max_missions: MaxMissions = MAX_MISSIONS,
    max_cells: MaxCells = MAX_CELLS,
    max_file_bytes: MaxFileBytes = MAX_FILE_BYTES,
    repeats: Annotated[
        int | None,
        option(
            "--repeats",
            "N",
            "Warm timing runs per mission after one cold run (timings are their medians; "
            "default: the experiment's timing_repeats, else 1).",
            min=1,
            max=1000,
        ),
    ] = None,
    footing: Annotated[
        str,
        option(
            "--footing",
            "NAME",
            "Mission loop: auto (compiled where it can run, else Python), compiled or "
            "python (the reference); rows record the footing that ran.",
        ),
    ] = "auto",
) -> int:
    """Run an experiment; print its summary and findings.

    Resumable: missions already in the database are skipped. The summary and the original
    study's findings are computed on all stored rows of the experiment. A team experiment
    (kind = "team", e.g. the bundled team) prints the team summary. Ctrl-C stops the sweep and
    says how much is stored (exit 130); running the same command again resumes.
    """
    import joblib

    from selfrepair.experiment.backends import check_backend
    from selfrepair.experiment.missions import expand
    from selfrepair.experiment.runner import run_missions
    from selfrepair.experiment.store import ResultStore
    from selfrepair.experiment.teams import (
        TeamExperimentConfig,
        execute_team_mission,
        expand_team,
        load_experiment,
    )
    from selfrepair.experiment.timing import execute_mission
    from selfrepair.experiment.variants import left_out

    missions: tuple[Mission, ...] = ()
    db_path: Path | None = None
    try:
        _check_options(backend, jobs, scheduler)
        if footing not in ("auto", "compiled", "python"):
            raise InputError(
                f"expected --footing auto, compiled or python, got {footing!r}", source="--footing"
            )
        check_backend(backend, jobs=jobs, scheduler=scheduler)
        if export_parquet is not None:
            _require_pyarrow()  # before the sweep, not after it
        cfg = load_experiment(resolve_experiment(config), max_file_bytes=max_file_bytes)
        execute: MissionFunction
        if isinstance(cfg, TeamExperimentConfig):
            if repeats is not None:
                raise InputError(
                    "--repeats times single-robot missions; a team experiment runs each once",
                    source="--repeats",
                )
            missions = expand_team(cfg, max_missions=max_missions, max_cells=max_cells)
            what, execute, report = "team missions", execute_team_mission, _team_report
        else:
            missions = expand(cfg, max_missions=max_missions, max_cells=max_cells)
            for name, reason in left_out(cfg):  # an optional strategy that cannot run here
                echo(f"{cfg.name}: {name} left out: {reason}")
            execute = partial(
                execute_mission, repeats=repeats or cfg.timing_repeats, footing=footing
            )
            what, report = "missions", partial(
                _report, crossover=cfg.crossover, physics=cfg.physics is not None
            )
        db_path = db if db is not None else Path("results") / f"{cfg.name}.sqlite"
        with ResultStore(db_path) as store:
            with mission_progress(f"{cfg.name}: {len(missions)} {what}") as on_progress:
                summary = run_missions(
                    missions,
                    store,
                    jobs=joblib.cpu_count() if jobs == -1 else jobs,
                    backend=backend,
                    scheduler=scheduler,
                    address=address,
                    execute=execute,
                    on_progress=on_progress,
                )
            elsewhere = f", {summary.elsewhere} by another writer" if summary.elsewhere else ""
            echo(
                f"{cfg.name}: {summary.total} missions, {summary.skipped} already stored, "
                f"{summary.ran} run{elsewhere} in {summary.seconds:.1f} s -> {db_path}"
            )
            keys = {m.key for m in missions}
            rows = [r for r in store.rows() if r["key"] in keys]
            report(rows, title=f"{cfg.name}: per strategy", db_path=db_path)
            if export_csv is not None:
                echo(f"wrote {store.export_csv(export_csv)} rows to {export_csv}")
            if export_parquet is not None:
                echo(f"wrote {store.export_parquet(export_parquet)} rows to {export_parquet}")
    except KeyboardInterrupt:
        sys.stdout.flush()
        sys.stderr.write(f"selfrepair: interrupted: {_stored_after_interrupt(missions, db_path)}\n")
        raise typer.Exit(130) from None
    return 0


def _report(
    rows: "list[dict[str, Value]]",
    *,
    title: str,
    db_path: Path,
    crossover: bool,
    physics: bool = False,
) -> None:
    """What ``experiment`` prints of a single-robot experiment's stored rows: (``physics``, an
    experiment with a ``[physics]`` section) the physics rows' summary and footing table, then
    of the lattice's rows the per-strategy summary, the fault sets that bite, the findings, the
    baselines, and (``crossover``) where replanning catches up (a picture next to the
    database)."""
    from selfrepair.experiment.findings import reference_note, summarize
    from selfrepair.experiment.report import all_findings
    from selfrepair.experiment.summary import fault_set_bite

    if physics:
        rows = _print_physics(rows, title)
    print_summary(summarize(rows), title=title)
    print_fault_sets(fault_set_bite(rows))
    print_findings(all_findings(rows), reference_note(rows))
    print_baselines(rows)
    if crossover:
        print_crossover(rows, db_path.with_name(f"{db_path.stem}-crossover.png"))


def _team_report(rows: "list[dict[str, Value]]", *, title: str, db_path: Path) -> None:
    """What ``experiment`` prints of a team experiment's stored rows: the per-strategy team
    summary."""
    from selfrepair.cli.team import print_team_summary
    from selfrepair.team.summary import summarize_team

    print_team_summary(summarize_team(rows), title=title)


def _print_physics(rows: "list[dict[str, Value]]", title: str) -> "list[dict[str, Value]]":
    """For an experiment with a ``[physics]`` section: the per-strategy summary of the physics
    rows and the footing table (the lattice's missions that physics completes, with and without
    a wall contact); returns the lattice rows, which the usual summary and findings read."""
    from selfrepair.cli.physics import print_footing
    from selfrepair.experiment.findings import summarize
    from selfrepair.experiment.physics import footing_summary, stored_footing_rows

    physics = [r for r in rows if r.get("simulator") == "physics"]
    if physics:
        print_summary(summarize(physics), title=f"{title} in physics")
        echo(f"{title}: the lattice simulator against physics")
        print_footing(footing_summary(stored_footing_rows(rows)))
    return [r for r in rows if r.get("simulator") != "physics"]


def _require_pyarrow() -> None:
    """The library's check, worded with the flags."""
    from selfrepair.experiment.store import require_pyarrow

    try:
        require_pyarrow()
    except ProblemError:
        raise InputError(
            "Parquet export needs pyarrow: pip install 'selfrepair[parquet]' (or use --export-csv)",
            source="--export-parquet",
        ) from None


def _stored_after_interrupt(missions: "Sequence[Mission]", db_path: Path | None) -> str:
    """How much of an interrupted experiment is stored, and how to go on (every stored row is
    whole: rows are committed in atomic batches)."""
    from selfrepair.errors import SelfRepairError
    from selfrepair.experiment.store import ResultStore

    if db_path is None or not missions:
        return "no mission was run"
    try:
        with ResultStore(db_path, read_only=True) as store:
            stored = len(store.keys() & {m.key for m in missions})
    except SelfRepairError:
        stored = 0
    return (
        f"{stored} of {len(missions)} missions are stored in {db_path}; "
        "run the same command again to resume"
    )


@app.command()
def report(
    results: Annotated[
        Path,
        typer.Argument(metavar="RESULTS", help="Results database written by `experiment`."),
    ],
    out: Annotated[
        str,  # not a Path: an empty path must reach the report, which refuses it
        typer.Option("--out", "-o", metavar="DIR", help="Directory for report.md and figures."),
    ],
    mission: Annotated[
        str | None,
        option(
            "--mission",
            "KEY",
            "Key (or key prefix) of the mission to draw (default: a telling one).",
        ),
    ] = None,
) -> int:
    """Write a Markdown report with tables and figures.

    The figures are PNG files (they need matplotlib: the `viz` extra).
    """
    from selfrepair.experiment.report import write_report

    if not results.is_file():
        raise InputError(
            "expected a results database written by `selfrepair experiment`", source=str(results)
        )
    if mission is not None and not mission:
        raise InputError("expected a non-empty mission key or key prefix", source="--mission")
    written = write_report(results, out, mission_key=mission)
    for path in written:
        echo(str(path))
    return 0


@app.command()
def animate(
    trace: TraceArg,
    out: Annotated[Path, typer.Option("--out", "-o", metavar="FILE", help="GIF file to write.")],
    fps: Annotated[int, option("--fps", "N", "Frames per second.", min=1, max=60)] = 4,
    max_frames: Annotated[
        int,
        option(
            "--max-frames", "N", "At most this many frames (long traces are subsampled).", min=1
        ),
    ] = 120,
    max_trace_bytes: MaxTraceBytes = MAX_TRACE_BYTES,
) -> int:
    """Animate a mission trace as a GIF.

    Shows the robot, its path, the faults and the replaced segments.
    """
    from selfrepair.experiment.animate import animate_trace

    with frames_progress(f"drawing {out.name}") as on_frame:
        frames = animate_trace(
            trace,
            out,
            fps=fps,
            max_frames=max_frames,
            on_frame=on_frame,
            max_trace_bytes=max_trace_bytes,
        )
    echo(f"wrote {out} ({frames} frames)")
    return 0
