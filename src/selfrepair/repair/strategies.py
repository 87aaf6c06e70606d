"""Repair strategies: what the executor does when the next action is unavailable.

A strategy has a lifecycle. At the start of a mission the executor calls its factory with a
:class:`MissionContext` (the robot, the goal, the table, and the world as functions: a planner, a
free-cell test, an edge cost), and gets a :class:`Repairer`; then, each time the next action is
faulty, it calls ``repairer.repair(request)`` with a :class:`RepairRequest` (the pose, the queued
actions and the known faults) and splices the :class:`Repair` into its queue. A repairer may keep
state between repairs (an incremental planner keeps its search); the built-in ``replacement``
keeps the mission's compiled look-ups at hand (:class:`ReplacementRepairer`), the others keep
nothing.

Factories live in the registry :data:`STRATEGIES` (:func:`register_strategy` adds one,
:func:`get_strategy` looks one up). The built-in strategies (:class:`StrategyName`):

``replan``
    The original baseline: plan from scratch from the current pose with the known faults.
``replacement``
    Look the faulty action up in the replacement table and take the first valid candidate (in the
    chosen recursion mode); fall back to ``replan`` when none is valid. The look-up goes through
    the compiled look-ups of :mod:`selfrepair.repair.lookups` (a warm hit is one integer-keyed
    dictionary look-up; same answers as the reference search). With ``StrategyOptions.rewrite``
    the repairer, once a fault is known, also walks the rest of the plan and substitutes every
    faulty action that has a valid replacement at its predicted pose, so later encounters never
    reach the repairer (see :class:`ReplacementRepairer`).
``lookahead``
    Replace a window of the plan, the faulty action and up to ``window`` actions after it, by the
    cheapest sub-plan that reaches the pose at the end of the window, found by A* with the known
    faults and at most ``lookahead_expansions`` expansions; fall back to ``replacement``, then
    ``replan``. This is the original work's proposed extension ("replanning windows").

Two baselines from neighbouring fields are registered by name and built elsewhere (imported on
first use, see :data:`_BUILT_ELSEWHERE`): ``dstar-lite``, incremental replanning
(:mod:`selfrepair.repair.dstar_lite`), and ``lpg-adapt``, plan repair with LPG-adapt
(:mod:`selfrepair.baselines.adapt`, needs the ``pddl`` extra).

This module is domain-generic and knows no maze: everything about the world comes in through the
context as values and functions, so the same strategies run any robot on any map.

:class:`RepairRequest` and :class:`Repair` are immutable ``NamedTuple`` values rather than frozen
dataclasses: they are built on every repair, inside the measured latency, and a frozen dataclass
costs several times more to construct. A :class:`Repair` says which queued actions to drop
(``consumed``, counted from the faulty one) and what to run instead (``actions``); every action in
it is available under the known faults, so the repaired queue starts with an executable action.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction
from itertools import chain
from typing import Any, NamedTuple, Protocol

from selfrepair.errors import ProblemError, choice
from selfrepair.geometry import Cell, FreeGrid, Heading, Pose
from selfrepair.limits import MAX_LOOKUP_PATTERNS
from selfrepair.repair.lookups import (
    MISSING,
    FaultLookups,
    GridLookups,
    Missing,
    action_index,
    compiled_replacement,
    fault_lookups,
    grid_lookups,
    occupancy_rows,
)
from selfrepair.repair.replacement import (
    DEFAULT_MAX_DEPTH,
    DEFERRING,
    FreeTest,
    RecursionMode,
    Replacement,
)
from selfrepair.robots.domain import Domain, run_open
from selfrepair.search.astar import PlanResult
from selfrepair.status import REPAIR_OF_PLAN, PlanStatus, RepairStatus
from selfrepair.tables.fileformat import resolve_table
from selfrepair.tables.model import ReplacementTable

__all__ = [
    "STRATEGIES",
    "DeferringRepairer",
    "FunctionRepairer",
    "MissionContext",
    "PlanFn",
    "Repair",
    "RepairRequest",
    "RepairSource",
    "RepairStatus",
    "Repairer",
    "ReplacementRepairer",
    "StrategyFactory",
    "StrategyName",
    "StrategyOptions",
    "get_strategy",
    "register_strategy",
    "strategy_names",
    "uses_table",
]


class StrategyName(StrEnum):
    """The built-in strategies (the registry may hold more)."""

    REPLAN = "replan"
    REPLACEMENT = "replacement"
    LOOKAHEAD = "lookahead"


class RepairSource(StrEnum):
    """Where the actions of a repair came from."""

    REPLACEMENT = "replacement"
    LOOKAHEAD = "lookahead"
    REPLAN = "replan"
    PLAN_REPAIR = "plan-repair"


@dataclass(frozen=True, slots=True)
class StrategyOptions:
    """Options of the strategies.

    ``table`` is a bundled table name, a table file path or a :class:`ReplacementTable`;
    ``recursion`` a :class:`~selfrepair.repair.replacement.RecursionMode` (or its name);
    ``max_depth`` the depth bound of ``guarded`` mode; ``window`` the lookahead window (actions
    after the faulty one); ``before`` the actions before the faulty one that a lookahead window
    may take in as well, when the fault is known that early (see :func:`lookahead`);
    ``lookahead_expansions`` the budget of one window search; ``rewrite``: the ``replacement``
    strategy substitutes, when it first meets a faulty action under the faults known, every
    faulty action of the rest of the plan that has a valid replacement at its predicted pose
    (whole-plan rewriting; other strategies ignore it; not in a deferring recursion mode such as
    ``primitive``, whose replacements may keep faulty actions for later);
    ``max_lookup_patterns`` the patterns one compiled look-up stores at most
    (:data:`~selfrepair.limits.MAX_LOOKUP_PATTERNS`). ``lpg_time_limit_s`` and ``lpg_seed`` are
    the wall-clock limit (seconds) and the seed of each LPG-adapt call of the ``lpg-adapt``
    strategy.
    """

    table: str | ReplacementTable = "handwritten"
    recursion: RecursionMode = RecursionMode.FLAT
    max_depth: int = DEFAULT_MAX_DEPTH
    window: int = 3
    lookahead_expansions: int = 20_000
    before: int = 0
    lpg_time_limit_s: float = 5.0
    lpg_seed: int = 0
    rewrite: bool = False
    max_lookup_patterns: int = MAX_LOOKUP_PATTERNS

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "recursion", choice(RecursionMode, self.recursion, "recursion mode")
        )
        if min(self.window, self.max_depth, self.before) < 0 or self.lookahead_expansions < 1:
            raise ProblemError(
                "window, before and max_depth must be >= 0 and lookahead_expansions >= 1"
            )
        if not self.lpg_time_limit_s > 0 or self.lpg_seed < 0:
            raise ProblemError("lpg_time_limit_s must be above 0 and lpg_seed >= 0")
        if self.max_lookup_patterns < 0:
            raise ProblemError(
                f"max_lookup_patterns must be at least 0, got {self.max_lookup_patterns}"
            )
        if not isinstance(self.rewrite, bool):
            raise ProblemError(f"rewrite must be True or False, got {self.rewrite!r}")
        if self.rewrite and self.recursion in DEFERRING:
            raise ProblemError(
                f"rewrite is not available in {self.recursion} recursion (its replacements may "
                "keep faulty actions for later)"
            )

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
        """The table itself (bundled tables and files are read once per process)."""
        if isinstance(self.table, ReplacementTable):
            return self.table
        return resolve_table(str(self.table))


PlanFn = Callable[[Pose, Cell, Heading | None, frozenset[Any], int | None], PlanResult]
"""``plan(start, goal, goal_heading, known_faults, max_expansions)``: an exact plan on the
mission's map with the mission's planner settings."""


@dataclass(frozen=True, slots=True)
class MissionContext:
    """What a strategy knows about its mission from the start.

    ``plan`` plans on the mission's map; ``replan_budget`` is the node budget of a full replan
    (``None``: unbounded). ``free`` tests a footprint, ``grid`` is the same map as a
    :class:`~selfrepair.geometry.FreeGrid` with a margin of at least the table's reach, and
    ``cost(pose, action)`` is the exact cost of one step (duration plus clearance term), and
    ``cost * cost_scale`` is an integer for every step. ``world``
    is the map itself (a :class:`selfrepair.world.maze.Maze`), typed loosely so that this layer does
    not depend on the world layer; only strategies that must read the map (e.g. to export it)
    use it. ``start`` is the mission's start pose (``None`` when unknown): a strategy that searches
    ahead of its first repair, as D* Lite does, starts there.
    """

    domain: Domain[Any, Any]
    goal: Cell
    goal_heading: Heading | None
    options: StrategyOptions
    table: ReplacementTable | None
    plan: PlanFn
    replan_budget: int | None
    free: FreeTest
    grid: FreeGrid
    cost: Callable[[Pose, Any], Fraction]
    world: object = None
    cost_scale: int = 1
    start: Pose | None = None

    def at_goal(self, pose: Pose) -> bool:
        """Whether ``pose`` satisfies the mission's goal."""
        return pose.cell == self.goal and (
            self.goal_heading is None or pose.heading == self.goal_heading
        )


