"""Team commands: ``selfrepair team run|compare|replay|table|frame`` and the team branch of
``selfrepair experiment``.

Exit codes: ``team run`` 0 when every item is delivered, 1 otherwise; ``team replay`` 0 when the
trace re-simulates with no conflict and no teleport, 1 otherwise; bad input is exit 2 (see
:func:`selfrepair.cli.main`). Heavy modules (numpy-based engine, scipy, matplotlib, pydantic)
are imported inside the commands, so ``selfrepair --help`` stays cheap.
"""

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from selfrepair.cli._app import (
    MaxCells,
    MaxFileBytes,
    MaxRobots,
    MaxTasks,
    MaxTraceBytes,
    app,
    command_group,
    console,
    echo,
    echo_json,
    option,
    option_group,
)
from selfrepair.cli._inputs import Backend, Json, TraceOut, find_input
from selfrepair.cli._mission import Events, SensingOpt, check_choice
from selfrepair.limits import (
    MAX_CELLS,
    MAX_FILE_BYTES,
    MAX_ROBOTS,
    MAX_TASKS,
    MAX_TRACE_BYTES,
)

if TYPE_CHECKING:
    from selfrepair.team.model import TeamScenario
    from selfrepair.team.result import TeamResult
    from selfrepair.team.summary import TeamSummary

__all__ = ["ScenarioLimits", "print_team_summary", "team_app"]

team_app = command_group(help="Team missions: several robots that repair each other.")
app.add_typer(team_app, name="team")

_STRATEGY_HELP = "team-replacement, reallocation or alone."

_TeamTrace = Annotated[
    Path, typer.Argument(metavar="TRACE", help="A team trace written by team run --trace.")
]


def _out() -> Any:
    """A rich console on stdout: the terminal's width on a terminal, wide when piped (tables
    keep every name and number on one line in logs; see :func:`selfrepair.cli._app.console`)."""
    return console()


RobotTable = Annotated[
    str | None,
    option(
        "--robot-table",
        "TABLE",
        "The robots' own table for their wheel faults: a bundled name or FILE.json "
        "(default: the scenario's 'table', else the robot's default, generated for a robot "
        "without a bundled one).",
    ),
]


TeamSensingRange = Annotated[
    int | None,
    option(
        "--sensing-range",
        "R",
        "Chebyshev cells each robot sees around it (default: the scenario's).",
        min=0,
    ),
]


def _with_world(parsed: Any, events: str, sensing: str, sensing_range: int | None) -> Any:
    """``parsed`` with the world events and sensing of the command line (``--events`` replaces
    the scenario's events; an empty option keeps the scenario's)."""
    from dataclasses import replace

    from selfrepair.world.events import Sensing, parse_events

    world = parsed.world
    if events:
        world = replace(world, events=parse_events(events))
    if sensing:
        check_choice(sensing, tuple(Sensing), "--sensing")
        world = replace(world, sensing=Sensing(sensing))
    if sensing_range is not None:
        world = replace(world, sensing_range=sensing_range)
    if world is parsed.world:
        return parsed
    from selfrepair.team.check import check_scenario

    changed = replace(parsed, world=world, digest="")  # no longer the file's content
    check_scenario(changed)
    return changed


ScenarioArg = Annotated[
    str, typer.Argument(metavar="SCENARIO", help="Bundled scenario (three-robots) or FILE.toml.")
]
"""The scenario argument of ``team run`` and ``team compare``: one declaration, one help text."""


@dataclass(frozen=True, slots=True)
class ScenarioLimits:
    """The limits of reading a scenario, one flag each, as ``team run`` and ``team compare``
    take them (:class:`selfrepair.team.randomteam.Limits` in the library)."""

    max_robots: MaxRobots = MAX_ROBOTS
    max_tasks: MaxTasks = MAX_TASKS
    max_cells: MaxCells = MAX_CELLS
    max_file_bytes: MaxFileBytes = MAX_FILE_BYTES

    def read(self, scenario: str) -> "TeamScenario":
        """The bundled scenario or scenario file ``scenario``, read within these limits."""
        from selfrepair.team.scenario import Limits, resolve_scenario

        limits = Limits(self.max_robots, self.max_tasks, self.max_cells, self.max_file_bytes)
        return resolve_scenario(scenario, limits=limits)


scenario_limits = option_group(ScenarioLimits, "limits")
"""A command with the four limit options in place of its parameter ``limits``."""


def _options(
    strategy: str, table: str, max_ticks: int | None, backend: str, robot_table: str | None = None
) -> Any:
    from selfrepair.team.result import TeamOptions

    return TeamOptions(
        strategy=strategy,
        table=table,
        max_ticks=max_ticks,
        backend=backend,
        robot_table="" if robot_table is None else find_input(robot_table),
    )


