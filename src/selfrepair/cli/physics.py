"""``selfrepair physics ...``: the four-wheel robot in MuJoCo (the ``physics`` extra).

* ``physics fidelity``: every action run in physics against the lattice (open loop and tracked);
  ``--write-domain FILE`` writes the domain identified from it; ``--in-sequence`` adds the second
  table, every nominal action run after each of a few others. Exit 0.
* ``physics run``: one mission (every option of ``run``) driven through MuJoCo by the same loop;
  ``--video FILE`` renders it headless (GIF or MP4), ``--trace FILE`` writes the lattice trace
  (localised poses) that ``selfrepair view`` shows. Exit 0 when the goal is reached, 1 otherwise.

MuJoCo and imageio are imported inside the commands; without the extra a command says what to
install (exit 2).
"""

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

from selfrepair.cli._app import app, command_group, echo, echo_json, flag, number_json, option
from selfrepair.cli._inputs import Json, TraceOut
from selfrepair.cli._mission import MissionOptions, mission_options
from selfrepair.cli._spec import mission_spec
from selfrepair.errors import InputError
from selfrepair.textio import JSONObject

if TYPE_CHECKING:
    from selfrepair.physics.fidelity import FidelityReport, SequenceReport
    from selfrepair.physics.mission import PhysicsMission

__all__ = [
    "fidelity_markdown",
    "outcome_json",
    "physics_experiment",
    "physics_fidelity",
    "physics_run",
    "sequence_markdown",
]

physics_app = command_group(help="The four-wheel robot in MuJoCo: model fidelity and missions.")
app.add_typer(physics_app, name="physics")

OpenLoop = Annotated[
    bool, flag("--open-loop", "Run wheel speeds open loop instead of tracking the lattice.")
]


@physics_app.command("fidelity")
def physics_fidelity(
    as_json: Json = False,
    nominal: Annotated[bool, flag("--nominal", "Only the fault-free robot's 81 rows.")] = False,
    write_domain: Annotated[
        Path | None, option("--write-domain", "FILE", "Write the identified domain here.")
    ] = None,
    in_sequence: Annotated[
        bool, flag("--in-sequence", "Also run every nominal action after each of a few others.")
    ] = False,
) -> int:
    """Run every action in physics and compare its end pose with the lattice's.

    Per action: position error (cells) and heading error (degrees), open loop and tracked;
    physics confirms an action whose tracked end is within 0.05 cells and 3 degrees. Then every
    action under every single fault that forbids it, per fault-behaviour model: the wheels
    perform what the model says, compared with the lattice's motion of that action. With
    --in-sequence, a second table: every nominal action run tracked after each of FFFF, BBBB,
    SFFS, FBFB, BFBF and itself; it holds in sequence when within 0.05 cells and 3 degrees
    after every one (and --write-domain marks each kept action with whether it does).
    """
    from selfrepair.physics.fidelity import measure, measure_in_sequence

    report = measure(faulty=not nominal)
    sequence = measure_in_sequence(from_rest=report) if in_sequence else None
    if write_domain is not None:
        import json

        text = json.dumps(report.identified(sequence=sequence), indent=1) + "\n"
        write_domain.write_text(text, encoding="utf-8")
    if as_json:
        out: JSONObject = {
            "summary": report.summary(),
            "rows": [_row_json(r) for r in report.rows],
        }
        if sequence is not None:
            out["in_sequence"] = _sequence_json(sequence)
        echo_json(out)
        return 0
    echo(fidelity_markdown(report))
    if sequence is not None:
        echo("")
        echo(sequence_markdown(sequence))
    return 0


def _sequence_json(report: "SequenceReport") -> JSONObject:
    return {
        "predecessors": list(report.predecessors),
        "summary": report.summary(),
        "rows": [
            {
                "action": r.action,
                "motion": r.motion,
                "from_rest": r.from_rest,
                "holds": r.holds,
                "after": [
                    {"first": f, "position": number_json(p), "heading": number_json(h)}
                    for f, p, h in r.after
                ],
            }
            for r in report.rows
        ],
    }


