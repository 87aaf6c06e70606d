"""The exact cost of an action and of a plan on the pose lattice (the formula is in
:mod:`selfrepair.search.lattice`): what the planner minimises, re-computed from the plan."""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction

from selfrepair.errors import ProblemError
from selfrepair.geometry import Pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.problem import PlanningProblem, StepTerm
from selfrepair.world.maze import Maze, clearance_map

__all__ = ["action_cost", "plan_cost"]


def action_cost(
    maze: Maze,
    pose: Pose,
    action: object,
    *,
    clearance_weight: Fraction,
    clearance_radius: int,
    domain: SomeDomain = FOUR_WHEEL,
) -> Fraction:
    """The exact cost of ``action`` at ``pose`` (see the module docstring for the formula), for
    the four-wheel robot unless ``domain`` is given.

    Does not check that the footprint cells are free; :func:`plan_cost` does.
    """
    cost = Fraction(domain.duration(action))
    if clearance_weight:
        clearance = clearance_map(maze)
        penalty = sum(
            max(0, clearance_radius - int(clearance[y, x]))
            if maze.in_bounds(x, y)
            else clearance_radius
            for x, y in domain.footprint(pose, action)
        )
        cost += clearance_weight * penalty
    return cost


def plan_cost(problem: PlanningProblem, actions: Sequence[object]) -> Fraction:
    """Re-simulate ``actions`` from ``problem.start`` and return their total cost.

    Raises :class:`ProblemError` if an action is unavailable under ``problem.faults``, sweeps a wall
    or leaves the grid, or if the plan does not end at the goal.
    """
    domain = problem.domain
    pose = problem.start
    total = Fraction(0)
    for index, action in enumerate(actions):
        name = domain.format_action(action)
        if not domain.available(action, problem.faults):
            raise ProblemError(f"action {index} ({name}) is not available under the faults")
        end, swept, _ = domain.step(pose, action)
        if not problem.maze.all_free(swept):
            raise ProblemError(
                f"action {index} ({name}) at {pose} sweeps a wall or leaves the grid"
            )
        total += action_cost(
            problem.maze,
            pose,
            action,
            clearance_weight=Fraction(problem.clearance_weight),
            clearance_radius=problem.clearance_radius,
            domain=domain,
        )
        total += _term_cost(problem.step_term, pose, action, index, name)
        pose = end
    if not problem.at_goal(pose):
        raise ProblemError(f"the plan ends at {pose}, not at the goal")
    return total


def _term_cost(
    term: StepTerm | None, pose: Pose, action: object, index: int, name: str
) -> Fraction:
    """The step term's cost of ``action`` at ``pose`` (0 without a term); a step a hard term
    forbids, or an action it has no count for, raises :class:`ProblemError`."""
    if term is None:
        return Fraction(0)
    if action not in term.actions:
        raise ProblemError(f"action {index} ({name}) is not one the step term was made for")
    count = int(term.dense_counts()[pose.y, pose.x, pose.heading, term.actions.index(action)])
    if term.penalty is None:
        if count:
            raise ProblemError(f"action {index} ({name}) at {pose} is forbidden by the hard term")
        return Fraction(0)
    return term.penalty * count
