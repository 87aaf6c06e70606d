"""The fault-agnostic table shape: ``per_action`` candidates per action, chosen to stay usable
under the most fault sets.

For each action the pool holds the concrete candidates found under every fault set that disables
it. A greedy set cover picks candidates by the fault sets they newly cover, then swaps improve
the choice; ties go to what the robot pays (or, with ``priority="walls"``, to candidates that fit
wherever the action fits). Remaining slots go to candidates diverse in the cells they sweep. See
:mod:`selfrepair.tables.generate` for the whole method.
"""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Generic

import numpy as np
import numpy.typing as npt

from selfrepair.geometry import Cell
from selfrepair.robots.domain import A, Domain, F
from selfrepair.tables.enumerate import (
    Objective,
    Path,
    Searcher,
    concrete_actions,
    domain_classes,
    scope_fault_sets,
    select_diverse,
    verify_entry,
)
from selfrepair.tables.model import GenerateOptions, TableEntry

__all__ = ["fault_agnostic_entries"]


@dataclass(frozen=True, slots=True)
class _Option(Generic[A]):
    """A concrete candidate in the fault-agnostic pool with its usability bitmask."""

    actions: tuple[A, ...]
    rank: tuple[int, int, int, int, tuple[str, ...]]
    usable: int
    extra: frozenset[Cell]


def fault_agnostic_entries(
    domain: Domain[A, F], options: GenerateOptions, searcher: Searcher[A, F]
) -> list[TableEntry[A, F]]:
    info = domain_classes(domain)
    scope = scope_fault_sets(domain, options.faults)
    masks = {
        a: sum(1 << i for i, f in enumerate(scope) if domain.available(a, f))
        for a in domain.actions
    }
    full = (1 << len(scope)) - 1
    durations = {a: int(domain.duration(a) * info.scale) for a in domain.actions}
    entries: list[TableEntry[A, F]] = []
    for action in domain.actions:
        motion = info.classes[info.of_action[action]]
        relevant = full & ~masks[action]
        situations = [
            searcher.costs_under(f) for i, f in enumerate(scope) if relevant >> i & 1
        ] or [searcher.costs(partial(operator.ne, action))]
        pool = _Pool(domain, options, action, motion.footprint, masks, durations, full, {}, {})
        for costs in situations:
            found = searcher.paths(costs)[motion.end]
            diverse = select_diverse(found, motion.footprint, options.per_action)
            for path in [*diverse, *found[: 2 * options.per_action]]:
                pool.paths.setdefault(path.motions, path)
                pool.add(concrete_actions(path, costs), path)
        for path in list(pool.paths.values()):
            if len(path.motions) == 1:
                for member in info.classes[path.motions[0]].members:
                    pool.add((member,), path)
        chosen = _greedy_cover(pool, relevant, options.per_action, no_faults=not scope)
        if not chosen:
            continue
        candidates = tuple(o.actions for o in sorted(chosen, key=lambda o: o.rank))
        verify_entry(domain, action, candidates)
        entries.append(TableEntry(action=action, candidates=candidates))
    return entries


