"""Automatic replacement tables: enumerate sub-plans in free space and keep the useful ones.

The original work found hand-written tables slow to write, error-prone and full of gaps; this
module writes them from the domain model alone, for any :class:`~selfrepair.domain.Domain` whose
states are :class:`~selfrepair.robot.Pose` values (both shipped domains).

How it works:

1. **Motion classes.** Actions with the same open-plane effect and the same footprint from the
   canonical state form one class (the four-wheel robot's 81 actions fall into the 9 motions of
   :data:`selfrepair.robot.MOTIONS`; the three-action robot's into 3). Under a fault set each class
   costs as much as its cheapest available member, and that member (first in domain order on
   ties, as :func:`selfrepair.robot.fastest_by_motion` picks) is the concrete action written.
   So the search branches over at most 9 classes, not 81 actions, and concrete wheel actions are
   chosen only when a fault set says which ones are left.
2. **Enumeration.** :func:`enumerate_paths` grows class sequences breadth-first from the canonical
   state up to ``max_length`` steps. Duplicates are pruned by key (relative end pose, swept cells):
   of the sequences that end in the same pose having swept the same cells only the cheapest is
   kept, so equivalent orderings are found once per cost level. Branches that can no longer get
   back to a target within the remaining steps are cut. Every sequence that ends where some class
   ends is a candidate replacement for that class.
3. **Choice.** Per target, candidates are ranked cheapest first (objective cost, then duration,
   then length). A candidate is kept only if the cells it sweeps beyond those of the replaced
   action (its *extra* cells) are not a superset of a kept candidate's extra cells: otherwise,
   wherever it fits the cheaper one fits too, so it could never be the first valid candidate.
   This is what makes the kept candidates diverse in the cells they sweep.

Two shapes (see :func:`generate_table`): ``fault-indexed`` stores, per fault set in scope and per
action it disables, up to ``per_action`` candidates made from the actions that fault set leaves;
``fault-agnostic`` stores ``per_action`` candidates per action, chosen (greedily, then improved by
swaps) to maximise the number of fault sets (among those in scope that disable the action) under
which at least one candidate has all its concrete actions available, then to minimise what the
robot pays (the cheapest usable candidate's cost, summed over those fault sets), then to maximise
the fault sets with a usable candidate that fits wherever the action fits; ``priority="walls"``
swaps the last two. Remaining slots go to candidates that are diverse in the cells they sweep.

Every entry is re-simulated (:func:`verify_entry`) before the table is built, and the table
value re-simulates it once more when constructed. Generation is deterministic: same options, same
bytes from :func:`selfrepair.table.dump_table`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.domain import Domain, get_domain, run_open
from selfrepair.errors import ProblemError, TableError
from selfrepair.robot import Cell
from selfrepair.table import ReplacementTable, TableEntry

__all__ = [
    "FAULT_SCOPES",
    "OBJECTIVES",
    "PRIORITIES",
    "SHAPES",
    "GenerateOptions",
    "MotionClass",
    "Path",
    "candidate_cost",
    "class_costs",
    "class_of",
    "cost_scale",
    "enumerate_paths",
    "generate_table",
    "motion_classes",
    "scope_fault_sets",
    "select_diverse",
    "verify_entry",
]

FAULT_SCOPES = ("all", "singles", "doubles", "none")
"""Which fault sets of the domain a table is made for."""

OBJECTIVES = ("duration", "length")
"""What a candidate's cost is: total duration in ticks, or number of actions."""

SHAPES = ("fault-agnostic", "fault-indexed")

PRIORITIES = ("cost", "walls")
"""Fault-agnostic tie-break after coverage: cheapest replacements first (the issue's order), or
first the candidates that fit wherever the replaced action fits."""


@dataclass(frozen=True, slots=True)
class GenerateOptions:
    """Everything that determines a generated table; recorded in its header ``parameters``."""

    domain: str = "four-wheel"
    shape: str = "fault-agnostic"
    max_length: int = 5
    per_action: int = 5
    faults: str = "all"
    objective: str = "duration"
    priority: str = "cost"

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ProblemError(
                f"unknown table shape {self.shape!r}; expected one of {', '.join(SHAPES)}"
            )
        if self.faults not in FAULT_SCOPES:
            raise ProblemError(
                f"unknown fault scope {self.faults!r}; expected one of {', '.join(FAULT_SCOPES)}"
            )
        if self.objective not in OBJECTIVES:
            raise ProblemError(
                f"unknown objective {self.objective!r}; expected one of {', '.join(OBJECTIVES)}"
            )
        if self.priority not in PRIORITIES:
            raise ProblemError(
                f"unknown priority {self.priority!r}; expected one of {', '.join(PRIORITIES)}"
            )
        if not 1 <= self.max_length <= 12:
            raise ProblemError(f"max_length must be from 1 to 12, got {self.max_length}")
        if self.per_action < 1:
            raise ProblemError(f"per_action must be at least 1, got {self.per_action}")

    def parameters(self) -> dict[str, Any]:
        """The options as the JSON header's ``parameters`` object."""
        return {
            "faults": self.faults,
            "max_length": self.max_length,
            "objective": self.objective,
            "per_action": self.per_action,
            "priority": self.priority,
        }