def sequence_markdown(report: "SequenceReport") -> str:
    """The in-sequence table as Markdown: the summary per motion kind, then one row per action
    with its end error (cells / degrees) after each predecessor."""
    lines = [
        f"in sequence (after {', '.join(report.predecessors)} and itself):",
        "",
        "| kind | actions | confirmed from rest | hold in sequence | median worst error |",
        "|---|---:|---:|---:|---|",
    ]
    for kind, s in report.summary().items():
        lines.append(
            f"| {kind} | {s['actions']} | {s['from_rest']} | {s['in_sequence']} | "
            f"{s['worst_position_median']:.3f} cells, {s['worst_heading_median']:.1f} deg |"
        )
    heads = " | ".join(f"after {p}" for p in (*report.predecessors, "itself"))
    lines += [
        "",
        f"| action | motion | from rest | in sequence | {heads} |",
        "|---|---|---|---|" + "---:|" * (len(report.predecessors) + 1),
    ]
    for r in report.rows:
        cells = " | ".join(f"{p:.3f} / {h:.1f}" for _, p, h in r.after)
        lines.append(
            f"| {r.action} | {r.motion} | {'yes' if r.from_rest else 'no'} | "
            f"{'yes' if r.holds else 'no'} | {cells} |"
        )
    return "\n".join(lines)


def _row_json(row: Any) -> JSONObject:
    return {
        "action": row.action,
        "motion": row.motion,
        "faults": row.faults,
        "behaviour": row.behaviour,
        "executed": row.executed,
        "open_position": number_json(row.open_position),
        "open_heading": number_json(row.open_heading),
        "tracked_position": number_json(row.tracked_position),
        "tracked_heading": number_json(row.tracked_heading),
        "confirmed": row.confirmed,
        "snapped": list(row.snapped) if row.snapped is not None else None,
        "why": row.why,
    }


def fidelity_markdown(report: "FidelityReport") -> str:
    """The fidelity table as Markdown: the summary, then one row per action."""
    lines = []
    for label, s in report.summary().items():
        lines.append(
            f"{label}: tracked {s['tracked_confirmed']}/{s['actions']} confirmed "
            f"({100 * s['tracked_share']:.0f}%), open loop {s['open_loop_confirmed']}/"
            f"{s['actions']} ({100 * s['open_loop_share']:.0f}%); median tracked error "
            f"{s['tracked_position_median']:.3f} cells, {s['tracked_heading_median']:.1f} deg; "
            f"{s['snapped']} snap to the lattice"
        )
    lines += [
        "",
        "| action | motion | faults | behaviour | performed | open: cells | open: deg | "
        "tracked: cells | tracked: deg | confirmed | note |",
        "|---|---|---|---|---|---:|---:|---:|---:|---|---|",
    ]
    for r in report.rows:
        lines.append(
            f"| {r.action} | {r.motion} | {r.faults or '-'} | {r.behaviour or '-'} | "
            f"{r.executed} | {r.open_position:.3f} | {r.open_heading:.1f} | "
            f"{r.tracked_position:.3f} | {r.tracked_heading:.1f} | "
            f"{'yes' if r.confirmed else 'no'} | {r.why} |"
        )
    return "\n".join(lines)


@physics_app.command("run")
@mission_options
def physics_run(
    *,
    strategy: Annotated[
        str, option("--strategy", "NAME", "Repair strategy (as for run).")
    ] = "replacement",
    mission: MissionOptions,
    open_loop: OpenLoop = False,
    video: Annotated[
        Path | None, option("--video", "FILE", "Render the mission to a .gif or .mp4.")
    ] = None,
    trace: TraceOut = None,
    as_json: Json = False,
) -> int:
    """Run one mission in MuJoCo: the same planner and strategy, localised after each action.

    Reports goal reached, wall contacts, the final pose error, simulated seconds and repairs.
    Exit 1 when the goal is not reached.
    """
    if video is not None and video.suffix.lower() not in (".gif", ".mp4"):
        raise InputError(f"expected a .gif or .mp4 file, got {video.name!r}", source="--video")
    from selfrepair.execution.trace import write_trace
    from selfrepair.physics.mission import VideoSpec, run_physics_mission

    spec = mission_spec(mission, strategy)
    done = run_physics_mission(
        spec, tracked=not open_loop, video=VideoSpec(video) if video is not None else None
    )
    if trace is not None:
        write_trace(done.result, trace)
    if as_json:
        echo_json(outcome_json(done))
    else:
        for key, value in outcome_json(done).items():
            echo(f"{key}: {value}")
    return 0 if done.result.reached else 1


