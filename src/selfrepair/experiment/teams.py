"""Team experiments: ``kind = "team"`` TOML files, their missions, and the mission function.

The hook between the experiment machinery (config errors, stable keys and seeds, the store, the
runner and its backends) and the team package, which builds and runs the cases
(:mod:`selfrepair.team.experiment`). A team file (format in docs/team.md)::

    kind = "team"
    name = "team"
    seed = 7
    repeats = 2

    [[mazes]]
    bundled = "wide-short"       # or file = "x.maze" / generate = {width=.., corridor=2, ...}

    [team]
    sizes = [2, 4, 8]            # robots per team
    tasks_per_robot = [1, 2]     # task loads
    grippers = ["all"]           # all | mixed (every third robot without a gripper)

    [faults]
    cases = ["immobilised-carrying", "gripper", "blocked", "wheels"]
    persistence = ["permanent", "transient"]
    duration = 40                # ticks a transient fault lasts

    [robot]                      # each robot's own wheel-fault handling
    strategy = "replacement"
    table = "handwritten"
    recursion = "flat"

    [[strategies]]
    name = "team-replacement"    # team-replacement | reallocation | alone
    tables = ["handwritten", "generated"]

:func:`load_experiment` reads either kind of experiment file; :func:`expand_team` gives the
missions (keys and seeds as in :mod:`selfrepair.experiment.missions`: the seed derives from the
maze, team size, load, equipment and replicate, so every fault case and strategy of one seed
meets the same team and tasks); :func:`execute_team_mission` is the mission function for
:func:`selfrepair.experiment.runner.run_missions`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BeforeValidator, Field, model_validator

from selfrepair.errors import ConfigError
from selfrepair.execution.faults import Persistence
from selfrepair.experiment.axes import Axis, cross, describe, total
from selfrepair.experiment.config import parse_config, read_experiment_text
from selfrepair.experiment.keys import (
    SCHEMA,
    Mission,
    canonical_json,
    derive_seed,
    keyed_mission,
    portable,
)
from selfrepair.experiment.mazes import maze_identity, maze_label, maze_of
from selfrepair.experiment.schema import ExperimentConfig, MazeSource
from selfrepair.experiment.store import Value
from selfrepair.limits import MAX_CELLS, MAX_FILE_BYTES, MAX_MISSIONS, MAX_ROBOTS, check_limit
from selfrepair.repair.replacement import RecursionMode
from selfrepair.repair.strategies import MissionKind, StrategyName
from selfrepair.team.experiment import FaultCase, TeamCase, case_row
from selfrepair.team.grid import components
from selfrepair.team.model import TeamTableName
from selfrepair.team.randomteam import GripperMix
from selfrepair.team.result import TeamOptions, TeamResult
from selfrepair.textio import JSONObject, source_dir
from selfrepair.tomlfile import Frozen, NonEmpty, find_line, read_toml, validate

__all__ = [
    "TeamExperimentConfig",
    "execute_team_mission",
    "expand_team",
    "is_team_rows",
    "load_experiment",
    "rerun_team_mission",
    "write_team_report",
]

TEAM_KIND = "team"
"""The ``kind`` of a team experiment file (a file without ``kind`` is a single-robot one)."""


class TeamMaze(MazeSource):
    """Where a team maze comes from: exactly one of ``bundled``, ``file``, ``generate`` (a team
    mission has no routes: its scenario places the robots and tasks)."""


class TeamSettings(Frozen):
    """Team sizes, task loads (tasks per robot) and equipment mixes to cross."""

    sizes: Annotated[tuple[Annotated[int, Field(ge=1, le=MAX_ROBOTS)], ...], NonEmpty]
    tasks_per_robot: Annotated[tuple[Annotated[int, Field(ge=1, le=16)], ...], NonEmpty] = (1,)
    grippers: Annotated[tuple[GripperMix, ...], NonEmpty] = (GripperMix.ALL,)



class TeamFaults(Frozen):
    """Fault cases, persistences and the duration (ticks) of a transient fault."""

    cases: Annotated[tuple[FaultCase, ...], NonEmpty]
    persistence: Annotated[tuple[Persistence, ...], NonEmpty] = (Persistence.PERMANENT,)
    duration: Annotated[int, Field(ge=1, le=100_000)] | None = None

    @model_validator(mode="after")
    def _timing(self) -> TeamFaults:
        if Persistence.INTERMITTENT in self.persistence:
            raise ValueError("team faults are permanent or transient, not intermittent")
        if Persistence.TRANSIENT in self.persistence and self.duration is None:
            raise ValueError("persistence \"transient\" needs a 'duration' (ticks, >= 1)")
        return self


class RobotSettings(Frozen):
    """How each robot handles its own wheel faults (a single-robot strategy and table)."""

    strategy: Literal[StrategyName.REPLACEMENT, StrategyName.REPLAN, StrategyName.LOOKAHEAD] = (
        StrategyName.REPLACEMENT
    )
    table: str = "handwritten"
    recursion: RecursionMode = RecursionMode.FLAT


def _team_strategy(value: object) -> StrategyName:
    """``value`` as a team strategy's name (a robot strategy's name is refused)."""
    return StrategyName.of(value, MissionKind.TEAM)


class TeamStrategyConfig(Frozen):
    """One team strategy; team replacement once per table."""

    name: Annotated[StrategyName, BeforeValidator(_team_strategy)]
    tables: tuple[TeamTableName, ...] = (TeamTableName.HANDWRITTEN,)


class TeamExperimentConfig(Frozen):
    """A whole team experiment: mazes x team sizes x loads x equipment x fault cases x
    persistences x strategies x repeats (see the module docstring)."""

    kind: Literal["team"]
    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")]
    description: str = ""
    seed: int = 0
    repeats: Annotated[int, Field(ge=1, le=1000)] = 1
    mazes: Annotated[tuple[TeamMaze, ...], Field(min_length=1)]
    team: TeamSettings
    faults: TeamFaults
    robot: RobotSettings = RobotSettings()
    strategies: Annotated[tuple[TeamStrategyConfig, ...], Field(min_length=1)]
    max_ticks: Annotated[int, Field(ge=1, le=10_000_000)] | None = None
    source: str = "<string>"

    @property
    def base_dir(self) -> Path:
        """The directory relative paths in the file are resolved against."""
        return source_dir(self.source)


def load_experiment(
    path: str | Path, *, max_file_bytes: int | None = MAX_FILE_BYTES
) -> ExperimentConfig | TeamExperimentConfig:
    """Read an experiment file of either kind (``kind = "team"`` or none); a file over
    ``max_file_bytes`` is refused unread."""
    text, source = read_experiment_text(path, max_file_bytes=max_file_bytes)
    data = read_toml(text, source=source)
    if data.get("kind") != TEAM_KIND:
        if "kind" in data:
            raise ConfigError(
                f"key 'kind': expected \"{TEAM_KIND}\" (or no 'kind' for a single-robot "
                f"experiment), got {data['kind']!r}",
                source=source,
                line=find_line(text, ("kind",)),
            )
        return parse_config(text, source=source)
    if "source" in data:
        raise ConfigError("unknown key 'source' (it is set by the loader)", source=source)
    config = validate(
        TeamExperimentConfig, {**data, "source": source}, text=text, source=source
    )
    _check_sizes(config, text)
    return config


def _check_sizes(config: TeamExperimentConfig, text: str) -> None:
    """Every team and its tasks must fit each maze: one cell per robot, two per task."""
    for index, entry in enumerate(config.mazes):
        identity = maze_identity(entry, config.base_dir, config.source, index)
        maze = maze_of(canonical_json(identity))
        label = components(maze)
        sizes: dict[int, int] = {}
        for number in label.values():
            sizes[number] = sizes.get(number, 0) + 1
        area = max(sizes.values(), default=0)
        for size in config.team.sizes:
            need = size + 2 * size * max(config.team.tasks_per_robot)
            if need > area:
                raise ConfigError(
                    f"key 'team.sizes': {size} robots with {max(config.team.tasks_per_robot)} "
                    f"tasks each need {need} free cells; maze {maze_label(identity)!r} has "
                    f"{area} connected free cells",
                    source=config.source,
                    line=find_line(text, ("team", "sizes")),
                )


def expand_team(
    config: TeamExperimentConfig,
    *,
    max_missions: int | None = MAX_MISSIONS,
    max_cells: int | None = MAX_CELLS,
) -> tuple[Mission, ...]:
    """Every mission of ``config``, in a deterministic order, with keys and seeds: one cross
    product (:func:`selfrepair.experiment.axes.cross`) over mazes, team sizes, loads, equipment
    mixes, repeats, fault settings and strategy variants, as single-robot missions are. Raises
    :class:`~selfrepair.errors.LimitError` before building any mission when there would be more
    than ``max_missions``, or a maze file has more than ``max_cells`` cells."""
    variants = tuple(
        (s.name, table if s.name is StrategyName.TEAM_REPLACEMENT else None)
        for s in config.strategies
        for table in (s.tables if s.name is StrategyName.TEAM_REPLACEMENT else s.tables[:1])
    )
    team, faults = config.team, config.faults
    settings_axis = tuple(
        (case, persistence)
        for case in faults.cases
        for persistence in (
            (Persistence.PERMANENT,) if case is FaultCase.NONE else faults.persistence
        )
    )
    mazes = Axis("maze", tuple(config.mazes), "mazes")
    rest = (
        Axis("size", tuple(team.sizes), "team sizes"),
        Axis("load", tuple(team.tasks_per_robot), "loads"),
        Axis("mix", tuple(team.grippers), "equipment mixes"),
        Axis("replicate", tuple(range(config.repeats)), "repeats"),
        Axis("fault", settings_axis, "fault settings"),
        Axis("variant", variants, "strategy variants"),
    )
    check_limit(
        total((mazes, *rest)), max_missions, name="max_missions", what="missions",
        detail=describe((mazes, *rest)), source=config.source,
    )  # fmt: skip
    identities = tuple(
        maze_identity(entry, config.base_dir, config.source, index, max_cells)
        for index, entry in enumerate(config.mazes)
    )
    axes = (Axis("maze", identities, "mazes"), *rest)
    robot = config.robot.model_dump(mode="json")
    missions: dict[str, Mission] = {}
    for point in cross(axes):
        identity, size, load, mix = point["maze"], point["size"], point["load"], point["mix"]
        (case, persistence), (name, table) = point["fault"], point["variant"]
        base: JSONObject = {
            "schema": SCHEMA,
            "kind": TEAM_KIND,
            "maze": identity,
            "team_size": size,
            "tasks": size * load,
            "grippers": mix.value,
            "replicate": point["replicate"],
        }
        seed = derive_seed(config.seed, portable(base))  # the same for every case and strategy
        transient = persistence is Persistence.TRANSIENT
        settings = {
            **base,
            "fault": case.value,
            "persistence": persistence.value,
            "duration": faults.duration if transient else None,
            "strategy": name.value,
            "team_table": None if table is None else table.value,
            "robot": robot,
            "max_ticks": config.max_ticks,
            "seed": seed,
        }
        mission = _mission(config, settings, seed, maze_label(identity), load)
        missions.setdefault(mission.key, mission)
    return tuple(missions.values())


def _mission(
    config: TeamExperimentConfig, settings: dict[str, Any], seed: int, label: str, load: int
) -> Mission:
    strategy, table = settings["strategy"], settings["team_table"]
    labels: tuple[tuple[str, str | int | None], ...] = (
        ("maze", label),
        ("team_size", settings["team_size"]),
        ("tasks", settings["tasks"]),
        ("task_load", load),
        ("grippers", settings["grippers"]),
        ("fault_case", settings["fault"]),
        ("persistence", settings["persistence"]),
        ("replicate", settings["replicate"]),
        ("strategy", strategy),
        ("team_table", table),
        ("variant", f"{strategy}[{table}]" if table else strategy),
    )
    return keyed_mission(config.name, seed, settings, labels)


def is_team_rows(rows: Sequence[Mapping[str, Value]]) -> bool:
    """Whether stored rows come from a team experiment."""
    return bool(rows) and all("fault_case" in r and r.get("team_size") is not None for r in rows)


_DUPLICATES = frozenset({"strategy", "team_table", "variant", "team_size", "tasks", "grippers"})
"""Row columns that the mission's own labels already hold."""

