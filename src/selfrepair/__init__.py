"""selfrepair: self-repairing robot plans.

A robot executes a plan; when an actuator fault makes some actions unavailable, a replacement
system swaps each faulty action for a precomputed sub-plan with the same start and end state,
falling back to replanning only when no replacement fits. See the README for the big picture.

The public API is the handful of names a user needs, all reachable from the package itself::

    import selfrepair as sr

    maze = sr.load_bundled("narrow-long")
    route = sr.bundled_routes("narrow-long")[0]
    robot = sr.get_domain("four-wheel")
    spec = sr.MissionSpec(maze, route.start, route.goal, domain=robot,
                          schedule=sr.FaultSchedule.permanent(robot.parse_faults("FL:F")))
    print(sr.mission_row(sr.run_mission(spec))["status"])

The names are imported on first use of any of them (from :mod:`selfrepair._api`, which says
which module each comes from), so ``import selfrepair`` alone stays cheap and ``selfrepair --help``
starts fast; the modules themselves remain importable as before. ``selfrepair.__version__`` is
looked up on first use too (reading the installed metadata costs more than the rest of a quick
command's start-up).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the same names, for type checkers and IDEs (never run)
    from selfrepair.errors import InputError, ProblemError, SelfRepairError
    from selfrepair.execution.executor import run_mission
    from selfrepair.execution.faults import FaultEvent, FaultSchedule
    from selfrepair.execution.metrics import mission_row
    from selfrepair.execution.result import MissionResult, MissionSpec
    from selfrepair.execution.trace import read_trace, replay, write_trace
    from selfrepair.geometry import Heading, Pose, parse_pose
    from selfrepair.repair.strategies import StrategyName, StrategyOptions, register_strategy
    from selfrepair.robots.domain import Domain, check_domain
    from selfrepair.robots.registry import domain_names, get_domain, load_plugin, register_domain
    from selfrepair.search.lattice import plan
    from selfrepair.search.problem import PlanningProblem
    from selfrepair.tables.fileformat import resolve_table
    from selfrepair.tables.generate import generate_table
    from selfrepair.tables.model import GenerateOptions, ReplacementTable
    from selfrepair.team.engine import run_team
    from selfrepair.team.model import TeamScenario
    from selfrepair.team.result import TeamOptions
    from selfrepair.world.bundled import bundled_routes, load_bundled
    from selfrepair.world.loading import load_maze
    from selfrepair.world.maze import Maze

__all__ = [
    "Domain",
    "FaultEvent",
    "FaultSchedule",
    "GenerateOptions",
    "Heading",
    "InputError",
    "Maze",
    "MissionResult",
    "MissionSpec",
    "PlanningProblem",
    "Pose",
    "ProblemError",
    "ReplacementTable",
    "SelfRepairError",
    "StrategyName",
    "StrategyOptions",
    "TeamOptions",
    "TeamScenario",
    "__version__",
    "bundled_routes",
    "check_domain",
    "domain_names",
    "generate_table",
    "get_domain",
    "load_bundled",
    "load_maze",
    "load_plugin",
    "mission_row",
    "parse_pose",
    "plan",
    "read_trace",
    "register_domain",
    "register_strategy",
    "replay",
    "resolve_table",
    "run_mission",
    "run_team",
    "write_trace",
]
"""The public names: those of :mod:`selfrepair._api`, and the version."""


def __getattr__(name: str) -> Any:
    """A public name, from :mod:`selfrepair._api` on first use (then a plain attribute)."""
    if name == "__version__":
        from selfrepair._version import package_version

        globals()["__version__"] = package_version()
        return package_version()
    if name not in __all__:
        raise AttributeError(f"module 'selfrepair' has no attribute {name!r}")
    from selfrepair import _api

    value = getattr(_api, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
