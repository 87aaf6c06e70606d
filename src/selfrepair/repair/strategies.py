"""Repair strategies: what the executor does when the next action is unavailable.

Each strategy is a plain function ``(RepairRequest) -> Repair`` in the registry :data:`STRATEGIES`:

``replan``
    The original baseline: plan from scratch from the current pose with the known faults.
``replacement``
    Look the faulty action up in the replacement table and take the first valid candidate (in the
    chosen recursion mode); fall back to ``replan`` when none is valid.
``lookahead``
    Replace a window of the plan, the faulty action and up to ``window`` actions after it, by the
    cheapest sub-plan that reaches the pose at the end of the window, found by A* with the known
    faults and at most ``lookahead_expansions`` expansions; fall back to ``replacement``, then
    ``replan``. This is the original work's proposed extension ("replanning windows").

:class:`RepairRequest` and :class:`Repair` are immutable ``NamedTuple`` values rather than frozen
dataclasses: they are built on every repair, inside the measured latency, and a frozen dataclass
costs several times more to construct.

A :class:`Repair` says which queued actions to drop (``consumed``, counted from the faulty one) and
what to run instead (``actions``); every action in it is available under the known faults, so the
repaired queue starts with an executable action.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import NamedTuple

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.replacement import (
    DEFAULT_MAX_DEPTH,
    RECURSION_MODES,
    find_replacement,
    flat_replacement_on_grid,
    free_cell_set,
)
from selfrepair.robots import four_wheel
from selfrepair.robots.four_wheel import FOUR_WHEEL, Action, FaultSet
from selfrepair.search.astar import PlanStatus
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem, PlanResult
from selfrepair.tables.fileformat import resolve_table
from selfrepair.tables.model import ReplacementTable
from selfrepair.world.maze import Maze

__all__ = [
    "STRATEGIES",
    "PlannerSettings",
    "Repair",
    "RepairRequest",
    "StrategyOptions",
    "get_strategy",
]


@dataclass(frozen=True, slots=True)
class PlannerSettings:
    """How every planner call of a mission is made (initial plan, replans, lookahead windows)."""

    heuristic: str = "grid-distance"
    backend: str = "auto"
    clearance_weight: Fraction = Fraction(0)
    clearance_radius: int = 2
    max_expansions: int | None = None


@dataclass(frozen=True, slots=True)
class StrategyOptions:
    """Options of the strategies.

    ``table`` is a bundled table name, a table file path or a :class:`ReplacementTable`;
    ``recursion`` a name in :data:`selfrepair.repair.replacement.RECURSION_MODES`; ``max_depth`` the depth
    bound of ``guarded`` mode; ``window`` the lookahead window (actions after the faulty one);
    ``lookahead_expansions`` the budget of one window search.
    """

    table: str | ReplacementTable = "handwritten"
    recursion: str = "flat"
    max_depth: int = DEFAULT_MAX_DEPTH
    window: int = 3
    lookahead_expansions: int = 20_000

    def __post_init__(self) -> None:
        if self.recursion not in RECURSION_MODES:
            raise ProblemError(
                f"unknown recursion mode {self.recursion!r}; expected one of "
                f"{', '.join(RECURSION_MODES)}"
            )
        if self.window < 0 or self.max_depth < 0 or self.lookahead_expansions < 1:
            raise ProblemError("window and max_depth must be >= 0 and lookahead_expansions >= 1")

    @property
    def table_label(self) -> str:
        """How the table is named in traces and result rows."""
        if isinstance(self.table, ReplacementTable):
            source = self.table.source
            if source.startswith("<bundled:") and source.endswith(">"):
                return source[len("<bundled:") : -1]  # a name resolve_table understands
            return source
        return str(self.table)

    def resolved_table(self) -> ReplacementTable:
        """The table itself (loaded once per process for names and paths)."""
        if isinstance(self.table, ReplacementTable):
            return self.table
        return _cached_table(str(self.table))


_TABLES: dict[str, ReplacementTable] = {}


def _cached_table(spec: str) -> ReplacementTable:
    table = _TABLES.get(spec)
    if table is None:
        table = resolve_table(spec)
        _TABLES[spec] = table
    return table


class RepairRequest(NamedTuple):
    """Everything a strategy may look at: the world as the executor believes it to be.

    ``queue`` holds the remaining actions, the faulty one first (a read-only sequence; the
    executor passes a view, not a copy, so that building a request costs O(1)).
    """

    maze: Maze
    pose: Pose
    queue: Sequence[Action]
    known: FaultSet
    goal: Cell
    goal_heading: Heading | None
    options: StrategyOptions
    planner: PlannerSettings
    table: ReplacementTable | None = None


class Repair(NamedTuple):
    """A strategy's answer.

    ``status``: ``"repaired"``, ``"stuck"`` (replan found no plan) or ``"budget_exhausted"``
    (replan hit its budget). ``source`` is the step source of the new actions (``"replacement"``,
    ``"lookahead"`` or ``"replan"``). ``attempts`` lists the strategies tried, in order.
    ``replans`` counts full replans (0 or 1); ``candidate_length``/``depth`` describe a table
    replacement; ``examined`` counts table candidates looked at; ``expansions`` the search nodes
    expanded by lookahead and replan. ``candidate_index`` is the position of the candidate a
    replacement used in the list the table gives for the faulty action and the known faults
    (``None`` for lookahead and replan).
    """

    status: str
    source: str
    actions: tuple[Action, ...] = ()
    consumed: int = 0
    replans: int = 0
    candidate_length: int | None = None
    depth: int | None = None
    examined: int = 0
    expansions: int = 0
    attempts: tuple[str, ...] = ()
    candidate_index: int | None = None


Strategy = Callable[[RepairRequest], Repair]


def _plan_to(
    request: RepairRequest, goal: Cell, heading: Heading | None, max_expansions: int | None
) -> PlanResult:
    """Plan from the robot's pose with the known faults and the mission's planner settings."""
    settings = request.planner
    problem = PlanningProblem(
        request.maze,
        request.pose,
        goal,
        heading,
        request.known,
        settings.clearance_weight,
        settings.clearance_radius,
    )
    return plan(
        problem,
        heuristic=settings.heuristic,
        max_expansions=max_expansions,
        backend=settings.backend,
    )


def replan(request: RepairRequest) -> Repair:
    """Plan from scratch from the current pose with the known faults."""
    result = _plan_to(request, request.goal, request.goal_heading, request.planner.max_expansions)
    status = {
        PlanStatus.SOLVED: "repaired",
        PlanStatus.UNSOLVABLE: "stuck",
        PlanStatus.BUDGET_EXHAUSTED: "budget_exhausted",
    }[result.status]
    return Repair(
        status,
        "replan",
        result.actions,
        len(request.queue),
        replans=1,
        expansions=result.expansions,
        attempts=("replan",),
    )


def replacement(request: RepairRequest) -> Repair:
    """The first valid table candidate for the faulty action, else :func:`replan`."""
    table = request.table if request.table is not None else request.options.resolved_table()
    if request.options.recursion == "flat":
        found = flat_replacement_on_grid(
            FOUR_WHEEL,
            table,
            request.queue[0],
            request.pose,
            request.known,
            free_cell_set(request.maze),
        )
    else:
        found = find_replacement(
            FOUR_WHEEL,
            table,
            request.queue[0],
            request.pose,
            request.known,
            request.maze.all_free,
            mode=request.options.recursion,
            max_depth=request.options.max_depth,
        )
    if found is not None:
        return Repair(
            "repaired",
            "replacement",
            found.actions,
            1,
            candidate_length=len(found.actions),
            depth=found.depth,
            examined=found.examined,
            attempts=("replacement",),
            candidate_index=found.index,
        )
    fallback = replan(request)
    return _chain(fallback, ("replacement",), examined=_examined_all(table, request))


def _examined_all(table: ReplacementTable, request: RepairRequest) -> int:
    return len(table.candidates(request.queue[0], request.known))


def lookahead(request: RepairRequest) -> Repair:
    """Replace the window (faulty action + up to ``window`` more) by the cheapest sub-plan to the
    window's end pose; else :func:`replacement` (which falls back to :func:`replan`)."""
    window = request.queue[: request.options.window + 1]
    end = request.pose
    for action in window:
        end = four_wheel.step(end, action)[0]
    result = _plan_to(request, end.cell, end.heading, request.options.lookahead_expansions)
    if result.status is PlanStatus.SOLVED:
        return Repair(
            "repaired",
            "lookahead",
            result.actions,
            len(window),
            expansions=result.expansions,
            attempts=("lookahead",),
        )
    fallback = replacement(request)
    return _chain(fallback, ("lookahead",), expansions=result.expansions)


def _chain(
    repair: Repair, before: tuple[str, ...], *, examined: int = 0, expansions: int = 0
) -> Repair:
    """``repair`` with the strategies tried before it prepended and their work added."""
    return Repair(
        repair.status,
        repair.source,
        repair.actions,
        repair.consumed,
        repair.replans,
        repair.candidate_length,
        repair.depth,
        repair.examined + examined,
        repair.expansions + expansions,
        before + repair.attempts,
        repair.candidate_index,
    )


STRATEGIES: dict[str, Strategy] = {
    "replan": replan,
    "replacement": replacement,
    "lookahead": lookahead,
}
"""Repair strategies by name."""


def get_strategy(name: str) -> Strategy:
    """The strategy called ``name``; unknown names raise :class:`ProblemError`."""
    try:
        return STRATEGIES[name]
    except KeyError:
        raise ProblemError(
            f"unknown strategy {name!r}; expected one of {', '.join(STRATEGIES)}"
        ) from None