_WARMED: set[tuple[object, ...]] = set()
"""(strategy, table, maze size) combinations this process has already run once."""


def execute_team_mission(mission: Mission) -> Mapping[str, Value]:
    """Run one team mission from its canonical configuration; the first mission of each
    strategy, table and maze size in a process runs twice and only the second run is kept (so
    one-off costs - kernel loading, lattices, the generated table - stay out of the timings)."""
    s = mission.settings
    maze = maze_of(canonical_json(s["maze"]))
    case, options = _case_of(s, mission.seed), _options_of(s, mission.seed)
    warm = (s["strategy"], s["team_table"], maze.width, maze.height)
    if warm not in _WARMED:
        case_row(maze, case, options)
        _WARMED.add(warm)
    row = case_row(maze, case, options)
    return {k: v for k, v in row.items() if k not in _DUPLICATES}


# --- the report -----------------------------------------------------------------------------------


def _case_of(settings: Mapping[str, Any], seed: int) -> TeamCase:
    return TeamCase(
        settings["team_size"],
        settings["tasks"],
        GripperMix(settings["grippers"]),
        FaultCase(settings["fault"]),
        Persistence(settings["persistence"]),
        settings["duration"],
        seed,
    )


def _options_of(settings: Mapping[str, Any], seed: int) -> TeamOptions:
    robot = settings["robot"]
    return TeamOptions(
        strategy=settings["strategy"],
        table=settings["team_table"] or TeamTableName.HANDWRITTEN,
        robot_strategy=robot["strategy"],
        robot_table=robot["table"],
        recursion=robot["recursion"],
        max_ticks=settings["max_ticks"],
        seed=seed,
    )