# --- motion classes ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class MotionClass:
    """Actions with one effect: ``end`` and ``footprint`` are taken from the canonical state."""

    index: int
    name: str
    end: Any
    footprint: frozenset[Cell]
    members: tuple[Any, ...]


@dataclass(frozen=True, slots=True)
class _Classes:
    """The motion classes of a domain and how each action maps to one."""

    domain: Domain[Any, Any]
    classes: tuple[MotionClass, ...]
    of_action: Mapping[Any, int]
    identity: frozenset[int]
    scale: int


_CLASS_CACHE: dict[str, _Classes] = {}


def motion_classes(domain: Domain[Any, Any]) -> tuple[MotionClass, ...]:
    """The domain's motion classes, in order of their first member in ``domain.actions``."""
    return _classes(domain).classes


def class_of(domain: Domain[Any, Any], action: Any) -> MotionClass:
    """The motion class ``action`` belongs to."""
    info = _classes(domain)
    return info.classes[info.of_action[action]]


def cost_scale(domain: Domain[Any, Any]) -> int:
    """The factor that turns every action cost of ``domain`` into an integer (search units)."""
    return _classes(domain).scale


def _classes(domain: Domain[Any, Any]) -> _Classes:
    cached = _CLASS_CACHE.get(domain.name)
    if cached is not None and cached.domain is domain:
        return cached
    start = domain.canonical
    by_key: dict[tuple[Any, frozenset[Cell]], list[Any]] = {}
    for action in domain.actions:
        key = (domain.apply(start, action), frozenset(domain.footprint(start, action)))
        by_key.setdefault(key, []).append(action)
    classes = tuple(
        MotionClass(i, domain.motion_class(members[0]), end, fp, tuple(members))
        for i, ((end, fp), members) in enumerate(by_key.items())
    )
    of_action = {a: c.index for c in classes for a in c.members}
    identity = frozenset(
        c.index for c in classes if c.end == start and c.footprint == frozenset({start.cell})
    )
    scale = math.lcm(*(domain.cost(a).denominator for a in domain.actions))
    built = _Classes(domain, classes, of_action, identity, scale)
    _CLASS_CACHE[domain.name] = built
    return built


# --- fault scopes and class costs -------------------------------------------------------------


def scope_fault_sets(domain: Domain[Any, Any], scope: str) -> tuple[frozenset[Any], ...]:
    """The domain's fault sets selected by ``scope``: all, singles, doubles or none."""
    if scope not in FAULT_SCOPES:
        raise ProblemError(
            f"unknown fault scope {scope!r}; expected one of {', '.join(FAULT_SCOPES)}"
        )
    if scope == "none":
        return ()
    if scope == "singles":
        return tuple(f for f in domain.fault_sets if len(f) == 1)
    if scope == "doubles":
        return tuple(f for f in domain.fault_sets if len(f) == 2)
    return tuple(domain.fault_sets)


ClassCost = tuple[int, int, Any]
"""(objective cost, duration, concrete action) of a class; costs scaled to integers."""


def class_costs(
    domain: Domain[Any, Any], allowed: Callable[[Any], bool], objective: str = "duration"
) -> dict[int, ClassCost]:
    """For each class with an allowed member, its cheapest allowed member and that member's cost.

    Costs are integers: durations multiplied by the least common multiple of the domain's cost
    denominators, so the search never touches fractions. With objective ``length`` every step costs
    one, and the member is still the fastest one.
    """
    info = _classes(domain)
    out: dict[int, ClassCost] = {}
    for motion in info.classes:
        best: tuple[int, Any] | None = None
        for action in motion.members:
            if not allowed(action):
                continue
            dur = int(domain.cost(action) * info.scale)
            if best is None or dur < best[0]:
                best = (dur, action)
        if best is not None:
            obj = best[0] if objective == "duration" else 1
            out[motion.index] = (obj, best[0], best[1])
    return out


