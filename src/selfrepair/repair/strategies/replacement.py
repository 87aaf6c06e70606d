"""The ``replacement`` strategy: look the faulty action up in the replacement table and take the
first valid candidate (in the chosen recursion mode); fall back to ``replan`` when none is valid.

The look-up goes through the compiled look-ups of :mod:`selfrepair.repair.lookups` (a warm hit is
one integer-keyed dictionary look-up; same answers as the reference search of
:mod:`selfrepair.repair.replacement`). With ``StrategyOptions.rewrite`` the repairer, once a
fault is known, also walks the rest of the plan and substitutes every faulty action that has a
valid replacement at its predicted pose, so later encounters never reach the repairer (see
:class:`ReplacementRepairer`). In a deferring recursion mode (``primitive``) the strategy is a
:class:`DeferringRepairer`.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import chain, islice

from selfrepair.errors import ProblemError
from selfrepair.geometry import FreeGrid
from selfrepair.repair.detours import DetourFinder
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
    same_replacement,
)
from selfrepair.repair.replacement import DEFERRING, Replacement
from selfrepair.repair.strategies.names import RepairSource, StrategyName
from selfrepair.repair.strategies.protocol import (
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    chained,
)
from selfrepair.repair.strategies.registry import register_strategy
from selfrepair.repair.strategies.replan import replan
from selfrepair.status import RepairStatus
from selfrepair.tables.model import SomeTable

__all__ = [
    "DeferringRepairer",
    "ReplacementRepairer",
    "deferring_lookups",
    "hit_repair",
    "replacement",
    "start_replacement",
    "strategy_lookups",
    "table_hit",
]


def hit_repair(found: Replacement) -> Repair:
    """The repair of a table hit ``found`` (what the strategy returns for it). It does not
    depend on the pose, so the compiled look-ups store it and a warm hit returns it as it is."""
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


DETOUR = RepairSource.DETOUR.value
"""The name of a detour attempt in ``Repair.attempts``."""


def _detour(position: int, actions: tuple[object, ...], consumed: int) -> Repair:
    """The repair of a detour (pose-independent, so the detour look-ups store it)."""
    return Repair(
        RepairStatus.REPAIRED,
        RepairSource.DETOUR,
        actions,
        consumed,
        candidate_length=len(actions),
        depth=0,
        examined=position + 1,
        attempts=(DETOUR,),
        candidate_index=position,
    )


def _table(context: MissionContext) -> SomeTable:
    if context.table is None:
        raise ProblemError("the replacement strategy needs a table")
    return context.table


def _lookups(context: MissionContext, known: frozenset[object]) -> FaultLookups[Repair]:
    options = context.options
    return fault_lookups(
        _table(context),
        known,
        mode=options.recursion,
        max_depth=options.max_depth,
        answer=hit_repair,
        max_patterns=options.max_lookup_patterns,
    )


def strategy_lookups(
    context: MissionContext, known: frozenset[object], grid: FreeGrid
) -> GridLookups[Repair]:
    """The look-ups the strategy reads under ``known`` on ``grid`` (the compiled mission loop
    copies their answers: :mod:`selfrepair.execution.compiled`)."""
    return grid_lookups(_lookups(context, known), grid)


def deferring_lookups(
    context: MissionContext, known: frozenset[object], guard: frozenset[object], grid: FreeGrid
) -> GridLookups[Replacement]:
    """The look-ups a :class:`DeferringRepairer` reads under ``known`` with the guard set
    ``guard`` on ``grid`` (answers with their deferred actions; the compiled mission loop copies
    them and makes each hit's repair with :func:`hit_repair`)."""
    options = context.options
    lookups = fault_lookups(
        _table(context),
        known,
        mode=options.recursion,
        max_depth=options.max_depth,
        answer=same_replacement,
        guard=guard,
        max_patterns=options.max_lookup_patterns,
    )
    return grid_lookups(lookups, grid)


def _miss(context: MissionContext, request: RepairRequest, action: object) -> Repair:
    """No valid candidate: :func:`replan`, with the candidates looked at counted."""
    examined = len(_table(context).candidates(action, request.known))
    return chained(replan(context, request), (StrategyName.REPLACEMENT,), examined=examined)


def table_hit(context: MissionContext, request: RepairRequest) -> Repair | None:
    """The repair of the first valid table candidate for the faulty action under the known
    faults, or ``None`` (no fallback: a strategy that wants to do something else on a miss)."""
    return _lookups(context, request.known).get(request.queue[0], request.pose, context.grid)


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
        "_belief",
        "_context",
        "_detours",
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
        self._belief = context.belief  # mutable: the stepper keeps its cells up to date
        self._rewrite = context.options.rewrite
        self._index = action_index(context.domain)
        grid = context.grid
        self._size = (grid.width, grid.height)
        self._quads = self._index.quads
        self._moves = self._index.slot_moves
        self._known: frozenset[object] | None = None
        self._last: tuple[object, int] = (None, -1)
        lookups = _lookups(context, frozenset())
        self._on_grid: GridLookups[Repair] = grid_lookups(lookups, grid)
        self._slots = self._on_grid.slots
        self._faulty = lookups.faulty_slots
        occupancy_rows(grid, lookups.radius)  # the grid's codes, before any timed repair
        self._detours: DetourFinder[Repair] | None = None

    def expect_blocked(self) -> None:
        """The mission's world changes: make the detour table and the grid's codes now, before
        any timed repair (else the first blocked action makes them)."""
        if self._detours is None:
            self._detours = DetourFinder(self._context.domain, self._context.grid, _detour)

    def repair_blocked(self, request: RepairRequest) -> Repair:
        """The first queued action sweeps a cell believed blocked: a local detour from the
        detour table (:mod:`selfrepair.repair.detours`), else a replan around the
        believed-blocked cells. With ``rewrite`` the detour also walks the rest of the queue
        (:meth:`_detours_rewritten`)."""
        finder = self._detours
        if finder is None:  # made on the first blocked action (the detour table is kept)
            finder = self._detours = DetourFinder(self._context.domain, self._context.grid, _detour)
        pose, queue, known, _ = request
        found = finder.find(pose, queue, known, self._belief.blocked)
        if found is None:
            return chained(replan(self._context, request), (DETOUR,))
        return self._detours_rewritten(request, found, finder) if self._rewrite else found

    def _detours_rewritten(
        self, request: RepairRequest, head: Repair, finder: DetourFinder[Repair]
    ) -> Repair:
        """``head`` (the first window's detour) extended over the rest of the queue in one pass:
        following the poses the plan predicts, every later window that starts with an action
        sweeping a believed-blocked cell is replaced by its detour (the same window rule, from
        the pose where the robot would meet it), up to the first that has none (the robot will
        replan there, as without rewriting, which drops the rest) or the first predicted pose
        off the maze. A detour ends where its window ends, so the predicted poses stay exact,
        and while the belief stays as it is the robot makes the same motions as without
        rewriting, with one repair instead of one per window. Faulty actions are left to the
        fault repairs (as they are when the robot meets them)."""
        actions = tuple(request.queue)
        known, blocked = request.known, self._belief.blocked
        parts: list[Sequence[object]] = [head.actions]
        done, begin, pose, rewritten = head.consumed, 0, request.pose, 0
        while (met := finder.next_blocked(pose, actions, begin, done)) is not None:
            k, pose = met
            found = finder.find(pose, islice(actions, k, None), known, blocked)
            if found is None:  # the robot will replan here: what follows would be dropped
                break
            parts.append(actions[done:k])
            parts.append(found.actions)
            done, begin = k + found.consumed, k
            rewritten += 1
        if not rewritten:
            return head
        return head._replace(
            actions=tuple(chain.from_iterable(parts)), consumed=done, rewritten=rewritten
        )

    def _use(self, known: frozenset[object]) -> None:
        """Switch to the look-ups of ``known`` (a new frozenset of the same faults keeps them)."""
        if self._known is None or known != self._known:
            lookups = _lookups(self._context, known)
            self._on_grid = grid_lookups(lookups, self._context.grid)
            self._slots = self._on_grid.slots
            self._faulty = lookups.faulty_slots
        self._known = known

    def _quad(self, action: object) -> int:
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
        parts: list[Sequence[object]] = [head.actions]
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
        self._pending: dict[int, tuple[object, frozenset[object]]] = {}

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
        return hit_repair(found)


def start_replacement(context: MissionContext) -> Repairer:
    """The ``replacement`` strategy's factory: :class:`ReplacementRepairer`, or
    :class:`DeferringRepairer` in a deferring recursion mode (``primitive``)."""
    if context.options.recursion in DEFERRING:
        return DeferringRepairer(context)
    return ReplacementRepairer(context)


register_strategy(StrategyName.REPLACEMENT, start_replacement, uses_table=True)
