"""The search half of table generation: motion classes, class costs under a fault set, and
breadth-first enumeration of candidate sub-plans from the canonical state in free space.

:mod:`selfrepair.tables.generate` explains the method and builds tables from these pieces;
:mod:`selfrepair.repair.coverage` uses the same classes and costs for its ground truth, so the
generator and the report that judges it agree on what an action costs.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction
from typing import Generic, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import TableError, choice
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import A, Domain, F, run_open

__all__ = [
    "ClassCost",
    "DomainClasses",
    "FaultScope",
    "MotionClass",
    "Objective",
    "Path",
    "Searcher",
    "candidate_cost",
    "class_costs",
    "class_of",
    "concrete_actions",
    "cost_scale",
    "domain_classes",
    "enumerate_paths",
    "motion_classes",
    "scope_fault_sets",
    "select_diverse",
    "verify_entry",
]


class FaultScope(StrEnum):
    """Which fault sets of the domain a table is made for (or measured on)."""

    ALL = "all"
    SINGLES = "singles"
    DOUBLES = "doubles"
    NONE = "none"


class Objective(StrEnum):
    """What a candidate's cost is: total duration in ticks, or number of actions."""

    DURATION = "duration"
    LENGTH = "length"


# --- motion classes ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class MotionClass(Generic[A]):
    """Actions with one effect: ``end`` and ``footprint`` are taken from the canonical state."""

    index: int
    name: str
    end: Pose
    footprint: frozenset[Cell]
    members: tuple[A, ...]


@dataclass(frozen=True, slots=True)
class DomainClasses(Generic[A, F]):
    """The motion classes of a domain and how each action maps to one."""

    domain: Domain[A, F]
    classes: tuple[MotionClass[A], ...]
    of_action: Mapping[A, int]
    identity: frozenset[int]
    scale: int


_CLASSES: BoundedCache[object, object] = BoundedCache(
    "domain motion classes", 16, kind=CacheKind.REPAIR
)


def motion_classes(domain: Domain[A, F]) -> tuple[MotionClass[A], ...]:
    """The domain's motion classes, in order of their first member in ``domain.actions``."""
    return domain_classes(domain).classes


def class_of(domain: Domain[A, F], action: A) -> MotionClass[A]:
    """The motion class ``action`` belongs to."""
    info = domain_classes(domain)
    return info.classes[info.of_action[action]]


def cost_scale(domain: Domain[A, F]) -> int:
    """The factor that turns every action cost of ``domain`` into an integer (search units)."""
    return domain_classes(domain).scale


def domain_classes(domain: Domain[A, F]) -> DomainClasses[A, F]:
    """The domain's actions grouped by effect from the canonical state (computed once per
    domain)."""
    # keyed by the domain itself, so the value is that domain's classes
    return cast("DomainClasses[A, F]", _CLASSES.get(domain, lambda: _classes(domain)))


def _classes(domain: Domain[A, F]) -> DomainClasses[A, F]:
    start = domain.canonical
    by_key: dict[tuple[Pose, frozenset[Cell]], list[A]] = {}
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
    return DomainClasses(domain, classes, of_action, identity, domain.time_unit)


# --- fault scopes and class costs -------------------------------------------------------------


def scope_fault_sets(domain: Domain[A, F], scope: str) -> tuple[frozenset[F], ...]:
    """The domain's fault sets selected by ``scope``: all, singles, doubles or none."""
    selected = choice(FaultScope, scope, "fault scope")
    if selected is FaultScope.NONE:
        return ()
    if selected is FaultScope.SINGLES:
        return tuple(f for f in domain.fault_sets if len(f) == 1)
    if selected is FaultScope.DOUBLES:
        return tuple(f for f in domain.fault_sets if len(f) == 2)
    return tuple(domain.fault_sets)


ClassCost = tuple[int, int, A]
"""(objective cost, duration, concrete action) of a class; costs scaled to integers."""


def class_costs(
    domain: Domain[A, F], allowed: Callable[[A], bool], objective: str = "duration"
) -> dict[int, ClassCost[A]]:
    """For each class with an allowed member, its cheapest allowed member and that member's cost.

    Costs are integers: durations multiplied by the least common multiple of the domain's cost
    denominators, so the search never touches fractions. With objective ``length`` every step costs
    one, and the member is still the fastest one.
    """
    info = domain_classes(domain)
    out: dict[int, ClassCost[A]] = {}
    for motion in info.classes:
        best: tuple[int, A] | None = None
        for action in motion.members:
            if not allowed(action):
                continue
            dur = int(domain.duration(action) * info.scale)
            if best is None or dur < best[0]:
                best = (dur, action)
        if best is not None:
            obj = best[0] if objective == Objective.DURATION else 1
            out[motion.index] = (obj, best[0], best[1])
    return out