@dataclass(slots=True)
class _Pool(Generic[A, F]):
    """The concrete candidates considered for one fault-agnostic entry.

    ``paths`` are the class sequences found under any fault set that disables the action (the
    diverse choice and the ``2 * per_action`` cheapest);
    ``options`` their concrete versions: the fastest under each such fault set, every member for
    one-step paths, and (added round by round in :func:`_greedy_cover`) the concrete version
    that stays usable under the most fault sets not yet covered.
    """

    domain: Domain[A, F]
    gen: GenerateOptions
    action: A
    base: frozenset[Cell]
    masks: Mapping[A, int]
    durations: Mapping[A, int]
    full: int
    paths: dict[tuple[int, ...], Path]
    options: dict[tuple[A, ...], _Option[A]]
    members: dict[int, list[tuple[int, int, A]]] = field(default_factory=dict)

    def add(self, concrete: tuple[A, ...], path: Path) -> None:
        if concrete in self.options or self.action in concrete:
            return
        usable = self.full
        for a in concrete:
            usable &= self.masks[a]
        self.options[concrete] = _Option(
            concrete,
            _healthy_rank(self.domain, concrete, path, self.gen),
            usable,
            path.footprint - self.base,
        )

    def add_robust(self, uncovered: int, relevant: int) -> None:
        """Per path, choose each step's member to keep the most uncovered fault sets usable."""
        info = domain_classes(self.domain)
        if not self.members:
            for motion in info.classes:
                self.members[motion.index] = [
                    (self.masks[m], -self.durations[m], m)
                    for m in motion.members
                    if m != self.action
                ]
        for path in self.paths.values():
            usable = self.full
            concrete: list[A] = []
            for ci in path.motions:
                members = self.members[ci]
                if not members:
                    break
                best_key: tuple[int, int, int] | None = None
                pick = members[0][2]  # the first member always wins the first comparison
                for mask, neg_duration, member in members:
                    key = (
                        (usable & mask & uncovered).bit_count(),
                        (usable & mask & relevant).bit_count(),
                        neg_duration,
                    )
                    if best_key is None or key > best_key:
                        best_key, pick = key, member
                usable &= self.masks[pick]
                concrete.append(pick)
            else:
                self.add(tuple(concrete), path)


def _healthy_rank(
    domain: Domain[A, F], concrete: tuple[A, ...], path: Path, options: GenerateOptions
) -> tuple[int, int, int, int, tuple[str, ...]]:
    scale = domain_classes(domain).scale
    duration = sum(int(domain.duration(a) * scale) for a in concrete)
    cost = duration if options.objective == Objective.DURATION else len(concrete)
    names = tuple(domain.format_action(a) for a in concrete)
    return (cost, duration, len(concrete), len(path.footprint), names)


_UNUSABLE = np.iinfo(np.int64).max // 4

Value = tuple[int, int, int]
"""(fault sets covered, minus the summed cost of the cheapest usable candidate under each covered
fault set, fault sets with a usable candidate that fits wherever the action does); with priority
``walls`` the last two swap places."""


_Row = tuple[npt.NDArray[np.int64], npt.NDArray[np.bool_]]
"""One option's costs and "fits" flags over the fault-set columns."""


@dataclass(frozen=True, slots=True)
class _Matrices:
    """Per option (row) and fault set (column): its cost where usable, and whether it is usable
    and sweeps no cell beyond the replaced action's own (so it fits wherever the action fits)."""

    cost: npt.NDArray[np.int64]
    safe: npt.NDArray[np.bool_]
    walls_first: bool

    @staticmethod
    def build(
        ranked: Sequence[_Option[A]],
        bits: Sequence[int],
        no_faults: bool,
        walls_first: bool,
        rows: dict[tuple[A, ...], _Row],
    ) -> _Matrices:
        """``rows`` memoises each option's row across rounds (the columns never change)."""
        columns = 1 if no_faults else len(bits)
        bit_array = np.array(bits, dtype=object)
        for option in ranked:
            if option.actions in rows:
                continue
            if no_faults:
                usable = np.ones(1, dtype=bool)
            else:
                usable = ((option.usable >> bit_array) & 1).astype(bool)
            rows[option.actions] = (
                np.where(usable, option.rank[0], _UNUSABLE),
                usable & (not option.extra),
            )
        cost = np.empty((len(ranked), columns), dtype=np.int64)
        safe = np.empty((len(ranked), columns), dtype=bool)
        for i, option in enumerate(ranked):
            cost[i], safe[i] = rows[option.actions]
        return _Matrices(cost, safe, walls_first)

    def base(self, rows: Sequence[int]) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.bool_]]:
        """Column minima and column "any safe" over ``rows``."""
        if not rows:
            return (
                np.full(self.cost.shape[1], _UNUSABLE, dtype=np.int64),
                np.zeros(self.cost.shape[1], dtype=bool),
            )
        return (
            np.asarray(self.cost[list(rows)].min(axis=0)),
            np.asarray(self.safe[list(rows)].any(axis=0)),
        )

    def best_addition(self, rows: Sequence[int]) -> tuple[Value, int]:
        """The best value and row when one row joins ``rows``; ties go to the lowest row, i.e.
        the cheapest option."""
        if self.cost.shape[0] == 0:
            return (0, 0, 0), 0
        base_cost, base_safe = self.base(rows)
        merged = np.minimum(self.cost, base_cost)
        usable = merged < _UNUSABLE
        covered = usable.sum(axis=1)
        safe = (self.safe | base_safe).sum(axis=1)
        total = np.where(usable, merged, 0).sum(axis=1)
        if self.walls_first:
            order = np.lexsort((np.arange(len(covered)), total, -safe, -covered))
            best = int(order[0])
            return (int(covered[best]), int(safe[best]), -int(total[best])), best
        order = np.lexsort((np.arange(len(covered)), -safe, total, -covered))
        best = int(order[0])
        return (int(covered[best]), -int(total[best]), int(safe[best])), best


