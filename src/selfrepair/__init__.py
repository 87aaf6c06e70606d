"""selfrepair: self-repairing robot plans.

A robot executes a plan; when an actuator fault makes some actions unavailable, a replacement
system swaps each faulty action for a precomputed sub-plan with the same start and end state,
falling back to replanning only when no replacement fits. See the README for the big picture.

The names a user needs are here, ``import selfrepair as sr``::

    maze = sr.load_bundled("narrow-long")
    route = sr.bundled_routes("narrow-long")[0]
    robot = sr.get_domain("four-wheel")
    spec = sr.MissionSpec(maze, route.start, route.goal, domain=robot, strategy="replacement",
                          schedule=sr.FaultSchedule.permanent(robot.parse_faults("FL:F")))
    row = sr.mission_row(sr.run_mission(spec))

Each is imported from its home module on first use (PEP 562), so ``import selfrepair`` and
``selfrepair --help`` stay fast and load neither numba, matplotlib nor scipy. ``__version__`` is
looked up the same way (reading the installed metadata costs more than the rest of a quick
command's start-up).
"""

from __future__ import annotations

TYPE_CHECKING = False  # not typing's: importing typing would double the cost of this import
if TYPE_CHECKING:  # what the names are, for type checkers and editors; nothing loads at run time
    from types import ModuleType
    from typing import Any

    from selfrepair.errors import (
        ConfigError,
        InputError,
        LimitError,
        ProblemError,
        SelfRepairError,
        TableError,
        TraceError,
    )
    from selfrepair.execution.executor import run_mission
    from selfrepair.execution.faults import FaultEvent, FaultSchedule
    from selfrepair.execution.metrics import mission_row
    from selfrepair.execution.result import MissionResult, MissionSpec, StepSource
    from selfrepair.execution.trace import read_trace, write_trace
    from selfrepair.geometry import Heading, Pose, parse_cell, parse_pose
    from selfrepair.repair.strategies import (
        RepairSource,
        StrategyName,
        StrategyOptions,
        register_strategy,
        strategy_names,
    )
    from selfrepair.robots.domain import Domain, check_domain
    from selfrepair.robots.registry import domain_names, get_domain, load_plugin, register_domain
    from selfrepair.search.lattice import plan
    from selfrepair.search.problem import PlanningProblem
    from selfrepair.tables.fileformat import bundled_table, dump_table, load_table
    from selfrepair.tables.generate import generate_table
    from selfrepair.tables.model import GenerateOptions, ReplacementTable
    from selfrepair.team.engine import run_team
    from selfrepair.team.metrics import team_row
    from selfrepair.team.model import TeamScenario
    from selfrepair.team.result import TeamOptions, TeamResult
    from selfrepair.team.scenario import resolve_scenario
    from selfrepair.world.bundled import bundled_routes, load_bundled, maze_names, resolve_maze
    from selfrepair.world.events import Sensing, WorldEvent, WorldSchedule, random_world
    from selfrepair.world.loading import load_maze
    from selfrepair.world.maze import Maze
    from selfrepair.world.routes import Route