# --- enumeration ------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Path:
    """A class sequence from the canonical state; ``cost``/``duration`` are scaled integers."""

    cost: int
    duration: int
    motions: tuple[int, ...]
    end: Pose
    footprint: frozenset[Cell]

    def rank(self) -> tuple[int, int, int, int, tuple[int, ...]]:
        """Sort key: cheapest first, then fastest, shortest, fewest cells, class order."""
        return (self.cost, self.duration, len(self.motions), len(self.footprint), self.motions)


def _chebyshev(a: Cell, b: Cell) -> int:
    return max(abs(a[0] - b[0]), abs(a[1] - b[1]))


def enumerate_paths(
    domain: Domain[A, F],
    costs: Mapping[int, ClassCost[A]],
    targets: Iterable[Pose],
    max_length: int,
) -> dict[Pose, list[Path]]:
    """Every non-dominated class sequence of at most ``max_length`` steps ending at a target.

    Breadth-first over lengths; a node is (end state, swept cells) and keeps only its cheapest
    sequence (ties: first found, i.e. shortest, then lowest class order). A wait class is used
    only as a whole sequence of its own, since a wait inside a longer sequence changes nothing
    but the cost. Returns, per target state, its sequences sorted by :meth:`Path.rank`.
    """
    info = domain_classes(domain)
    start = domain.canonical
    target_set = frozenset(targets)
    target_cells = {t.cell for t in target_set}
    reach = max((_chebyshev(c.end.cell, start.cell) for c in info.classes), default=0) or 1
    order = sorted(costs)
    step_cache: dict[tuple[Pose, int], tuple[Pose, frozenset[Cell]]] = {}

    def step(state: Pose, ci: int) -> tuple[Pose, frozenset[Cell]]:
        hit = step_cache.get((state, ci))
        if hit is None:
            action = costs[ci][2]
            hit = (domain.apply(state, action), frozenset(domain.footprint(state, action)))
            step_cache[(state, ci)] = hit
        return hit

    def near(cell: Cell, steps_left: int) -> bool:
        return any(_chebyshev(cell, t) <= steps_left * reach for t in target_cells)

    best: dict[tuple[Pose, frozenset[Cell]], tuple[int, int]] = {}
    found: dict[tuple[Pose, frozenset[Cell]], Path] = {}
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
    out: dict[Pose, list[Path]] = {t: [] for t in target_set}
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
class Searcher(Generic[A, F]):
    """Runs :func:`enumerate_paths` once per distinct class-cost signature (many fault sets leave
    the same cheapest cost per class), and computes class costs once per fault set."""

    domain: Domain[A, F]
    objective: str
    max_length: int
    memo: dict[tuple[tuple[int, int, int], ...], dict[Pose, list[Path]]]
    costs_memo: dict[frozenset[F], dict[int, ClassCost[A]]]

    def costs(self, allowed: Callable[[A], bool]) -> dict[int, ClassCost[A]]:
        """Class costs with the actions ``allowed`` says are left (not memoised)."""
        return class_costs(self.domain, allowed, self.objective)

    def costs_under(self, faults: frozenset[F]) -> dict[int, ClassCost[A]]:
        """Class costs under a fault set, memoised."""
        hit = self.costs_memo.get(faults)
        if hit is None:
            hit = self.costs_memo[faults] = self.costs(lambda a: self.domain.available(a, faults))
        return hit

    def paths(self, costs: Mapping[int, ClassCost[A]]) -> dict[Pose, list[Path]]:
        """Every class's candidate sequences under ``costs`` (see :func:`enumerate_paths`)."""
        signature = tuple((ci, c[0], c[1]) for ci, c in sorted(costs.items()))
        hit = self.memo.get(signature)
        if hit is None:
            targets = [c.end for c in domain_classes(self.domain).classes]
            hit = enumerate_paths(self.domain, costs, targets, self.max_length)
            self.memo[signature] = hit
        return hit


def concrete_actions(path: Path, costs: Mapping[int, ClassCost[A]]) -> tuple[A, ...]:
    return tuple(costs[ci][2] for ci in path.motions)


# --- verification -----------------------------------------------------------------------------


def verify_entry(
    domain: Domain[A, F],
    action: A,
    candidates: Iterable[tuple[A, ...]],
    faults: frozenset[F] | None = None,
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


def candidate_cost(domain: Domain[A, F], candidate: Iterable[A], objective: str) -> Fraction:
    """A candidate's exact cost under ``objective``: total duration, or number of actions."""
    actions = tuple(candidate)
    if objective == Objective.LENGTH:
        return Fraction(len(actions))
    return sum((domain.duration(a) for a in actions), Fraction(0))
