"""The ``lpg-adapt`` strategy: repair the robot's plan with LPG-adapt, the AI-planning baseline.

On each faulty encounter the situation goes to LPG-adapt (Fox, Gerevini, Long, Serina 2006)
through :func:`selfrepair.baselines.lpg.lpg_adapt_repair`: the robot's current pose as the start,
the known faults, and the remaining plan (the request's queue, faulty action first) as the plan to
adapt, with the strategy options' time limit (``StrategyOptions.lpg_time_limit_s``) and seed
(``lpg_seed``). LPG's plan counts only after it re-simulates in the maze under the known faults
(every action available, no wall swept, the goal reached: ``lpg_adapt_repair`` checks it with the
world model before returning ``SOLVED``); it then replaces the whole queue, with step source
``plan-repair``.

Anything else (LPG ran out of time, found no plan, crashed, or cannot take the maze) is recorded,
not raised: the strategy falls back to :func:`~selfrepair.repair.strategies.replan` (A* with the
known faults), and the repair's ``attempts`` say what happened, e.g.
``("lpg-adapt:timeout", "replan")``; the metrics count such repairs as ``fallbacks``. A goal that
the known faults make unreachable therefore ends as the replan's ``stuck``.

LPG-td 1.4 takes at most :data:`~selfrepair.baselines.lpg.LPG_MAX_OBJECTS` objects (free cells
plus 11 constants). The strategy counts them once per mission: on a maze with more free cells
(``wide-long``) every repair falls back at once, as ``lpg-adapt:error``, without exporting the
maze. LPG looks for any valid plan, not a cheapest one, and knows nothing of the clearance term
(the export has none): the executed plan is costed by the metrics like every other strategy's.

In a changing world (:mod:`selfrepair.world.events`) the strategy sees cells
(``sees_cells``): the stepper asks its ``repair`` when the next action sweeps a cell the robot
believes blocked too, and every LPG problem is posed on the maze with the believed-blocked cells
as walls (:func:`~selfrepair.world.maze.believed_maze`, the robot's own cell left free), so
LPG-adapt is told the changed cells as a changed initial state, and its plan is checked on that
map (as a replan's is planned on it).

The strategy plans for the four-wheel robot only (the PDDL export's robot) and needs the ``pddl``
extra; starting it without either raises :class:`~selfrepair.errors.ProblemError` with a
one-line reason.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, cast

from selfrepair.baselines.lpg import (
    LPG_MAX_OBJECTS,
    MAX_LPG_TIME_LIMIT,
    LpgStatus,
    lpg_adapt_repair,
    lpg_available,
)
from selfrepair.baselines.pddlschema import HEADING_NAMES, MODE_NAMES, WHEEL_NAMES
from selfrepair.errors import ProblemError
from selfrepair.repair.strategies import (
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    RepairSource,
    RepairStatus,
    StrategyName,
    register_strategy,
    replan,
)
from selfrepair.robots.four_wheel import FOUR_WHEEL, Action
from selfrepair.search.problem import PlanningProblem
from selfrepair.world.maze import Maze, believed_maze

__all__ = ["LPG_ADAPT", "LpgAdaptRepairer", "check_lpg_adapt", "lpg_objects", "start_lpg_adapt"]

LPG_ADAPT = StrategyName.LPG_ADAPT
"""The strategy's name in the registry and in ``Repair.attempts``."""

_CONSTANTS = len(HEADING_NAMES) + len(WHEEL_NAMES) + len(MODE_NAMES)


def lpg_objects(maze: Maze) -> int:
    """How many PDDL objects a problem on ``maze`` has: one per free cell, plus the constants."""
    return len(maze.free_cells()) + _CONSTANTS


@dataclass(frozen=True, slots=True)
class LpgAdaptRepairer:
    """The strategy started for one mission. ``fits`` is false when the maze has more objects
    than LPG takes (every repair then falls back without calling LPG)."""

    context: MissionContext
    maze: Maze
    fits: bool
    sees_cells: ClassVar[bool] = True
    """Asked for blocked actions too; its problems carry the believed-blocked cells."""

    def repair(self, request: RepairRequest) -> Repair:
        """LPG-adapt's repair of the remaining plan, else a replan (see the module docstring)."""
        context = self.context
        if not self.fits:
            return _fall_back(context, request, LpgStatus.ERROR)
        blocked = context.belief.blocked - {request.pose.cell}
        problem = PlanningProblem(
            believed_maze(self.maze, blocked) if blocked else self.maze,
            request.pose,
            context.goal,
            context.goal_heading,
            request.known,
            domain=FOUR_WHEEL,
        )
        options = context.options
        result = lpg_adapt_repair(
            problem,
            cast("tuple[Action, ...]", tuple(request.queue)),  # a four-wheel robot's queue
            time_limit_s=options.lpg_time_limit_s,
            seed=options.lpg_seed,
        )
        if result.status is not LpgStatus.SOLVED:
            return _fall_back(context, request, result.status)
        return Repair(
            RepairStatus.REPAIRED,
            RepairSource.PLAN_REPAIR,
            result.actions,
            len(request.queue),
            attempts=(LPG_ADAPT,),
        )


def _fall_back(context: MissionContext, request: RepairRequest, status: LpgStatus) -> Repair:
    """A replan, with LPG's failed attempt (and why it failed) recorded before it."""
    fallback = replan(context, request)
    return fallback._replace(attempts=(f"{LPG_ADAPT}:{status.value}", *fallback.attempts))


def start_lpg_adapt(context: MissionContext) -> Repairer:
    """The strategy factory. Raises :class:`ProblemError` when the ``pddl`` extra is missing, the
    robot is not the four-wheel one, the context carries no maze, or the time limit is above
    :data:`~selfrepair.baselines.lpg.MAX_LPG_TIME_LIMIT`."""
    check_lpg_adapt(context.domain.name)
    maze = context.world
    if not isinstance(maze, Maze):
        raise ProblemError("the lpg-adapt strategy needs the mission's maze (MissionContext.world)")
    limit = context.options.lpg_time_limit_s
    if limit > MAX_LPG_TIME_LIMIT:
        raise ProblemError(
            f"lpg_time_limit_s must be at most {MAX_LPG_TIME_LIMIT:g} seconds, got {limit:g}"
        )
    return LpgAdaptRepairer(context, maze, lpg_objects(maze) <= LPG_MAX_OBJECTS)


def check_lpg_adapt(domain: str) -> None:
    """Raise :class:`ProblemError` (one line) when the strategy cannot run for robot ``domain``
    here: it needs the ``pddl`` extra and the four-wheel robot."""
    if domain != FOUR_WHEEL.name:
        raise ProblemError(
            f"the lpg-adapt strategy plans for the {FOUR_WHEEL.name} robot only (the PDDL "
            f"export's robot), not {domain!r}"
        )
    if not lpg_available():
        raise ProblemError(
            "the lpg-adapt strategy needs the pddl extra (unified-planning and up-lpg): "
            "pip install 'selfrepair[pddl]'"
        )


register_strategy(LPG_ADAPT, start_lpg_adapt)
