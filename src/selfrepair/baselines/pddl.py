"""The four-wheel robot's planning problem as PDDL: a domain file, a problem file, and plans.

Everything geometric comes from the one world model, :mod:`selfrepair.robots.four_wheel`
(:data:`~selfrepair.robots.four_wheel.ACTIONS`, :func:`~selfrepair.robots.four_wheel.step`,
:func:`~selfrepair.robots.four_wheel.motion`, :func:`~selfrepair.robots.four_wheel.duration`): the
exporter only asks it where an action ends, which cells it sweeps and how long it takes, and writes
the answers down as facts.

Encoding (PDDL with ``:strips :typing :action-costs``)
    State: ``(robot-at ?c - cell)`` and ``(facing ?h - heading)``. The cells are the free cells of
    the maze (objects ``cX_Y``); the headings, wheels and wheel commands are domain constants
    (``north east south west``, ``fl fr rl rr``, ``f s b``).

    Faults are facts, not deleted actions: the initial state holds ``(healthy W M)`` for every wheel
    ``W`` and command ``M`` that no known fault forbids, and each of the 81 actions is a schema
    named by its code (``ffff``, ``sfbb``, ...) whose precondition asks ``(healthy W M)`` for each
    of its four wheel commands. A plan made before a fault therefore still parses after it, and a
    validator names its first step that a fault makes inapplicable.

    Geometry is static facts, a predicate per motion (named as
    :attr:`~selfrepair.robots.four_wheel.Motion.name`), computed with ``step`` on every free pose:

    ===============  ===============  ============================================  ===========
    motion shape     parameters       static facts                                  effect
    ===============  ===============  ============================================  ===========
    stays, no turn   none             none (the 9 waits)                            cost only
    stays and turns  ``?h ?g``        ``(turn-left ?h ?g)``                         heading
    moves, no turn   ``?c ?h ?d``     ``(forward ?c ?h ?d)``                        cell
    moves and turns  ``?c ?h ?d ?g``  ``(arc-forward-left ?c ?h ?d)`` and           both
                                      ``(arc-forward-left-heading ?h ?g)``
    ===============  ===============  ============================================  ===========

    A fact with a cell is listed only when every cell the motion sweeps from that pose is free, so
    the footprint is checked where it is computed, once. "Stays" means that from every probe pose
    the motion ends on its start cell and sweeps nothing else, so a turn needs no cell parameter. A
    fact on headings alone is computed on probe poses: the world model acts the same in every cell.
    An arc's fact is split in two (no fact has four arguments) because LPG-td 1.4's plan adaptation
    crashes on four-argument facts.

    Cost: ``(increase (total-cost) N)`` with ``N`` the action's duration in thirds of a tick
    (:data:`~selfrepair.robots.four_wheel.TICKS_DENOMINATOR`), and ``(:metric minimize
    (total-cost))``; a plan's total cost is its duration times three.

Size
    Why this shape: a grounder instantiates each schema over the tuples its static fact allows. With
    a pose per object and a ``(move-ok ?from ?to)`` fact per motion, the 54 in-place turn actions
    and 9 waits would ground to ``63 * 4 * free cells`` instances; here to 54 * 4 and 9. Ground
    instances (``PddlTask.ground_actions``) and problem-file sizes on the bundled mazes, all 81
    schemas (the domain file is 24 kB whatever the maze):

    ============  ======  ==========  ============  ==============  =============  ==========
    maze          cells   free cells  static facts  ground actions  pose encoding  problem.pddl
    ============  ======  ==========  ============  ==============  =============  ==========
    narrow-short  15x15   97          408           2,145           26,364         13 kB
    wide-short    25x25   382         5,348         17,725          113,764        189 kB
    narrow-long   49x49   1,167       4,752         23,865          317,724        152 kB
    wide-long     61x61   2,721       47,496        149,841         835,308        1.7 MB
    ============  ======  ==========  ============  ==============  =============  ==========

    A planner call need not take all 81 schemas: under known faults only the fastest available
    action of each motion can be useful (the lattice planner's own pruning), so
    :func:`export_pddl` takes ``actions=``; ``action_costs=False`` leaves costs out for planners
    that cannot take numeric fluents (see :mod:`selfrepair.baselines.lpg`).
    :data:`MAX_PDDL_CELLS` bounds the maze (width times height) to keep files and grounding in
    reach of a planner; ``max_cells=`` raises it.

Plans
    One step per line, IPC style: ``(ffff c3_4 north c3_3)``, the parameters those of the schema,
    computed by stepping from the start pose, and a closing comment with the total cost.
    :func:`parse_pddl_plan` reads that form and LPG's ``0: (FFFF C3_4 NORTH C3_3) [1]`` back into
    actions, checking each step's parameters against the poses it re-simulates from the start.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from selfrepair.baselines.pddlschema import (
    HEADING_NAMES,
    MODE_NAMES,
    PROBE_POSES,
    REPRESENTATIVE,
    VARIABLE_TYPES,
    WHEEL_NAMES,
    Atom,
    PddlTask,
    cell_name,
    parameter_bindings,
    schema,
    static_predicates,
)
from selfrepair.errors import ProblemError
from selfrepair.geometry import Heading, Pose
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import ACTIONS, Action, Fault, Motion, Wheel
from selfrepair.search.problem import PlanningProblem, check_search_inputs

__all__ = ["MAX_PDDL_CELLS", "export_pddl"]

MAX_PDDL_CELLS = 4096
"""Largest maze (width times height, here 64 x 64) that :func:`export_pddl` accepts by default.
The bundled mazes are at most 61 x 61; a larger maze needs ``max_cells=`` (CLI: ``--max-cells``)."""


def _check_exportable(problem: PlanningProblem, max_cells: int) -> None:
    if problem.domain is not four_wheel.FOUR_WHEEL:
        raise ProblemError(
            f"the PDDL export knows the four-wheel robot only, got domain {problem.domain.name!r}"
        )
    maze = problem.maze
    if max_cells < 1:
        raise ProblemError(f"max_cells must be >= 1, got {max_cells}")
    if maze.width * maze.height > max_cells:
        raise ProblemError(
            f"the {maze.width}x{maze.height} maze has {maze.width * maze.height} cells, more than "
            f"the PDDL export limit of {max_cells}; raise it with max_cells= (CLI: --max-cells)"
        )
    # The planners' own start/goal checks (the backend argument is theirs and irrelevant here).
    check_search_inputs(
        maze,
        (("start", problem.start.cell), ("goal", problem.goal)),
        backend="python",
        max_expansions=None,
        time_limit=None,
    )
    if problem.clearance_weight:
        raise ProblemError(
            "the PDDL export encodes durations only; expected clearance_weight 0, "
            f"got {problem.clearance_weight}"
        )


def _motion_facts(problem: PlanningProblem, motion: Motion) -> tuple[list[Atom], int]:
    """The static facts of one motion on the maze, from the world model's ``step``, and the
    number of ground instances they allow.

    A fact with a cell argument is listed for every free pose from which the motion sweeps only
    free cells; a fact on headings alone is listed once per start heading (from probe poses).
    """
    action = REPRESENTATIVE[motion]
    facts: list[Atom] = []
    counts = []
    for name, args in static_predicates(motion):
        on_cells = any(VARIABLE_TYPES[v] == "cell" for v in args)
        starts = (
            [Pose(x, y, h) for x, y in problem.maze.free_cells() for h in Heading]
            if on_cells
            else PROBE_POSES  # headings only: the same in every cell, one probe per heading
        )
        found = []
        for pose in starts:
            end, swept, _ = four_wheel.step(pose, action)
            if on_cells and not problem.maze.all_free(swept):
                continue
            bindings = parameter_bindings(pose, end)
            found.append((name, *(bindings[v] for v in args)))
        facts += found
        counts.append(len(found))
    return facts, counts[0] if counts else 1  # the first fact pins a step down; a wait: once


def export_pddl(
    problem: PlanningProblem,
    *,
    name: str = "",
    actions: Iterable[Action] = ACTIONS,
    action_costs: bool = True,
    max_cells: int = MAX_PDDL_CELLS,
) -> PddlTask:
    """``problem`` (maze, start pose, goal cell and optional heading, known faults) in PDDL terms.

    ``actions`` chooses the schemas (default: all 81, in :data:`ACTIONS` order); a planner call
    may pass fewer, e.g. only the fastest available action of each motion. ``action_costs=False``
    leaves out costs and the metric (for planners that cannot take numeric fluents).

    Raises :class:`ProblemError` for another robot than the four-wheel one, a maze of more than
    ``max_cells`` cells (width times height, see :data:`MAX_PDDL_CELLS`), a start or goal outside
    the maze or in a wall, a non-zero clearance weight (the encoding's cost is duration only), or
    no action.
    """
    _check_exportable(problem, max_cells)
    chosen = set(actions)
    schemas = tuple(schema(a) for a in ACTIONS if a in chosen)
    if not schemas:
        raise ProblemError("expected at least one action to export")
    facts = {m: _motion_facts(problem, m) for m in four_wheel.MOTIONS}
    static = [f for fs, _ in facts.values() for f in fs]
    ground = sum(facts[four_wheel.motion(s.action)][1] for s in schemas)
    healthy = [
        ("healthy", WHEEL_NAMES[w], MODE_NAMES[m])
        for w in Wheel
        for m in MODE_NAMES
        if Fault(w, m) not in problem.faults
    ]
    start = problem.start
    init = [("robot-at", cell_name(start.cell)), ("facing", HEADING_NAMES[start.heading])]
    goal: list[Atom] = [("robot-at", cell_name(problem.goal))]
    if problem.goal_heading is not None:
        goal.append(("facing", HEADING_NAMES[problem.goal_heading]))
    maze = problem.maze
    heading = "" if problem.goal_heading is None else f",{problem.goal_heading.name}"
    comment = (
        f"{maze.width}x{maze.height} maze {maze.name or '(unnamed)'}: start {start}, goal "
        f"{problem.goal[0]},{problem.goal[1]}{heading}, known faults: "
        f"{four_wheel.format_faults(problem.faults) or 'none'}"
    )
    return PddlTask(
        name=_pddl_name(name or maze.name or "maze"),
        comment=comment,
        schemas=schemas,
        cells=tuple(cell_name(c) for c in maze.free_cells()),
        init=(*init, *healthy, *static),
        goal=tuple(goal),
        action_costs=action_costs,
        static_facts=len(static),
        ground_actions=ground,
    )


def _pddl_name(text: str) -> str:
    """A PDDL name from free text: letters, digits and ``-``, starting with a letter."""
    cleaned = re.sub(r"[^a-z0-9-]+", "-", text.lower()).strip("-")
    return cleaned if cleaned[:1].isalpha() else f"p-{cleaned}"