class RepairRequest(NamedTuple):
    """What a repairer looks at: the world as the executor believes it to be.

    ``queue`` holds the remaining actions, the faulty one first (a read-only sequence; the
    executor passes a view, not a copy, so that building a request costs O(1)). It is empty for
    the defensive replan made when the queue runs out away from the goal. ``step`` is the number
    of steps executed so far.
    """

    pose: Pose
    queue: Sequence[Any]
    known: frozenset[Any]
    step: int = 0


class Repair(NamedTuple):
    """A strategy's answer.

    ``status`` says whether the queue was repaired; ``source`` is the step source of the new
    actions. ``attempts`` lists the strategies tried, in order. ``replans`` counts full replans;
    ``candidate_length``/``depth``/``candidate_index`` describe a table replacement (the index in
    the looked-up candidate list); ``examined`` counts table candidates looked at;
    ``expansions`` the search nodes expanded by planning. An attempt that gave up may say why
    after a colon: ``("lpg-adapt:timeout", "replan")`` means LPG-adapt ran out of time and the
    strategy fell back to replanning. ``rewritten`` counts the later queued actions a whole-plan
    rewrite substituted (their replacements are in ``actions``, which then runs up to the last
    substituted one, and ``consumed`` covers them); 0 for any other repair.
    """

    status: RepairStatus
    source: RepairSource
    actions: tuple[Any, ...] = ()
    consumed: int = 0
    replans: int = 0
    candidate_length: int | None = None
    depth: int | None = None
    examined: int = 0
    expansions: int = 0
    attempts: tuple[str, ...] = ()
    candidate_index: int | None = None
    rewritten: int = 0