# --- enumeration ------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Path:
    """A class sequence from the canonical state; ``cost``/``duration`` are scaled integers."""

    cost: int
    duration: int
    motions: tuple[int, ...]
    end: Any
    footprint: frozenset[Cell]

    def rank(self) -> tuple[int, int, int, int, tuple[int, ...]]:
        """Sort key: cheapest first, then fastest, shortest, fewest cells, class order."""
        return (self.cost, self.duration, len(self.motions), len(self.footprint), self.motions)


def _chebyshev(a: Cell, b: Cell) -> int:
    return max(abs(a[0] - b[0]), abs(a[1] - b[1]))


def enumerate_paths(
    domain: Domain[Any, Any],
    costs: Mapping[int, ClassCost],
    targets: Iterable[Any],
    max_length: int,
) -> dict[Any, list[Path]]:
    """Every non-dominated class sequence of at most ``max_length`` steps ending at a target.

    Breadth-first over lengths; a node is (end state, swept cells) and keeps only its cheapest
    sequence (ties: first found, i.e. shortest, then lowest class order). A wait class is used
    only as a whole sequence of its own, since a wait inside a longer sequence changes nothing
    but the cost. Returns, per target state, its sequences sorted by :meth:`Path.rank`.
    """
    info = _classes(domain)
    start = domain.canonical
    target_set = frozenset(targets)
    target_cells = {t.cell for t in target_set}
    reach = max((_chebyshev(c.end.cell, start.cell) for c in info.classes), default=0) or 1
    order = sorted(costs)
    step_cache: dict[tuple[Any, int], tuple[Any, frozenset[Cell]]] = {}

    def step(state: Any, ci: int) -> tuple[Any, frozenset[Cell]]:
        hit = step_cache.get((state, ci))
        if hit is None:
            action = costs[ci][2]
            hit = (domain.apply(state, action), frozenset(domain.footprint(state, action)))
            step_cache[(state, ci)] = hit
        return hit

    def near(cell: Cell, steps_left: int) -> bool:
        return any(_chebyshev(cell, t) <= steps_left * reach for t in target_cells)

    best: dict[tuple[Any, frozenset[Cell]], tuple[int, int]] = {}
    found: dict[tuple[Any, frozenset[Cell]], Path] = {}
    frontier: list[Path] = [Path(0, 0, (), start, frozenset({start.cell}))]
    for length in range(1, max_length + 1):
        nxt: list[Path] = []
        for path in frontier:
            for ci in order:
                if ci in info.identity and path.motions:
                    continue
                end, cells = step(path.end, ci)
                if not near(end.cell, max_length - length):
                    continue
                obj, dur, _ = costs[ci]
                new = Path(
                    path.cost + obj,
                    path.duration + dur,
                    (*path.motions, ci),
                    end,
                    path.footprint | cells,
                )
                key = (end, new.footprint)
                old = best.get(key)
                if old is not None and old <= (new.cost, new.duration):
                    continue
                best[key] = (new.cost, new.duration)
                if ci not in info.identity:
                    nxt.append(new)
                if end in target_set:
                    found[key] = new
        frontier = nxt
    out: dict[Any, list[Path]] = {t: [] for t in target_set}
    for (end, _), path in found.items():
        out[end].append(path)
    for paths in out.values():
        paths.sort(key=Path.rank)
    return out


def select_diverse(paths: Sequence[Path], base: frozenset[Cell], limit: int) -> list[Path]:
    """Up to ``limit`` paths, cheapest first, none of whose extra cells cover a kept one's.

    ``base`` is the replaced action's own footprint: those cells are free whenever the action is
    executable, so only the cells beyond it decide whether a candidate fits next to a wall.
    ``paths`` must be sorted by :meth:`Path.rank`.
    """
    kept: list[Path] = []
    extras: list[frozenset[Cell]] = []
    for path in paths:
        if len(kept) >= limit:
            break
        extra = path.footprint - base
        if any(e <= extra for e in extras):
            continue
        kept.append(path)
        extras.append(extra)
    return kept


# --- per fault set search, memoised by class-cost signature -----------------------------------


