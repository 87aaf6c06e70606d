"""The public API's names, imported by plain import statements (which the import contracts see).

``import selfrepair as sr`` gives these names through :func:`selfrepair.__getattr__`, which
imports this module on the first use of any of them, so ``import selfrepair`` alone (and
``selfrepair --help``) imports none of the package. This module sits beside the command line at the
top of the layers contract: it may import every folder, and no folder may import it.
"""

from __future__ import annotations

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