class Repairer(Protocol):
    """A strategy started for one mission: answers repair requests, possibly keeping state.

    A repairer may also have an integer attribute ``horizon`` (0 when absent): then the executor
    asks it for a repair as soon as one of the next ``horizon`` queued actions after the first is
    faulty under the known faults, not only when the first one is (the first faulty action is then
    not at the front of ``RepairRequest.queue``; see :func:`lookahead`).
    """

    def repair(self, request: RepairRequest) -> Repair:
        """A repair for ``request`` (its first queued action is faulty)."""
        ...


StrategyFactory = Callable[[MissionContext], Repairer]
"""Starts a strategy for one mission."""


@dataclass(frozen=True, slots=True)
class FunctionRepairer:
    """A stateless strategy: a plain function of (context, request)."""

    context: MissionContext
    fn: Callable[[MissionContext, RepairRequest], Repair]
    horizon: int = 0

    def repair(self, request: RepairRequest) -> Repair:
        """``fn(context, request)``."""
        return self.fn(self.context, request)


def stateless(fn: Callable[[MissionContext, RepairRequest], Repair]) -> StrategyFactory:
    """The factory of a strategy that keeps no state between repairs."""

    def start(context: MissionContext) -> Repairer:
        return FunctionRepairer(context, fn)

    start.__doc__ = fn.__doc__
    return start