@dataclass(slots=True)
class _Searcher:
    """Runs :func:`enumerate_paths` once per distinct class-cost signature (many fault sets leave
    the same cheapest cost per class), and computes class costs once per fault set."""

    domain: Domain[Any, Any]
    objective: str
    max_length: int
    memo: dict[tuple[tuple[int, int, int], ...], dict[Any, list[Path]]]
    costs_memo: dict[Any, dict[int, ClassCost]]

    def costs(self, allowed: Callable[[Any], bool]) -> dict[int, ClassCost]:
        """Class costs with the actions ``allowed`` says are left (not memoised)."""
        return class_costs(self.domain, allowed, self.objective)

    def costs_under(self, faults: frozenset[Any]) -> dict[int, ClassCost]:
        """Class costs under a fault set, memoised."""
        hit = self.costs_memo.get(faults)
        if hit is None:
            hit = self.costs_memo[faults] = self.costs(lambda a: self.domain.available(a, faults))
        return hit

    def paths(self, costs: Mapping[int, ClassCost]) -> dict[Any, list[Path]]:
        """Every class's candidate sequences under ``costs`` (see :func:`enumerate_paths`)."""
        signature = tuple((ci, c[0], c[1]) for ci, c in sorted(costs.items()))
        hit = self.memo.get(signature)
        if hit is None:
            targets = [c.end for c in _classes(self.domain).classes]
            hit = enumerate_paths(self.domain, costs, targets, self.max_length)
            self.memo[signature] = hit
        return hit


def _concrete(path: Path, costs: Mapping[int, ClassCost]) -> tuple[Any, ...]:
    return tuple(costs[ci][2] for ci in path.motions)


# --- verification -----------------------------------------------------------------------------


def verify_entry(
    domain: Domain[Any, Any],
    action: Any,
    candidates: Iterable[tuple[Any, ...]],
    faults: frozenset[Any] | None = None,
) -> None:
    """Re-simulate every candidate: it must be non-empty, avoid ``action``, end where ``action``
    ends, and (for a fault-indexed entry) use only actions available under ``faults``.

    Raises :class:`TableError` naming the entry otherwise; the generator calls this on every
    entry before building the table, so a generator bug can never reach a file.
    """
    target = domain.apply(domain.canonical, action)
    name = domain.format_action(action)
    for k, candidate in enumerate(candidates):
        text = " ".join(domain.format_action(a) for a in candidate)
        where = f"generated entry {name}" + (
            "" if faults is None else f" under {domain.format_faults(faults)!r}"
        )
        if not candidate or action in candidate:
            raise TableError(
                f"{where}: candidate {k} [{text}] is empty or uses {name}", source="<generator>"
            )
        if run_open(domain, domain.canonical, candidate) != target:
            raise TableError(
                f"{where}: candidate {k} [{text}] does not end at {target}", source="<generator>"
            )
        if faults is not None and not all(domain.available(a, faults) for a in candidate):
            raise TableError(
                f"{where}: candidate {k} [{text}] uses a forbidden action", source="<generator>"
            )


# --- the two shapes ---------------------------------------------------------------------------


def _fault_indexed(
    domain: Domain[Any, Any], options: GenerateOptions, searcher: _Searcher
) -> list[TableEntry]:
    info = _classes(domain)
    entries: list[TableEntry] = []
    for faults in scope_fault_sets(domain, options.faults):
        costs = searcher.costs_under(faults)
        found = searcher.paths(costs)
        chosen: dict[int, tuple[tuple[Any, ...], ...]] = {}
        for action in domain.actions:
            if domain.available(action, faults):
                continue
            ci = info.of_action[action]
            if ci not in chosen:
                motion = info.classes[ci]
                kept = select_diverse(found[motion.end], motion.footprint, options.per_action)
                chosen[ci] = tuple(_concrete(p, costs) for p in kept)
            verify_entry(domain, action, chosen[ci], faults)
            entries.append(TableEntry(action=action, candidates=chosen[ci], faults=faults))
    return entries


@dataclass(frozen=True, slots=True)
class _Option:
    """A concrete candidate in the fault-agnostic pool with its usability bitmask."""

    actions: tuple[Any, ...]
    rank: tuple[int, int, int, int, tuple[str, ...]]
    usable: int
    extra: frozenset[Cell]