@team_app.command("run")
@scenario_limits
def team_run(
    *,
    scenario: ScenarioArg,
    strategy: Annotated[str, option("--strategy", "NAME", _STRATEGY_HELP)] = "team-replacement",
    table: Annotated[
        str, option("--table", "TABLE", "Team table: handwritten or generated.")
    ] = "handwritten",
    robot_table: RobotTable = None,
    trace: TraceOut = None,
    as_json: Json = False,
    max_ticks: Annotated[
        int | None,
        option("--max-ticks", "N", "End the mission after this many ticks (default: generous)."),
    ] = None,
    backend: Backend = "auto",
    detect: Annotated[
        str | None,
        option(
            "--detect",
            "MODE",
            "How robots learn their wheel faults: now or on-use (default: the scenario's).",
        ),
    ] = None,
    events: Events = "",
    sensing: SensingOpt = "",
    sensing_range: TeamSensingRange = None,
    limits: ScenarioLimits,
) -> int:
    """Run one team mission.

    Allocation, team plan, execution with faults, world events and repairs (--events,
    --sensing and --sensing-range replace the scenario's [world]). Exit 1 when an item is not
    delivered.
    """
    from selfrepair.team.engine import run_team
    from selfrepair.team.metrics import team_row
    from selfrepair.team.trace import write_team_trace

    parsed = limits.read(scenario)
    if detect is not None:
        from dataclasses import replace

        from selfrepair.errors import choice
        from selfrepair.execution.faults import Detection

        parsed = replace(parsed, detection=choice(Detection, detect, "detection"))
    parsed = _with_world(parsed, events, sensing, sensing_range)
    options = _options(strategy, table, max_ticks, backend, robot_table)
    result = run_team(parsed, options)
    disturbed = parsed.faults or parsed.world
    baseline = run_team(parsed.without_faults(), options).makespan if disturbed else None
    if trace is not None:
        write_team_trace(result, trace, baseline)
    if as_json:
        echo_json(team_row(result, baseline))
    else:
        _print_result(result, baseline)
    return 0 if result.all_delivered else 1


def _print_result(result: "TeamResult", baseline: Any) -> None:
    scenario = result.scenario
    echo(
        f"{scenario.name}: {len(scenario.robots)} robots, {len(scenario.tasks)} tasks on "
        f"{scenario.maze.name or 'the maze'}, strategy {result.options.label}"
    )
    for fault in scenario.faults:
        echo(f"  fault: {fault.describe()} ({fault.persistence})")
    if scenario.world:
        echo(f"  world: {scenario.world.describe()}")
    for d in result.discoveries:
        echo(
            f"  tick {d.at / result.scale:g}: {d.robot} learns of fault {d.index} "
            f"({scenario.faults[d.index].describe()}), {d.delay / result.scale:g} ticks after "
            f"it started (detection {scenario.detection})"
        )
    ratio = (
        f" ({float(result.makespan / baseline):.2f} x fault-free {baseline})" if baseline else ""
    )
    echo(
        f"{result.status}: {len(result.delivered)}/{len(scenario.tasks)} delivered, makespan "
        f"{result.makespan} ticks{ratio}; {result.reason}"
    )
    for r in result.repairs:
        what = f"{r.candidate} with {r.helper}" if r.candidate else str(r.source)
        echo(
            f"  tick {r.at / result.scale:g}: {r.robot} {r.kind} at {r.action} -> {r.outcome} by "
            f"{what}; disturbed {', '.join(r.disturbed) or 'none'}; {r.plans} plannings; "
            f"{r.latency_ns / 1000:.0f} µs"
        )
    echo(
        f"messages {result.messages}, drive plannings {result.plans}, yields {result.yields}, "
        f"own repairs {len(result.own_repairs)}"
    )