# --- the built-in strategies ----------------------------------------------------------------------


def replan(context: MissionContext, request: RepairRequest) -> Repair:
    """Plan from scratch from the current pose with the known faults."""
    result = context.plan(
        request.pose, context.goal, context.goal_heading, request.known, context.replan_budget
    )
    return Repair(
        REPAIR_OF_PLAN[result.status],
        RepairSource.REPLAN,
        result.actions,
        len(request.queue),
        replans=1,
        expansions=result.expansions,
        attempts=(StrategyName.REPLAN,),
    )


def _hit(found: Replacement) -> Repair:
    """The repair of a table hit. It does not depend on the pose, so the compiled look-ups store
    it and a warm hit returns it as it is."""
    return Repair(
        RepairStatus.REPAIRED,
        RepairSource.REPLACEMENT,
        found.actions,
        1,
        candidate_length=len(found.actions),
        depth=found.depth,
        examined=found.examined,
        attempts=(StrategyName.REPLACEMENT,),
        candidate_index=found.position,
    )


def _table(context: MissionContext) -> ReplacementTable:
    if context.table is None:
        raise ProblemError("the replacement strategy needs a table")
    return context.table


def _lookups(context: MissionContext, known: frozenset[Any]) -> FaultLookups[Repair]:
    options = context.options
    return fault_lookups(
        _table(context),
        known,
        mode=options.recursion,
        max_depth=options.max_depth,
        answer=_hit,
        max_patterns=options.max_lookup_patterns,
    )


def _miss(context: MissionContext, request: RepairRequest, action: Any) -> Repair:
    """No valid candidate: :func:`replan`, with the candidates looked at counted."""
    examined = len(_table(context).candidates(action, request.known))
    return _chain(replan(context, request), (StrategyName.REPLACEMENT,), examined=examined)


def replacement(context: MissionContext, request: RepairRequest) -> Repair:
    """The first valid table candidate for the faulty action, else :func:`replan` (the stateless
    form, for strategies that fall back to it; the ``replacement`` strategy itself is
    :class:`ReplacementRepairer`)."""
    action = request.queue[0]
    found = _lookups(context, request.known).get(action, request.pose, context.grid)
    return _miss(context, request, action) if found is None else found