def _fault_agnostic(
    domain: Domain[Any, Any], options: GenerateOptions, searcher: _Searcher
) -> list[TableEntry]:
    info = _classes(domain)
    scope = scope_fault_sets(domain, options.faults)
    masks = {
        a: sum(1 << i for i, f in enumerate(scope) if domain.available(a, f))
        for a in domain.actions
    }
    full = (1 << len(scope)) - 1
    durations = {a: int(domain.cost(a) * info.scale) for a in domain.actions}
    entries: list[TableEntry] = []
    for action in domain.actions:
        motion = info.classes[info.of_action[action]]
        relevant = full & ~masks[action]
        situations = [
            searcher.costs_under(f) for i, f in enumerate(scope) if relevant >> i & 1
        ] or [searcher.costs(lambda a, x=action: a != x)]
        pool = _Pool(domain, options, action, motion.footprint, masks, durations, full, {}, {})
        for costs in situations:
            found = searcher.paths(costs)[motion.end]
            diverse = select_diverse(found, motion.footprint, options.per_action)
            for path in [*diverse, *found[: 2 * options.per_action]]:
                pool.paths.setdefault(path.motions, path)
                pool.add(_concrete(path, costs), path)
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
class _Pool:
    """The concrete candidates considered for one fault-agnostic entry.

    ``paths`` are the class sequences found under any fault set that disables the action (the
    diverse choice and the ``2 * per_action`` cheapest);
    ``options`` their concrete versions: the fastest under each such fault set, every member for
    one-step paths, and (added round by round in :func:`_greedy_cover`) the concrete version
    that stays usable under the most fault sets not yet covered.
    """

    domain: Domain[Any, Any]
    gen: GenerateOptions
    action: Any
    base: frozenset[Cell]
    masks: Mapping[Any, int]
    durations: Mapping[Any, int]
    full: int
    paths: dict[tuple[int, ...], Path]
    options: dict[tuple[Any, ...], _Option]
    members: dict[int, list[tuple[int, int, Any]]] = field(default_factory=dict)

    def add(self, concrete: tuple[Any, ...], path: Path) -> None:
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
        info = _classes(self.domain)
        if not self.members:
            for motion in info.classes:
                self.members[motion.index] = [
                    (self.masks[m], -self.durations[m], m)
                    for m in motion.members
                    if m != self.action
                ]
        for path in self.paths.values():
            usable = self.full
            concrete = []
            for ci in path.motions:
                members = self.members[ci]
                if not members:
                    break
                best_key: tuple[int, int, int] | None = None
                pick = None
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
    domain: Domain[Any, Any], concrete: tuple[Any, ...], path: Path, options: GenerateOptions
) -> tuple[int, int, int, int, tuple[str, ...]]:
    scale = _classes(domain).scale
    duration = sum(int(domain.cost(a) * scale) for a in concrete)
    cost = duration if options.objective == "duration" else len(concrete)
    names = tuple(domain.format_action(a) for a in concrete)
    return (cost, duration, len(concrete), len(path.footprint), names)


_UNUSABLE = np.iinfo(np.int64).max // 4

Value = tuple[int, int, int]
"""(fault sets covered, minus the summed cost of the cheapest usable candidate under each covered
fault set, fault sets with a usable candidate that fits wherever the action does); with priority
``walls`` the last two swap places."""


@dataclass(frozen=True, slots=True)
class _Matrices:
    """Per option (row) and fault set (column): its cost where usable, and whether it is usable
    and sweeps no cell beyond the replaced action's own (so it fits wherever the action fits)."""

    cost: npt.NDArray[np.int64]
    safe: npt.NDArray[np.bool_]
    walls_first: bool

    @staticmethod
    def build(
        ranked: Sequence[_Option],
        bits: Sequence[int],
        no_faults: bool,
        walls_first: bool,
        rows: dict[tuple[Any, ...], tuple[Any, Any]],
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


def _greedy_cover(pool: _Pool, relevant: int, limit: int, *, no_faults: bool) -> list[_Option]:
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
    chosen: list[_Option] = []
    current: Value = (0, 0, 0)
    walls_first = pool.gen.priority == "walls"
    rows: dict[tuple[Any, ...], tuple[Any, Any]] = {}
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
    chosen: list[_Option], ranked: Sequence[_Option], matrices: _Matrices, current: Value
) -> list[_Option]:
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
    chosen: list[_Option], ranked: Sequence[_Option], relevant: int, limit: int, *, no_faults: bool
) -> list[_Option]:
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


def generate_table(
    options: GenerateOptions | None = None, domain: Domain[Any, Any] | None = None
) -> ReplacementTable:
    """Generate a replacement table (see the module docstring); deterministic in ``options``."""
    options = options or GenerateOptions()
    dom = domain if domain is not None else get_domain(options.domain)
    searcher = _Searcher(dom, options.objective, options.max_length, {}, {})
    if options.shape == "fault-indexed":
        entries = _fault_indexed(dom, options, searcher)
    else:
        entries = _fault_agnostic(dom, options, searcher)
    return ReplacementTable(
        domain=dom.name,
        shape=options.shape,
        made_by="generator",
        entries=tuple(entries),
        parameters=options.parameters(),
        source="<generator>",
    )


def candidate_cost(domain: Domain[Any, Any], candidate: Iterable[Any], objective: str) -> Fraction:
    """A candidate's exact cost under ``objective``: total duration, or number of actions."""
    actions = tuple(candidate)
    if objective == "length":
        return Fraction(len(actions))
    return sum((domain.cost(a) for a in actions), Fraction(0))