def outcome_json(done: "PhysicsMission") -> JSONObject:
    """A physics mission's outcome as JSON-ready values."""
    o, r = done.outcome, done.result
    return {
        "status": r.status.value,
        "reason": r.reason,
        "strategy": r.spec.strategy,
        "tracked": o.tracked,
        "reached": o.reached,
        "wall_contacts": o.wall_contacts,
        "final_error_cells": number_json(o.final_error),
        "seconds": number_json(o.seconds),
        "ticks": str(r.ticks),
        "physics_steps": o.physics_steps,
        "actions": len(done.steps),
        "repairs": o.repairs,
        "deviations": o.deviations,
        "max_position_error_cells": number_json(o.max_position_error),
        "max_heading_error_degrees": number_json(o.max_heading_error),
    }


@physics_app.command("experiment")
def physics_experiment(
    mazes: Annotated[
        list[str] | None,
        option("--maze", "NAME", "A bundled maze (repeat it; default: the short two)."),
    ] = None,
    strategies: Annotated[
        list[str] | None,
        option(
            "--strategy",
            "NAME",
            "replan, replacement, rewriting or lookahead (repeat it; default: all four).",
        ),
    ] = None,
    open_loop: OpenLoop = False,
    robot: Annotated[
        str,
        option(
            "--robot",
            "MODEL",
            "four-wheel (the lattice's 81 actions, hand-written table) or "
            "four-wheel-confirmed (only the actions physics confirms, a generated table) or "
            "four-wheel-in-sequence (only those that also hold in sequence, a generated table).",
        ),
    ] = "four-wheel",
    workers: Annotated[int, option("--workers", "N", "Processes to run missions in.", min=1)] = 1,
    as_json: Json = False,
) -> int:
    """The paper's missions (bundled mazes, routes, 12 fault sets) on the lattice and in MuJoCo.

    Per strategy: the missions the lattice simulator completes, and how many of those physics
    completes, with and without wall contact.
    """
    from dataclasses import asdict

    from selfrepair.experiment.physics import (
        DEFAULT_MAZES,
        STRATEGIES,
        footing_summary,
        physics_experiment,
    )

    rows = physics_experiment(
        tuple(mazes or DEFAULT_MAZES),
        tuple(strategies or STRATEGIES),
        tracked=not open_loop,
        workers=workers,
        robot=robot,
    )
    summary = footing_summary(rows)
    if as_json:
        echo_json({"summary": summary, "rows": [asdict(r) for r in rows]})
        return 0
    print_footing(summary)
    return 0


def print_footing(summary: dict[str, dict[str, Any]]) -> None:
    """The per-strategy footing table of :func:`~selfrepair.experiment.physics.footing_summary`
    as Markdown (``physics experiment`` and experiments with a ``[physics]`` section)."""
    echo("| strategy | missions | lattice reached | physics reached of those | "
         "of those without wall contact |")  # fmt: skip
    echo("|---|---:|---:|---:|---:|")
    for label, s in summary.items():
        share = s["physics_share_of_lattice"]
        clean = s["no_contact_share_of_lattice"]
        echo(
            f"| {label} | {s['missions']} | {s['lattice_reached']} | {s['both_reached']} "
            f"({_percent(share)}) | {s['both_reached_no_contact']} ({_percent(clean)}) |"
        )


def _percent(share: float | None) -> str:
    return "-" if share is None else f"{100 * share:.1f}%"