def _choose(
    rows: Sequence[Mapping[str, Value]], key_prefix: str | None, source: str
) -> Mapping[str, Value]:
    """The mission to draw: the one whose key starts with ``key_prefix``, else a telling one (a
    team replacement with a handover that delivered everything, in a small team)."""
    if key_prefix is not None:
        hits = [r for r in rows if key_prefix and str(r["key"]).startswith(key_prefix)]
        if len(hits) != 1:
            raise ConfigError(
                f"expected the mission key prefix to match exactly one stored mission, "
                f"{len(hits)} match {key_prefix!r}",
                source=source,
            )
        return hits[0]

    def score(row: Mapping[str, Value]) -> tuple[object, ...]:
        candidates = str(row.get("candidates") or "")
        return (
            row.get("all_delivered") == 1,
            row.get("strategy") == StrategyName.TEAM_REPLACEMENT
            and row.get("team_table") == "handwritten",  # the columns, never the label's text
            "handover" in candidates,
            row.get("team_size") in (3, 4),
            str(row.get("persistence")) == "permanent",
            str(row["key"]),
        )

    return max(rows, key=score)


def rerun_team_mission(row: Mapping[str, Value]) -> tuple[TeamResult, Fraction]:
    """Run the stored team mission ``row`` again from its stored configuration (deterministic:
    the same team, tasks, faults and strategy) and its fault-free baseline."""
    from selfrepair.team.experiment import run_case

    settings = json.loads(str(row["config"]))
    seed = int(str(row["seed"]))
    maze = maze_of(canonical_json(settings["maze"]))
    return run_case(maze, _case_of(settings, seed), _options_of(settings, seed))