class ReplacementRepairer:
    """The ``replacement`` strategy started for one mission.

    A hit reads the occupancy code of the pose from the mission's grid and looks the masked code
    up in the compiled map of the faulty action under the known faults (see
    :mod:`selfrepair.repair.lookups`); the stored :class:`Repair` is returned as it is. A pattern
    met for the first time runs the reference search once. With no valid candidate it replans.

    With ``options.rewrite`` a hit also walks the rest of the queue once, following the poses the
    plan predicts, and substitutes every faulty action that has a valid replacement there, up
    to the first faulty action without one: that one stays, and the robot replans when it meets
    it (as it would without rewriting), which drops everything after it anyway.
    Replacements end where the replaced action ends, so the predicted poses stay exact, and with
    permanent faults detected at once the robot executes the same steps as without rewriting,
    but meets one faulty action per fault set instead of one per occurrence. The executor still
    checks each next action against the faults known at that time (new faults trigger a new
    rewrite), and the simulator still holds the true faults and walls.

    State (per mission): the known faults of the last request and the compiled look-ups for them
    as read on the mission's grid (:class:`~selfrepair.repair.lookups.GridLookups`, shared with
    other missions on the same grid). Actions are tracked by slot ``4 * index + heading``;
    ``moves[slot]`` is the change of cell and the new heading of an action from a heading.
    """

    __slots__ = (
        "_context",
        "_faulty",
        "_index",
        "_known",
        "_last",
        "_moves",
        "_on_grid",
        "_quads",
        "_rewrite",
        "_size",
        "_slots",
    )

    def __init__(self, context: MissionContext) -> None:
        table = _table(context)
        if table.domain is not context.domain:
            raise ProblemError(
                f"table for domain {table.domain.name!r} used with domain {context.domain.name!r}"
            )
        self._context = context
        self._rewrite = context.options.rewrite
        self._index = action_index(context.domain)
        grid = context.grid
        self._size = (grid.width, grid.height)
        self._quads = self._index.quads
        self._moves = self._index.slot_moves
        self._known: frozenset[Any] | None = None
        self._last: tuple[Any, int] = (None, -1)
        lookups = _lookups(context, frozenset())
        self._on_grid: GridLookups[Repair] = grid_lookups(lookups, grid)
        self._slots = self._on_grid.slots
        self._faulty = lookups.faulty_slots
        occupancy_rows(grid, lookups.radius)  # the grid's codes, before any timed repair

    def _use(self, known: frozenset[Any]) -> None:
        """Switch to the look-ups of ``known`` (a new frozenset of the same faults keeps them)."""
        if self._known is None or known != self._known:
            lookups = _lookups(self._context, known)
            self._on_grid = grid_lookups(lookups, self._context.grid)
            self._slots = self._on_grid.slots
            self._faulty = lookups.faulty_slots
        self._known = known

    def _quad(self, action: Any) -> int:
        """``4 *`` the index of ``action`` (by identity, else by equality)."""
        quad = self._quads.get(id(action))
        return 4 * self._index.of(action) if quad is None else quad

    def repair(self, request: RepairRequest) -> Repair:
        """The stored repair of the pattern around the pose (see the class docstring).

        The hot path of a warm hit, kept to a few dozen bytecodes: the request unpacked at once,
        the last faulty action's slot remembered by identity (a robot meets the same faulty
        action again and again), then the pose's occupancy code by row and column, one ``&``, one
        dictionary look-up and one truth test."""
        pose, queue, known, _ = request
        if known is not self._known:
            self._use(known)
        action = queue[0]
        last, quad = self._last
        if action is not last:
            quad = self._quad(action)
            self._last = (action, quad)
        slot = quad + pose.heading
        entry = self._slots[slot]
        if entry is None:
            entry = self._on_grid.slot(slot)
        mask, answers, rows = entry
        found: Repair | Missing | None = answers.get(rows[pose.y][pose.x] & mask, MISSING)
        if not found:  # a stored repair is a non-empty tuple; MISSING and None are false
            if found is MISSING:
                found = self._on_grid.fill(slot, pose.x, pose.y, rows[pose.y][pose.x] & mask)
            if found is None:
                return _miss(self._context, request, action)
        return self._rewritten(request, found, slot) if self._rewrite else found

    def _rewritten(self, request: RepairRequest, head: Repair, slot: int) -> Repair:
        """``head`` extended over the rest of the queue: every later faulty action with a valid
        replacement at its predicted pose substituted, up to the first one without (the robot
        will replan there, dropping the rest) or the first predicted pose off the maze (a plan
        that leaves it is not this walk's to mend). The actions after the last substitution stay
        queued as they are, so every action of the repair is available."""
        rest = request.queue[1:]
        faulty, moves, slots = self._faulty, self._moves, self._slots
        width, height = self._size
        quads = list(map(self._quads.get, map(id, rest)))  # in C; by identity (see _quad)
        dx, dy, h = moves[slot]
        x, y = request.pose.x + dx, request.pose.y + dy
        parts: list[Sequence[Any]] = [head.actions]
        done = substituted = 0
        for k, quad in enumerate(quads):
            if quad is None:
                quad = self._quad(rest[k])
            slot = quad + h
            if faulty[slot]:
                if not (0 <= x < width and 0 <= y < height):
                    break
                mask, answers, rows = slots[slot] or self._on_grid.slot(slot)
                key = rows[y][x] & mask
                hit: Repair | Missing | None = answers.get(key, MISSING)
                if hit is MISSING:
                    hit = self._on_grid.fill(slot, x, y, key)
                if hit is None:  # the robot will replan here: what follows would be dropped
                    break
                if done < k:
                    parts.append(rest[done:k])
                parts.append(hit.actions)
                done = k + 1
                substituted += 1
            dx, dy, h = moves[slot]
            x += dx
            y += dy
        if not substituted:
            return head
        return Repair(  # built directly: NamedTuple._replace costs several microseconds
            head.status,
            head.source,
            tuple(chain.from_iterable(parts)),
            1 + done,
            head.replans,
            head.candidate_length,
            head.depth,
            head.examined,
            head.expansions,
            head.attempts,
            head.candidate_index,
            substituted,
        )


