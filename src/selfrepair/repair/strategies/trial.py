"""The ``trial-and-error`` strategy: repair without any fault model (after IT&E, Cully et al.,
Nature 2015: a damaged robot tries behaviours from a repertoire in an order learned offline, and
keeps what works).

The robot knows no faults and no fault-behaviour model. It only sees whether a command did what it
was commanded to do: an action that went elsewhere, bumped or failed is *unusable* from then on
(the stepper checks the queue against that set, see :class:`~.protocol.Assumption`). An unusable
action at the front of the queue is replaced by a candidate of the replacement table, tried in an
order learned offline from simulated damage: for each action, its candidates are ranked by the
share of the domain's fault sets that forbid the action under which every command of the
candidate still works (a pure count over ``Domain.available``, made once per table; ties keep the
table's order), a candidate that worked for the action before first. A candidate is *kept* when
all its commands did what they should, *dropped* (never tried again for that action) when one did
not. When no candidate is usable and executable there, a breadth-first search over the usable
actions (the fastest of each motion class, footprints free on the map, at most
:data:`SEARCH_DEPTH` commands and :data:`SEARCH_NODES` poses) finds a way to the pose the action
should have reached; the same search takes the robot back to where the queue starts after a
command went astray.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from fractions import Fraction
from typing import Any, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.diagnosis import Observation
from selfrepair.errors import ProblemError
from selfrepair.geometry import Pose
from selfrepair.repair.strategies.names import RepairSource, StrategyName
from selfrepair.repair.strategies.protocol import (
    Assumption,
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
)
from selfrepair.repair.strategies.registry import register_strategy
from selfrepair.robots.domain import A, F, SomeDomain
from selfrepair.status import RepairStatus
from selfrepair.tables.model import ReplacementTable

__all__ = ["SEARCH_DEPTH", "SEARCH_NODES", "TrialRepairer", "learned_order"]

SEARCH_DEPTH = 8
"""Commands the fallback search may string together."""
SEARCH_NODES = 4000
"""Poses the fallback search may visit."""

Candidate = tuple[object, ...]


def learned_order(table: ReplacementTable[A, F]) -> dict[A, tuple[tuple[A, ...], ...]]:
    """Per action, every candidate the table holds for it (under any fault set it indexes),
    ranked by its success share under simulated damage (see the module docstring)."""
    # keyed by the table: the value orders its candidates
    return cast("dict[A, tuple[tuple[A, ...], ...]]", _ORDERS.get(table, lambda: _learn(table)))


_ORDERS: BoundedCache[object, object] = BoundedCache(
    "trial-and-error candidate orders", 8, kind=CacheKind.PREFILLED
)


def _learn(table: ReplacementTable[A, F]) -> dict[A, tuple[tuple[A, ...], ...]]:
    domain = table.domain
    damage = domain.fault_sets
    order: dict[A, tuple[tuple[A, ...], ...]] = {}
    for action in domain.actions:
        pooled: dict[tuple[A, ...], None] = {}
        for faults in (frozenset(), *damage):
            for candidate in table.candidates(action, faults):
                pooled.setdefault(tuple(candidate), None)
        broken = [f for f in damage if not domain.available(action, f)]

        def share(candidate: tuple[A, ...], broken: list[frozenset[F]] = broken) -> Fraction:
            works = sum(all(domain.available(b, f) for b in candidate) for f in broken)
            return Fraction(works, len(broken) or 1)

        ranked = sorted(enumerate(pooled), key=lambda item: (-share(item[1]), item[0]))
        order[action] = tuple(c for _, c in ranked)
    return order


class TrialRepairer:
    """The ``trial-and-error`` strategy started for one mission (see the module docstring).
    Mutable: the unusable actions, the kept and dropped candidates, the command blocks at the
    front of the queue."""

    __slots__ = (
        "_anchor",
        "_context",
        "_drop",
        "_fastest",
        "_order",
        "_rejoining",
        "_trying",
        "_wanted",
        "dropped",
        "kept",
        "surprise_step",
        "unusable",
    )

    def __init__(self, context: MissionContext) -> None:
        if context.table is None:
            raise ProblemError("the trial-and-error strategy needs a table")
        self._context = context
        self._order = learned_order(context.table)
        self.unusable: frozenset[object] = frozenset()
        """The actions seen to misbehave."""
        self.kept: dict[object, Candidate] = {}
        """Per action, the candidate that last worked for it."""
        self.dropped: set[tuple[object, Candidate]] = set()
        """(action, candidate) pairs that went wrong."""
        self._trying: tuple[object, Candidate, int] | None = None
        self._anchor: Pose | None = None
        self._rejoining = 0
        self._drop = 0
        self._wanted = False
        self._fastest: tuple[object, ...] = ()
        self.surprise_step: int | None = None

    def assumption(self) -> Assumption:
        """No fault is assumed; the actions seen to misbehave are unusable."""
        return Assumption(frozenset(), self.unusable)

    def observe(self, observation: Observation, deviated: bool, moved: bool) -> bool:
        """Mark a command that did not do what it should unusable; keep or drop the candidate
        being tried; whether to rejoin the queue before the next command."""
        surprising = deviated or not moved
        if surprising:
            if self.surprise_step is None:
                self.surprise_step = observation.step
            self.unusable = self.unusable | {observation.action}
            self._fastest = ()
        trying = self._trying
        if trying is not None:
            action, candidate, left = trying
            if surprising:
                self.dropped.add((action, candidate))
                self.kept.pop(action, None)
                self._trying = None
            elif left <= 1:
                self.kept[action] = candidate
                self._trying = None
            else:
                self._trying = (action, candidate, left - 1)
        rejoin = False
        if self._rejoining:
            if moved and not deviated:
                self._rejoining -= 1
                if not self._rejoining:
                    self._anchor = None
            else:
                self._drop = max(0, self._rejoining - int(moved))
                self._rejoining = 0
                rejoin = True
        elif deviated:
            self._anchor = self._context.domain.apply(observation.start, observation.action)
            rejoin = True
        self._wanted = rejoin
        return rejoin

    def repair(self, request: RepairRequest) -> Repair:
        """A rejoin when asked for one; else the first usable, executable candidate in the
        learned order; else the fallback search."""
        if self._wanted:
            self._wanted = False
            return self._rejoin(request)
        if not request.queue:
            return self._goal(request, 0)
        action = request.queue[0]
        domain = self._context.domain
        first = self.kept.get(action)
        ordered = self._order.get(action, ())
        examined = 0
        for candidate in ((first,) if first else ()) + ordered:
            examined += 1
            if (action, candidate) in self.dropped or not self._usable(request.pose, candidate):
                continue
            self._trying = (action, candidate, len(candidate))
            return Repair(
                RepairStatus.REPAIRED,
                RepairSource.REPLACEMENT,
                candidate,
                1,
                candidate_length=len(candidate),
                examined=examined,
                attempts=(StrategyName.TRIAL_AND_ERROR,),
            )
        target = domain.apply(request.pose, action)
        return self._search(request, target, 1, examined)

    def _usable(self, pose: Pose, candidate: Candidate) -> bool:
        """Whether every command of ``candidate`` is usable and executable from ``pose`` on."""
        domain, free, unusable = self._context.domain, self._context.free, self.unusable
        for action in candidate:
            if action in unusable or not free(domain.footprint(pose, action)):
                return False
            pose = domain.apply(pose, action)
        return True

    def _rejoin(self, request: RepairRequest) -> Repair:
        drop, self._drop = self._drop, 0
        target = self._anchor
        if target is None or len(request.queue) - drop <= 0:
            self._anchor = None
            target = None
        if target is None or request.pose == target:
            self._anchor = None
            if len(request.queue) - drop > 0:
                return Repair(RepairStatus.REPAIRED, RepairSource.LOOKAHEAD, (), drop,
                              attempts=("rejoin",))  # fmt: skip
            return self._goal(request, drop)
        found = self._search(request, target, drop, 0)
        if found.status is RepairStatus.REPAIRED:
            self._rejoining = len(found.actions)
        else:
            self._anchor = None
        return found

    def _goal(self, request: RepairRequest, drop: int) -> Repair:
        """The queue ran out away from the goal: search to the goal (``StrategyOptions``'
        planner needs a fault model, this strategy has none)."""
        context = self._context
        goal = context.goal
        found = self._bfs(request.pose, lambda p: p.cell == goal and context.at_goal(p), 10**6)
        if found is None:
            return Repair(RepairStatus.STUCK, RepairSource.REPLAN, attempts=("search",))
        return Repair(RepairStatus.REPAIRED, RepairSource.REPLAN, found, drop,
                      attempts=("search",))  # fmt: skip

    def _search(self, request: RepairRequest, target: Pose, consumed: int, examined: int) -> Repair:
        """The fallback search to ``target`` (see the module docstring)."""
        found = self._bfs(request.pose, lambda p: p == target, SEARCH_NODES)
        if found is None:
            return Repair(RepairStatus.STUCK, RepairSource.LOOKAHEAD, examined=examined,
                          attempts=(StrategyName.TRIAL_AND_ERROR, "search"))  # fmt: skip
        return Repair(
            RepairStatus.REPAIRED,
            RepairSource.LOOKAHEAD,
            found,
            consumed,
            examined=examined,
            attempts=(StrategyName.TRIAL_AND_ERROR, "search"),
        )

    def _bfs(
        self, start: Pose, done: Callable[[Pose], bool], nodes: int
    ) -> tuple[object, ...] | None:
        """The fewest usable commands (the fastest of each motion class) from ``start`` to a
        pose for which ``done`` holds, footprints free, at most :data:`SEARCH_DEPTH` of them
        unless ``nodes`` is unbounded (then any length); ``None`` when there is none."""
        context = self._context
        domain: SomeDomain = context.domain
        if not self._fastest:
            best: dict[str, object] = {}
            for action in domain.actions:
                if action in self.unusable:
                    continue
                key = domain.motion_class(action)
                if key not in best or domain.duration(action) < domain.duration(best[key]):
                    best[key] = action
            self._fastest = tuple(best.values())
        depth_limit = SEARCH_DEPTH if nodes < 10**6 else 10**6
        if done(start):
            return ()
        parents: dict[Pose, tuple[Pose, object] | None] = {start: None}
        frontier: deque[tuple[Pose, int]] = deque([(start, 0)])
        while frontier and len(parents) < nodes:
            pose, depth = frontier.popleft()
            if depth >= depth_limit:
                continue
            for action in self._fastest:
                if not context.free(domain.footprint(pose, action)):
                    continue
                nxt = domain.apply(pose, action)
                if nxt in parents:
                    continue
                parents[nxt] = (pose, action)
                if done(nxt):
                    path = []
                    at = nxt
                    while (link := parents[at]) is not None:
                        at, step = link
                        path.append(step)
                    return tuple(reversed(path))
                frontier.append((nxt, depth + 1))
        return None

    def report(self) -> dict[str, Any]:
        """What the result row records (no isolation: this strategy has no hypotheses)."""
        return {
            "surprise_step": self.surprise_step,
            "isolation_actions": None,
            "isolated": (),
            "probes": 0,
            "hypotheses_left": None,
            "classes_left": None,
            "inexplicable": 0,
        }


def start_trial(context: MissionContext) -> Repairer:
    """The ``trial-and-error`` strategy's factory."""
    return TrialRepairer(context)


register_strategy(StrategyName.TRIAL_AND_ERROR, start_trial, uses_table=True, hidden=True)
