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
    from selfrepair.world.loading import load_maze
    from selfrepair.world.maze import Maze
    from selfrepair.world.routes import Route

_HOMES: dict[str, str] = {
    # a mission of one robot
    "MissionSpec": "selfrepair.execution.result",
    "MissionResult": "selfrepair.execution.result",
    "StepSource": "selfrepair.execution.result",
    "FaultSchedule": "selfrepair.execution.faults",
    "FaultEvent": "selfrepair.execution.faults",
    "run_mission": "selfrepair.execution.executor",
    "mission_row": "selfrepair.execution.metrics",
    "read_trace": "selfrepair.execution.trace",
    "write_trace": "selfrepair.execution.trace",
    # strategies
    "StrategyOptions": "selfrepair.repair.strategies",
    "StrategyName": "selfrepair.repair.strategies",
    "RepairSource": "selfrepair.repair.strategies",
    "register_strategy": "selfrepair.repair.strategies",
    "strategy_names": "selfrepair.repair.strategies",
    # planning
    "plan": "selfrepair.search.lattice",
    "PlanningProblem": "selfrepair.search.problem",
    # robots
    "Domain": "selfrepair.robots.domain",
    "check_domain": "selfrepair.robots.domain",
    "get_domain": "selfrepair.robots.registry",
    "register_domain": "selfrepair.robots.registry",
    "domain_names": "selfrepair.robots.registry",
    "load_plugin": "selfrepair.robots.registry",
    # tables
    "ReplacementTable": "selfrepair.tables.model",
    "GenerateOptions": "selfrepair.tables.model",
    "bundled_table": "selfrepair.tables.fileformat",
    "load_table": "selfrepair.tables.fileformat",
    "dump_table": "selfrepair.tables.fileformat",
    "generate_table": "selfrepair.tables.generate",
    # mazes, routes, poses
    "Maze": "selfrepair.world.maze",
    "load_bundled": "selfrepair.world.bundled",
    "bundled_routes": "selfrepair.world.bundled",
    "maze_names": "selfrepair.world.bundled",
    "resolve_maze": "selfrepair.world.bundled",
    "load_maze": "selfrepair.world.loading",
    "Route": "selfrepair.world.routes",
    "Pose": "selfrepair.geometry",
    "Heading": "selfrepair.geometry",
    "parse_pose": "selfrepair.geometry",
    "parse_cell": "selfrepair.geometry",
    # teams
    "run_team": "selfrepair.team.engine",
    "TeamScenario": "selfrepair.team.model",
    "TeamOptions": "selfrepair.team.result",
    "TeamResult": "selfrepair.team.result",
    "resolve_scenario": "selfrepair.team.scenario",
    "team_row": "selfrepair.team.metrics",
    # errors
    "SelfRepairError": "selfrepair.errors",
    "InputError": "selfrepair.errors",
    "ConfigError": "selfrepair.errors",
    "LimitError": "selfrepair.errors",
    "ProblemError": "selfrepair.errors",
    "TableError": "selfrepair.errors",
    "TraceError": "selfrepair.errors",
}
"""Each public name and the module it is defined in."""

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
    "StepSource",
    "StrategyName",
    "StrategyOptions",
    "TableError",
    "TeamOptions",
    "TeamResult",
    "TeamScenario",
    "TraceError",
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
"""The public names: ``__version__`` and every key of :data:`_HOMES` (a test checks both agree)."""


def __getattr__(name: str) -> Any:
    """Import a public name from its home on first use and keep it (PEP 562)."""
    if name == "__version__":
        from importlib.metadata import PackageNotFoundError, version

        try:
            found: Any = version("selfrepair")
        except PackageNotFoundError:  # pragma: no cover - a source tree without install
            found = "0.0.0"
    elif name in _HOMES:
        import importlib

        found = getattr(importlib.import_module(_HOMES[name]), name)
    else:
        raise AttributeError(f"module 'selfrepair' has no attribute {name!r}")
    globals()[name] = found
    return found


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