@team_app.command("compare")
@scenario_limits
def team_compare(
    *,
    scenario: ScenarioArg,
    repeats: Annotated[
        int, option("--repeats", "N", "Runs per strategy; latencies are medians.", min=1, max=1000)
    ] = 5,
    backend: Backend = "auto",
    robot_table: RobotTable = None,
    limits: ScenarioLimits,
) -> int:
    """Run a scenario with every team strategy, side by side.

    The first repair's latency is the median over the repeats, after a warm-up run.
    """
    import statistics

    from rich.table import Table
    from rich.text import Text

    from selfrepair.repair.strategies import StrategyName
    from selfrepair.team.engine import run_team
    from selfrepair.team.model import TeamTableName

    parsed = limits.read(scenario)
    variants = [
        (StrategyName.TEAM_REPLACEMENT, TeamTableName.HANDWRITTEN),
        (StrategyName.TEAM_REPLACEMENT, TeamTableName.GENERATED),
        (StrategyName.REALLOCATION, TeamTableName.HANDWRITTEN),
        (StrategyName.ALONE, TeamTableName.HANDWRITTEN),
    ]
    calm = _options(StrategyName.ALONE, "handwritten", None, backend, robot_table)
    baseline = run_team(parsed.without_faults(), calm)
    view = Table(title=f"{parsed.name}: fault-free makespan {baseline.makespan} ticks")
    for column in (
        "strategy", "delivered", "makespan", "vs fault-free", "first repair µs (median)",
        "disturbed", "plannings in repairs", "messages",
    ):  # fmt: skip
        view.add_column(column, justify="left" if column == "strategy" else "right")
    for strategy, table in variants:
        options = _options(strategy, table, None, backend, robot_table)
        run_team(parsed, options)  # warm: one-off costs stay out of the latencies
        runs = [run_team(parsed, options) for _ in range(repeats)]
        result = runs[-1]
        first = [r.repairs[0].latency_ns for r in runs if r.repairs]
        disturbed = {name for r in result.repairs for name in r.disturbed}
        view.add_row(
            Text(options.label),
            f"{len(result.delivered)}/{len(parsed.tasks)}",
            f"{float(result.makespan):g}",
            f"{float(result.makespan / baseline.makespan):.2f}" if result.all_delivered else "-",
            f"{statistics.median(first) / 1000:,.0f}" if first else "-",
            str(len(disturbed)),
            str(sum(r.plans for r in result.repairs)),
            str(result.messages),
        )
    _out().print(view)
    return 0


@team_app.command("replay")
def team_replay(
    trace: _TeamTrace,
    max_trace_bytes: MaxTraceBytes = MAX_TRACE_BYTES,
) -> int:
    """Re-simulate a team trace; report what does not hold.

    No teleport, no conflict, every act possible. Exit 1 otherwise.
    """
    from selfrepair.team.trace import read_team_trace, replay_team

    report = replay_team(read_team_trace(trace, max_trace_bytes=max_trace_bytes))
    echo(f"{trace}: {report}")
    return 0 if report.ok else 1


@team_app.command("table")
def team_table(
    name: Annotated[
        str, typer.Argument(metavar="TABLE", help="handwritten or generated.")
    ] = "handwritten",
    as_json: Json = False,
) -> int:
    """Print a team replacement table.

    Per situation, its candidates in order.
    """
    from rich.table import Table

    from selfrepair.team.table import get_team_table

    table = get_team_table(name)
    rows = [
        {
            "action": key[0].value,
            "incident": key[1].value,
            "load": key[2].value,
            "candidate": t.name,
            "scope": t.scope.value,
            "steps": str(t),
        }
        for key, t in table.rows()
    ]
    if as_json:
        echo_json(rows)
        return 0
    view = Table(title=f"team table {table.name}: {len(rows)} candidates")
    for column in ("action", "incident", "load", "candidate", "scope", "steps"):
        view.add_column(column)
    for row in rows:
        view.add_row(
            *(row[c] for c in ("action", "incident", "load", "candidate", "scope", "steps"))
        )
    _out().print(view)
    return 0


@team_app.command("frame")
def team_frame(
    trace: _TeamTrace,
    out: Annotated[Path, typer.Option("--out", "-o", metavar="FILE", help="PNG file to write.")],
    tick: Annotated[
        float | None,
        option("--tick", "T", "The moment to draw, in ticks (default: the first repair)."),
    ] = None,
    max_trace_bytes: MaxTraceBytes = MAX_TRACE_BYTES,
) -> int:
    """Draw one moment of a team trace as a PNG.

    Shows the robots, their paths, the items and the faults.
    """
    from selfrepair.team.draw import draw_team_frame

    written = draw_team_frame(trace, out, tick=tick, max_trace_bytes=max_trace_bytes)
    echo(f"wrote {written}")
    return 0


def print_team_summary(summaries: "list[TeamSummary]", *, title: str) -> None:
    """The per-strategy team summary as a table."""
    from rich.table import Table
    from rich.text import Text

    from selfrepair.team.summary import TeamSummary

    out = _out()
    view = Table(title=title)
    for i, header in enumerate(TeamSummary.HEADERS):
        view.add_column(header, justify="left" if i == 0 else "right")
    for s in summaries:
        view.add_row(*(Text(cell) for cell in s.cells()))
    out.print(view)
