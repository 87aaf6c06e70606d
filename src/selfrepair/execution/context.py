"""A mission's context: what its strategy is started on, made from its :class:`MissionSpec`.

:func:`mission_context` builds the
:class:`~selfrepair.repair.strategies.MissionContext` of a mission: the planner on the map the
robot believes (the maze less the cells it has seen blocked; with a planning objective, the
tolerant objective before any fault is known), the free-cell test over the map's buffer
(:func:`free_test`) and the step cost with the mission's clearance term.
:func:`start_repairer` starts the mission's strategy on it. The executor
(:func:`selfrepair.execution.executor.run_mission`) uses both once per mission, a team robot once
per drive (:mod:`selfrepair.team.driving`) and the Gymnasium environment once per episode.
"""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction

from selfrepair.execution.faults import Detection
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.repair.replacement import FreeTest, table_reach
from selfrepair.repair.strategies import Belief, MissionContext, Repairer, get_strategy
from selfrepair.repair.tolerance import PlanObjective, fault_model
from selfrepair.repair.tolerance_masks import tolerance_term
from selfrepair.search.astar import PlanResult, PlanStatus
from selfrepair.search.lattice import action_cost, cost_scale, plan, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.search.term import StepTerm
from selfrepair.tables.model import SomeTable
from selfrepair.world.maze import believed_maze

__all__ = ["free_test", "mission_context", "start_repairer"]


def mission_context(spec: MissionSpec, table: SomeTable | None) -> MissionContext:
    """The :class:`~selfrepair.repair.strategies.MissionContext` of ``spec``: its planner, free
    test and step cost on its map, with ``table`` (``None`` for strategies without one)."""
    settings = spec.planner
    weight = Fraction(settings.clearance_weight)
    maze, domain, radius = spec.maze, spec.domain, settings.clearance_radius
    heuristic, backend = settings.heuristic, settings.backend

    objective = spec.objective
    belief = Belief()

    def plan_to(
        start: Pose,
        goal: Cell,
        heading: Heading | None,
        known: frozenset[object],
        budget: int | None,
    ) -> PlanResult:
        blocked = belief.blocked
        if blocked and goal in blocked and goal != start.cell:  # no way in while it is blocked
            return PlanResult(PlanStatus.UNSOLVABLE, (), (), None, Fraction(0), 0, 0)
        world = believed_maze(maze, blocked - {start.cell}) if blocked else maze
        problem = PlanningProblem(world, start, goal, heading, known, weight, radius, domain)
        if objective is not None and not known:  # the tolerant objective: before any fault
            term = _objective_term(spec, objective, table)
            found = plan(
                replace(problem, step_term=term), heuristic=heuristic, max_expansions=budget,
                backend=backend,
            )  # fmt: skip
            if found.status is not PlanStatus.UNSOLVABLE or objective.penalty is not None:
                return found  # a hard objective without a tolerant plan: the plain optimum
        return plan(problem, heuristic=heuristic, max_expansions=budget, backend=backend)

    def cost(pose: Pose, action: object) -> Fraction:
        return action_cost(
            maze, pose, action, clearance_weight=weight, clearance_radius=radius, domain=domain
        )

    margin = max(2, table_reach(table)) if table is not None else 2
    grid = maze.free_grid(margin)
    return MissionContext(
        domain=domain,
        goal=spec.goal,
        goal_heading=spec.goal_heading,
        options=spec.options,
        table=table,
        plan=plan_to,
        replan_budget=settings.max_expansions,
        free=free_test(grid),
        grid=grid,
        cost=cost,
        world=spec.maze,
        cost_scale=cost_scale(spec.domain, weight),
        start=spec.start,
        clearance_weight=weight,
        clearance_radius=radius,
        backend=backend,
        belief=belief,
        behaviour=spec.behaviour,
        observers=spec.observers if spec.schedule.detection is Detection.HIDDEN else (),
    )


def start_repairer(spec: MissionSpec, context: MissionContext) -> Repairer:
    """The repairer of ``spec``'s strategy started for a mission (or a team robot's drive) on
    ``context``; in a changing world a strategy that repairs blocked actions itself prepares for
    them (``expect_blocked``) before the clock runs."""
    repairer = get_strategy(spec.strategy)(context)
    if spec.world and (expect := getattr(repairer, "expect_blocked", None)) is not None:
        expect()
    return repairer


def _objective_term(
    spec: MissionSpec, objective: PlanObjective, table: SomeTable | None
) -> StepTerm:
    """The tolerance term of ``objective`` for the mission's first plan: masks of the
    replacement strategy with the mission's table (or the one its options name) and recursion."""
    chosen = table if table is not None else spec.options.resolved_table()
    options = spec.options
    return tolerance_term(
        chosen,
        spec.maze.free_grid(max(2, table_reach(chosen))),
        planning_actions(spec.domain, frozenset()),
        fault_model(spec.domain, objective.k),
        penalty=objective.penalty,
        mode=options.recursion,
        max_depth=options.max_depth,
        max_patterns=options.max_lookup_patterns,
    )


def free_test(grid: FreeGrid) -> FreeTest:
    """``grid.all_free`` as one closure over the buffer (no method call per cell)."""
    data, stride, margin = grid.data, grid.stride, grid.margin
    width, height = grid.width, grid.height

    def all_free(cells: tuple[Cell, ...]) -> bool:
        for x, y in cells:
            if not (
                0 <= x < width and 0 <= y < height and data[(y + margin) * stride + x + margin]
            ):
                return False
        return True

    return all_free