def _greedy_cover(
    pool: _Pool[A, F], relevant: int, limit: int, *, no_faults: bool
) -> list[_Option[A]]:
    """Choose up to ``limit`` options for one fault-agnostic entry.

    First maximise the :data:`Value` (fault sets covered; then minus the summed cost of the
    cheapest usable option under each; then fault sets where some usable option fits wherever
    the action fits -- the last two swapped with priority ``walls``), greedily and then by single
    swaps. The run-time machinery takes the first valid candidate and candidates are written
    cheapest first, so that sum is what the robot pays in free space. Free slots then go to
    options that are the first to fit some wall arrangement (see :func:`select_diverse`) under
    some fault set.
    """
    bits = [i for i in range(relevant.bit_length()) if relevant >> i & 1]
    chosen: list[_Option[A]] = []
    current: Value = (0, 0, 0)
    walls_first = pool.gen.priority == "walls"
    rows: dict[tuple[A, ...], _Row] = {}
    while len(chosen) < limit:
        covered_mask = 0
        for o in chosen:
            covered_mask |= o.usable
        pool.add_robust(relevant & ~covered_mask, relevant)
        ranked = sorted(pool.options.values(), key=lambda o: o.rank)
        matrices = _Matrices.build(ranked, bits, no_faults, walls_first, rows)
        value, index = matrices.best_addition([ranked.index(o) for o in chosen])
        if value <= current:
            break
        chosen.append(ranked[index])
        current = value
    ranked = sorted(pool.options.values(), key=lambda o: o.rank)
    chosen = _improve_by_swaps(
        chosen, ranked, _Matrices.build(ranked, bits, no_faults, walls_first, rows), current
    )
    return _fill_diverse(chosen, ranked, relevant, limit, no_faults=no_faults)


def _improve_by_swaps(
    chosen: list[_Option[A]], ranked: Sequence[_Option[A]], matrices: _Matrices, current: Value
) -> list[_Option[A]]:
    """Local search after the greedy pass: replace one pick by the best pool option while that
    strictly improves the value (greedy maximum coverage can miss the optimum)."""
    for _ in range(4 * len(chosen)):
        improved = False
        for i in range(len(chosen)):
            rest = chosen[:i] + chosen[i + 1 :]
            value, index = matrices.best_addition([ranked.index(o) for o in rest])
            if value > current and ranked[index] not in rest:
                chosen, current, improved = [*rest, ranked[index]], value, True
        if not improved:
            break
    return chosen


def _fill_diverse(
    chosen: list[_Option[A]],
    ranked: Sequence[_Option[A]],
    relevant: int,
    limit: int,
    *,
    no_faults: bool,
) -> list[_Option[A]]:
    """Add, cheapest first, options that are the first to fit some wall arrangement under some
    fault set: no chosen option usable there sweeps a subset of their extra cells."""
    chosen = list(chosen)
    for option in ranked:
        if len(chosen) >= limit:
            break
        if option in chosen:
            continue
        blocked = 0
        for other in chosen:
            if other.extra <= option.extra:
                blocked |= other.usable
        if no_faults:
            adds = not any(o.extra <= option.extra for o in chosen)
        else:
            adds = bool(option.usable & relevant & ~blocked)
        if adds:
            chosen.append(option)
    return chosen