def write_team_report(
    rows: Sequence[Mapping[str, Value]],
    out_dir: Path,
    source: str,
    *,
    mission_key: str | None = None,
) -> list[Path]:
    """Write the team report for ``rows`` into ``out_dir`` (see :mod:`selfrepair.team.report`);
    the chosen mission is run again from its stored configuration (deterministic)."""
    from selfrepair.team.draw import animate_team_trace, draw_team_frame
    from selfrepair.team.report import render_team_markdown, write_team_figures
    from selfrepair.team.trace import write_team_trace

    written = write_team_figures(rows, out_dir)
    chosen = _choose(rows, mission_key, source)
    settings = json.loads(str(chosen["config"]))
    result, baseline = rerun_team_mission(chosen)
    trace = out_dir / "mission.jsonl"
    write_team_trace(result, trace, baseline)
    picture = draw_team_frame(trace, out_dir / "mission.png")
    animation = out_dir / "mission.gif"
    animate_team_trace(trace, animation, max_frames=60)
    note = (
        f"{settings['team_size']} robots, {settings['tasks']} tasks on {chosen['maze']}, fault "
        f"{chosen.get('fault')} ({settings['persistence']}), {chosen['variant']}; "
        f"{len(result.delivered)}/{settings['tasks']} delivered, makespan {result.makespan} "
        f"ticks against {baseline} without the fault"
    )
    report = out_dir / "report.md"
    report.write_text(render_team_markdown(rows, source, chosen, note), encoding="utf-8")
    return [report, *written, trace, picture, animation]