class DeferringRepairer:
    """The ``replacement`` strategy in a recursion mode that defers faulty complex actions
    (``primitive``): a replacement may keep a faulty complex action, to be replaced when the robot
    reaches it (see :mod:`selfrepair.repair.replacement`).

    State (per mission): for each deferred action still ahead in the queue, the guard set of the
    replacement it belongs to, keyed by its distance from the end of the queue (which repairs of
    the actions before it do not change). When the robot reaches it, its replacement is searched
    with that guard set plus itself, so no replacement reuses an action that an enclosing one is
    still replacing (the guard that keeps recursion from cycling, carried over execution). A full
    replan replaces the whole queue and forgets them.
    """

    __slots__ = ("_context", "_pending")

    def __init__(self, context: MissionContext) -> None:
        self._context = context
        self._pending: dict[int, tuple[Any, frozenset[Any]]] = {}

    def repair(self, request: RepairRequest) -> Repair:
        """The first valid candidate (deferred actions kept), else :func:`replan`."""
        context = self._context
        table = _table(context)
        queue, action = request.queue, request.queue[0]
        remaining = len(queue)
        pending = self._pending
        for marker in [m for m in pending if m > remaining]:
            del pending[marker]  # passed: no longer ahead
        outer = pending.pop(remaining, None)
        guard = outer[1] if outer is not None and outer[0] == action else frozenset()
        options = context.options
        found = compiled_replacement(
            table,
            action,
            request.pose,
            request.known,
            context.grid,
            mode=options.recursion,
            max_depth=options.max_depth,
            guard=guard,
            max_patterns=options.max_lookup_patterns,
        )
        if found is None:
            pending.clear()  # a replan replaces the whole queue
            return _miss(context, request, action)
        replacing = guard | {action}
        after = remaining - 1 + len(found.actions)
        for position in found.deferred:
            deferred = found.actions[position]
            pending[after - position] = (deferred, replacing | {deferred})
        return _hit(found)


def start_replacement(context: MissionContext) -> Repairer:
    """The ``replacement`` strategy's factory: :class:`ReplacementRepairer`, or
    :class:`DeferringRepairer` in a deferring recursion mode (``primitive``)."""
    if context.options.recursion in DEFERRING:
        return DeferringRepairer(context)
    return ReplacementRepairer(context)


def lookahead(context: MissionContext, request: RepairRequest) -> Repair:
    """Replace a window of the queue by the cheapest sub-plan to the window's end pose.

    The window runs from the front of the queue to ``window`` actions after the first faulty
    action. That faulty action is the first one queued when the executor met it there; with
    ``before > 0`` the executor asks as soon as it is among the next ``before`` actions after the
    front, under the faults known (:attr:`FunctionRepairer.horizon`), so the window also takes in
    the up to ``before`` actions that would have been executed before it. The robot cannot undo
    actions it has executed, so a window can reach back only when the fault is known ahead.

    When no sub-plan is found within ``lookahead_expansions``: :func:`replacement` (which falls
    back to :func:`replan`) for the faulty action at the pose where the robot will meet it, after
    the healthy actions before it.
    """
    domain = context.domain
    queue = request.queue
    faulty = _first_faulty(domain, queue, request.known, context.options.before)
    window = queue[: faulty + context.options.window + 1]
    end = run_open(domain, request.pose, window)
    budget = context.options.lookahead_expansions
    result = context.plan(request.pose, end.cell, end.heading, request.known, budget)
    if result.status is PlanStatus.SOLVED:
        return Repair(
            RepairStatus.REPAIRED,
            RepairSource.LOOKAHEAD,
            result.actions,
            len(window),
            expansions=result.expansions,
            attempts=(StrategyName.LOOKAHEAD,),
        )
    if not faulty:
        fallback = replacement(context, request)
    else:
        prefix = tuple(queue[:faulty])
        at = run_open(domain, request.pose, prefix)
        later = request._replace(pose=at, queue=tuple(queue[faulty:]))
        fallback = replacement(context, later)
        fallback = fallback._replace(
            actions=prefix + fallback.actions, consumed=fallback.consumed + faulty
        )
    return _chain(fallback, (StrategyName.LOOKAHEAD,), expansions=result.expansions)


