"""How good is a replacement table? Coverage and optimality against an exact ground truth.

**Ground truth** (:mod:`selfrepair.repair.optimum`): for a fault set, the cheapest replacement
of a disabled action in free space with the actions that are left, with no length limit, and an
exact test of whether one exists at all.

**Table coverage** (:func:`coverage_report`). For every fault set in scope and every action it
disables: does the run-time machinery (:func:`selfrepair.repair.replacement.find_replacement` in the
chosen recursion mode, in free space) find a replacement from the table, and how far is the
cost of the replacement it picks above the optimum. Next to walls (:func:`wall_coverage`, flat
mode): over every free cell and heading of a maze, the share of (pose, fault set, disabled
action) triples whose action is executable there (and replaceable in free space) but for which no
candidate whose actions are all available fits (every swept cell free).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from fractions import Fraction
from typing import Protocol, cast

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import TableError
from selfrepair.geometry import Cell, Heading, Pose, relative_cell
from selfrepair.repair.optimum import (
    compose,
    effect,
    inverse,
    optimal_replacements,
    reachable,
)
from selfrepair.repair.replacement import find_replacement
from selfrepair.robots.domain import A, Domain, F
from selfrepair.tables.enumerate import (
    Objective,
    candidate_cost,
    scope_fault_sets,
)
from selfrepair.tables.model import ReplacementTable
from selfrepair.textio import JSONObject, JSONValue


class WallGrid(Protocol):
    """What wall coverage needs of a map: its walls as a boolean ``[y, x]`` array and a name
    (a :class:`selfrepair.world.maze.Maze` is one)."""

    @property
    def walls(self) -> npt.NDArray[np.bool_]: ...

    @property
    def name(self) -> str: ...


__all__ = [
    "CoverageReport",
    "FaultRow",
    "PairResult",
    "WallRow",
    "compose",
    "coverage_report",
    "effect",
    "free_space",
    "free_space_rows",
    "inverse",
    "optimal_replacements",
    "reachable",
    "wall_coverage",
]

# --- free-space coverage ----------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class FaultRow:
    """Free-space coverage of one fault set.

    ``disabled``: actions the fault set disables; ``replaceable``: those with a replacement at
    all (ground truth); ``covered``: those the table replaces; ``optimal``: covered ones whose
    picked replacement costs exactly the optimum; ``excess_sum``/``excess_max``: how far the
    picked replacements cost above the optimum, relative (cost / optimum - 1).
    """

    faults: str
    disabled: int
    replaceable: int
    covered: int
    optimal: int
    excess_sum: Fraction
    excess_max: Fraction


@dataclass(frozen=True, slots=True)
class PairResult:
    """One (fault set, disabled action) pair in free space: the exact optimum (``None``: no
    replacement exists), and the replacement the table yields (``None``: none) with its cost,
    the index of its candidate in the looked-up list and its recursion depth."""

    faults: str
    action: str
    optimum: Fraction | None
    cost: Fraction | None
    candidate: int | None
    depth: int | None
    actions: tuple[str, ...]

    def to_json(self) -> JSONObject:
        """JSON-ready (fractions as strings)."""
        return {
            "faults": self.faults,
            "action": self.action,
            "optimum": None if self.optimum is None else str(self.optimum),
            "cost": None if self.cost is None else str(self.cost),
            "excess": (
                None if self.cost is None or not self.optimum else str(self.cost / self.optimum - 1)
            ),
            "candidate": self.candidate,
            "depth": self.depth,
            "actions": list(self.actions),
        }


@dataclass(frozen=True, slots=True)
class WallRow:
    """Coverage next to walls on one maze: ``pairs`` executable (pose, fault set, disabled
    action) triples whose action is replaceable in free space, ``uncovered`` those where no
    usable candidate fits."""

    maze: str
    pairs: int
    uncovered: int

    @property
    def share(self) -> float:
        """Uncovered share of the pairs (0 when there are none)."""
        return self.uncovered / self.pairs if self.pairs else 0.0


@dataclass(frozen=True, slots=True)
class CoverageReport:
    """Everything :func:`coverage_report` measures about one table."""

    table: str
    shape: str
    made_by: str
    objective: str
    mode: str
    scope: str
    rows: tuple[FaultRow, ...]
    walls: tuple[WallRow, ...]
    pairs: tuple[PairResult, ...] = ()

    def totals(self) -> JSONObject:
        """Sums over fault sets and mazes, with the headline shares (``None`` where the
        denominator is zero: nothing replaceable, nothing covered, no wall pairs)."""
        disabled = sum(r.disabled for r in self.rows)
        replaceable = sum(r.replaceable for r in self.rows)
        covered = sum(r.covered for r in self.rows)
        optimal = sum(r.optimal for r in self.rows)
        excess = sum((r.excess_sum for r in self.rows), Fraction(0))
        pairs = sum(w.pairs for w in self.walls)
        uncovered = sum(w.uncovered for w in self.walls)
        return {
            "fault_sets": len(self.rows),
            "disabled": disabled,
            "replaceable": replaceable,
            "covered": covered,
            "coverage": covered / replaceable if replaceable else None,
            "optimal": optimal,
            "optimal_share": optimal / covered if covered else None,
            "mean_excess": float(excess / covered) if covered else None,
            "max_excess": float(max((r.excess_max for r in self.rows), default=Fraction(0))),
            "fault_sets_fully_covered": sum(r.covered == r.replaceable for r in self.rows),
            "wall_pairs": pairs,
            "wall_uncovered": uncovered,
            "wall_uncovered_share": uncovered / pairs if pairs else None,
        }

    def to_json(self) -> JSONObject:
        """A JSON-ready dictionary (fractions as strings)."""
        rows: list[JSONValue] = []
        for r in self.rows:
            row = asdict(r)
            row["excess_sum"] = str(r.excess_sum)
            row["excess_max"] = str(r.excess_max)
            rows.append(row)
        walls: list[JSONValue] = [{**asdict(w), "share": w.share} for w in self.walls]
        return {
            "table": self.table,
            "shape": self.shape,
            "made_by": self.made_by,
            "objective": self.objective,
            "mode": self.mode,
            "faults": self.scope,
            "totals": self.totals(),
            "fault_sets": rows,
            "walls": walls,
            "pairs": [p.to_json() for p in self.pairs],
        }


def free_space_rows(
    table: ReplacementTable[A, F],
    fault_sets: Sequence[frozenset[F]],
    objective: str = "duration",
    mode: str = "flat",
) -> tuple[FaultRow, ...]:
    """One :class:`FaultRow` per fault set (see :func:`coverage_report`)."""
    return free_space(table, fault_sets, objective, mode)[0]


def free_space(
    table: ReplacementTable[A, F],
    fault_sets: Sequence[frozenset[F]],
    objective: str = "duration",
    mode: str = "flat",
) -> tuple[tuple[FaultRow, ...], tuple[PairResult, ...]]:
    """Per fault set a :class:`FaultRow`, and per (fault set, disabled action) a
    :class:`PairResult`."""
    dom = table.domain
    rows = []
    pairs = []
    for faults in fault_sets:
        fault_text = dom.format_faults(faults)
        optimum = optimal_replacements(dom, faults, objective)
        replaceable = covered = optimal = 0
        excess_sum = excess_max = Fraction(0)
        for action, best in optimum.items():
            if best is not None:
                replaceable += 1
            found = find_replacement(
                table, action, dom.canonical, faults, lambda cells: True, mode=mode
            )
            name = dom.format_action(action)
            if found is None:
                pairs.append(PairResult(fault_text, name, best, None, None, None, ()))
                continue
            if best is None:
                raise AssertionError(
                    f"table replaces {name} under {fault_text!r}, which the ground truth "
                    "calls impossible"
                )
            actions = cast("tuple[A, ...]", found.actions)  # the table's own actions
            cost = candidate_cost(dom, actions, objective)
            pairs.append(
                PairResult(
                    fault_text,
                    name,
                    best,
                    cost,
                    found.position,
                    found.depth,
                    tuple(dom.format_action(a) for a in actions),
                )
            )
            covered += 1
            excess = cost / best - 1
            optimal += excess == 0
            excess_sum += excess
            excess_max = max(excess_max, excess)
        rows.append(
            FaultRow(
                fault_text,
                len(optimum),
                replaceable,
                covered,
                optimal,
                excess_sum,
                excess_max,
            )
        )
    return tuple(rows), tuple(pairs)


# --- coverage next to walls -------------------------------------------------------------------


def _offsets(domain: Domain[A, F], candidate: Sequence[A]) -> frozenset[tuple[int, int]]:
    """The cells a sequence sweeps from the canonical state, as (forward, right) offsets."""
    start: Pose = domain.canonical
    state, cells = start, set[Cell]()
    for action in candidate:
        cells.update(domain.footprint(state, action))
        state = domain.apply(state, action)
    out = set()
    for cell in cells:
        e = effect(start, Pose(cell[0], cell[1], start.heading))
        out.add((e[0], e[1]))
    return frozenset(out)


@dataclass(slots=True)
class _MaskCache:
    """Boolean masks "this footprint fits at (x, y) facing h" for one maze, memoised."""

    free: npt.NDArray[np.bool_]
    margin: int
    masks: dict[tuple[int, frozenset[tuple[int, int]]], npt.NDArray[np.bool_]]

    def fits(self, heading: int, offsets: frozenset[tuple[int, int]]) -> npt.NDArray[np.bool_]:
        key = (heading, offsets)
        hit = self.masks.get(key)
        if hit is None:
            h, w = self.free.shape[0] - 2 * self.margin, self.free.shape[1] - 2 * self.margin
            hit = np.ones((h, w), dtype=bool)
            probe = Pose(0, 0, _HEADINGS[heading])
            for f, lat in offsets:
                dx, dy = relative_cell(probe, f, lat)
                m = self.margin
                hit &= self.free[m + dy : m + dy + h, m + dx : m + dx + w]
            self.masks[key] = hit
        return hit


_HEADINGS = tuple(Heading)


_OPTIMA: BoundedCache[tuple[object, frozenset[object]], object] = BoundedCache(
    "exact optimal replacements", 256, kind=CacheKind.REPAIR
)


def _optimum_cached(domain: Domain[A, F], faults: frozenset[F]) -> dict[A, Fraction | None]:
    optima = _OPTIMA.get((domain, faults), lambda: optimal_replacements(domain, faults))
    return cast("dict[A, Fraction | None]", optima)  # keyed by the domain: its actions


def wall_coverage(
    table: ReplacementTable[A, F],
    maze: WallGrid,
    fault_sets: Sequence[frozenset[F]],
    name: str = "",
) -> WallRow:
    """Coverage next to walls (flat mode) over every free cell and heading of ``maze``.

    Counts the (pose, fault set, disabled action) triples where the action is executable and has
    a replacement in free space (the ground truth), and those among them where no candidate whose
    actions are all available fits. Whether some replacement exists at that very pose (say, one
    that leaves the corridor and comes back) is not asked: that would need a search per pose.
    """
    dom = table.domain
    fp_cache: dict[tuple[A, ...], frozenset[tuple[int, int]]] = {}

    def offsets(seq: tuple[A, ...]) -> frozenset[tuple[int, int]]:
        hit = fp_cache.get(seq)
        if hit is None:
            hit = fp_cache[seq] = _offsets(dom, seq)
        return hit

    groups: dict[
        tuple[frozenset[tuple[int, int]], tuple[frozenset[tuple[int, int]], ...]], int
    ] = {}
    for faults in fault_sets:
        optimum = _optimum_cached(dom, faults)
        for action in dom.actions:
            if dom.available(action, faults) or optimum[action] is None:
                continue
            usable = tuple(
                sorted(
                    {
                        offsets(c)
                        for c in table.candidates(action, faults)
                        if action not in c and all(dom.available(b, faults) for b in c)
                    },
                    key=sorted,
                )
            )
            key = (offsets((action,)), usable)
            groups[key] = groups.get(key, 0) + 1
    all_offsets = [o for key in groups for o in (key[0], *key[1])]
    margin = max((max(abs(f), abs(lat)) for o in all_offsets for f, lat in o), default=0) + 1
    walls = np.asarray(maze.walls, dtype=bool)
    free = np.pad(~walls, margin, constant_values=False)
    cache = _MaskCache(free, margin, {})
    pairs = uncovered = 0
    for (own, usable), weight in groups.items():
        for heading in range(4):
            executable = cache.fits(heading, own)
            covered = np.zeros_like(executable)
            for o in usable:
                covered |= cache.fits(heading, o)
            pairs += weight * int(executable.sum())
            uncovered += weight * int((executable & ~covered).sum())
    return WallRow(name or maze_name(maze), pairs, uncovered)


def maze_name(maze: WallGrid) -> str:
    """A maze's name, or ``"<maze>"``."""
    return str(getattr(maze, "name", "") or "<maze>")


def coverage_report(
    table: ReplacementTable[A, F],
    *,
    faults: str = "all",
    objective: str | None = None,
    mode: str = "flat",
    mazes: Iterable[tuple[str, WallGrid]] = (),
    label: str = "",
) -> CoverageReport:
    """Free-space coverage and optimality for every fault set in scope ``faults``, and wall
    coverage on each of ``mazes``. ``objective`` defaults to the table's own (its header
    ``parameters``), else ``duration``."""
    dom = table.domain
    objective = objective or str(table.parameters.get("objective", "duration"))
    if objective not in set(Objective):
        raise TableError(
            f"expected an objective from {', '.join(Objective)}, got {objective!r}",
            source=table.source,
        )
    fault_sets = scope_fault_sets(dom, faults)
    rows, pairs = free_space(table, fault_sets, objective, mode)
    walls = tuple(wall_coverage(table, maze, fault_sets, name) for name, maze in mazes)
    return CoverageReport(
        label or table.source,
        table.shape,
        table.made_by,
        objective,
        mode,
        faults,
        rows,
        walls,
        pairs,
    )