def _home(name: str) -> ModuleType | None:
    """The module that defines the public ``name`` (imported now), or ``None``. Written as
    import statements, not module names in strings, so the import contracts see them."""
    match name:
        case "MissionSpec" | "MissionResult" | "StepSource":
            from selfrepair.execution import result as execution_result
            return execution_result
        case "FaultSchedule" | "FaultEvent":
            from selfrepair.execution import faults as execution_faults
            return execution_faults
        case "run_mission":
            from selfrepair.execution import executor as execution_executor
            return execution_executor
        case "mission_row":
            from selfrepair.execution import metrics as execution_metrics
            return execution_metrics
        case "read_trace" | "write_trace":
            from selfrepair.execution import trace as execution_trace
            return execution_trace
        case (
            "StrategyOptions"
            | "StrategyName"
            | "RepairSource"
            | "register_strategy"
            | "strategy_names"
        ):
            from selfrepair.repair import strategies as repair_strategies
            return repair_strategies
        case "plan":
            from selfrepair.search import lattice as search_lattice
            return search_lattice
        case "PlanningProblem":
            from selfrepair.search import problem as search_problem
            return search_problem
        case "Domain" | "check_domain":
            from selfrepair.robots import domain as robots_domain
            return robots_domain
        case "get_domain" | "register_domain" | "domain_names" | "load_plugin":
            from selfrepair.robots import registry as robots_registry
            return robots_registry
        case "ReplacementTable" | "GenerateOptions":
            from selfrepair.tables import model as tables_model
            return tables_model
        case "bundled_table" | "load_table" | "dump_table":
            from selfrepair.tables import fileformat as tables_fileformat
            return tables_fileformat
        case "generate_table":
            from selfrepair.tables import generate as tables_generate
            return tables_generate
        case "Maze":
            from selfrepair.world import maze as world_maze
            return world_maze
        case "WorldEvent" | "WorldSchedule" | "Sensing" | "random_world":
            from selfrepair.world import events as world_events
            return world_events
        case "load_bundled" | "bundled_routes" | "maze_names" | "resolve_maze":
            from selfrepair.world import bundled as world_bundled
            return world_bundled
        case "load_maze":
            from selfrepair.world import loading as world_loading
            return world_loading
        case "Route":
            from selfrepair.world import routes as world_routes
            return world_routes
        case "Pose" | "Heading" | "parse_pose" | "parse_cell":
            from selfrepair import geometry as geometry
            return geometry
        case "run_team":
            from selfrepair.team import engine as team_engine
            return team_engine
        case "TeamScenario":
            from selfrepair.team import model as team_model
            return team_model
        case "TeamOptions" | "TeamResult":
            from selfrepair.team import result as team_result
            return team_result
        case "resolve_scenario":
            from selfrepair.team import scenario as team_scenario
            return team_scenario
        case "team_row":
            from selfrepair.team import metrics as team_metrics
            return team_metrics
        case (
            "SelfRepairError"
            | "InputError"
            | "ConfigError"
            | "LimitError"
            | "ProblemError"
            | "TableError"
            | "TraceError"
        ):
            from selfrepair import errors as errors
            return errors
        case _:
            return None


__all__ = [
    "ConfigError",
    "Domain",
    "FaultEvent",
    "FaultSchedule",
    "GenerateOptions",
    "Heading",
    "InputError",
    "LimitError",
    "Maze",
    "MissionResult",
    "MissionSpec",
    "PlanningProblem",
    "Pose",
    "ProblemError",
    "RepairSource",
    "ReplacementTable",
    "Route",
    "SelfRepairError",
    "Sensing",
    "StepSource",
    "StrategyName",
    "StrategyOptions",
    "TableError",
    "TeamOptions",
    "TeamResult",
    "TeamScenario",
    "TraceError",
    "WorldEvent",
    "WorldSchedule",
    "__version__",
    "bundled_routes",
    "bundled_table",
    "check_domain",
    "domain_names",
    "dump_table",
    "generate_table",
    "get_domain",
    "load_bundled",
    "load_maze",
    "load_plugin",
    "load_table",
    "maze_names",
    "mission_row",
    "parse_cell",
    "parse_pose",
    "plan",
    "random_world",
    "read_trace",
    "register_domain",
    "register_strategy",
    "resolve_maze",
    "resolve_scenario",
    "run_mission",
    "run_team",
    "strategy_names",
    "team_row",
    "write_trace",
]
"""The public names: ``__version__`` and every name :func:`_home` knows (a test checks both
agree)."""


def __getattr__(name: str) -> Any:
    """Import a public name from its home on first use and keep it (PEP 562)."""
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            found: Any = version("selfrepair")
        except PackageNotFoundError:  # pragma: no cover - a source tree without install
            found = "0.0.0"
    elif name in __all__ and (home := _home(name)) is not None:
        found = getattr(home, name)
    else:
        raise AttributeError(f"module 'selfrepair' has no attribute {name!r}")
    globals()[name] = found
    return found


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