def _first_faulty(
    domain: Domain[Any, Any], queue: Sequence[Any], known: frozenset[Any], before: int
) -> int:
    """The index of the first queued action unavailable under ``known``, among the first
    ``before + 1`` (0 when none is: the front is then repaired as it is)."""
    for i in range(min(before + 1, len(queue))):
        if not domain.available(queue[i], known):
            return i
    return 0


def start_lookahead(context: MissionContext) -> Repairer:
    """The ``lookahead`` strategy's factory: stateless, looking ``options.before`` actions ahead
    of the front for known faults."""
    return FunctionRepairer(context, lookahead, context.options.before)


def _chain(
    repair: Repair, before: tuple[str, ...], *, examined: int = 0, expansions: int = 0
) -> Repair:
    """``repair`` with the strategies tried before it prepended and their work added."""
    return repair._replace(
        examined=repair.examined + examined,
        expansions=repair.expansions + expansions,
        attempts=before + repair.attempts,
    )


# --- the registry ---------------------------------------------------------------------------

STRATEGIES: dict[str, StrategyFactory] = {
    StrategyName.REPLAN: stateless(replan),
    StrategyName.REPLACEMENT: start_replacement,
    StrategyName.LOOKAHEAD: start_lookahead,
}
"""Strategy factories by name (built-ins and those registered so far)."""

_TABLE_USERS: set[str] = {StrategyName.REPLACEMENT, StrategyName.LOOKAHEAD}
"""Strategies that use a replacement table (the executor loads one only for these)."""

_BUILT_ELSEWHERE: dict[str, str] = {
    "dstar-lite": "selfrepair.repair.dstar_lite:start_dstar_lite",
    "lpg-adapt": "selfrepair.baselines.adapt:start_lpg_adapt",
}
"""Strategies whose modules import this one, by ``"module:factory"``: imported on first use (so
that importing the registry does not import every strategy, and no module imports itself)."""


def register_strategy(
    name: str, factory: StrategyFactory, *, replace: bool = False, uses_table: bool = False
) -> None:
    """Make ``factory`` available as strategy ``name`` (``uses_table``: the executor loads the
    mission's table for it). A name in use raises :class:`ProblemError` unless ``replace``."""
    if name in STRATEGIES and STRATEGIES[name] is not factory and not replace:
        raise ProblemError(f"a strategy named {name!r} is already registered")
    STRATEGIES[name] = factory
    if uses_table:
        _TABLE_USERS.add(name)


def uses_table(name: str) -> bool:
    """Whether strategy ``name`` needs the mission's replacement table."""
    get_strategy(name)
    return name in _TABLE_USERS


def get_strategy(name: str) -> StrategyFactory:
    """The factory of strategy ``name``; unknown names raise :class:`ProblemError`."""
    factory = STRATEGIES.get(name)
    if factory is not None:
        return factory
    target = _BUILT_ELSEWHERE.get(name)
    if target is not None:
        module, _, attribute = target.partition(":")
        factory = getattr(importlib.import_module(module), attribute)
        STRATEGIES[name] = factory
        return factory  # type: ignore[no-any-return]  # a factory by contract
    raise ProblemError(f"unknown strategy {name!r}; expected one of {', '.join(strategy_names())}")


def strategy_names() -> tuple[str, ...]:
    """Every strategy name :func:`get_strategy` accepts, built-ins first."""
    return tuple(dict.fromkeys([*STRATEGIES, *_BUILT_ELSEWHERE]))
