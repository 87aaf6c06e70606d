"""Automatic replacement tables: enumerate sub-plans in free space and keep the useful ones.

The original work found hand-written tables slow to write, error-prone and full of gaps; this
module writes them from the domain model alone, for any :class:`~selfrepair.robots.domain.Domain`.

How it works:

1. **Motion classes.** Actions with the same open-plane effect and the same footprint from the
   canonical state form one class (the four-wheel robot's 81 actions fall into the 9 motions of
   :data:`selfrepair.robots.four_wheel.MOTIONS`; the three-action robot's into 3). Under a fault
   set each class costs as much as its cheapest available member, and that member (first in
   domain order on ties, as :func:`selfrepair.robots.domain.primitive_by_motion` picks) is the
   concrete action written.
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

The code is split in three: :mod:`selfrepair.tables.enumerate` (motion classes, class costs,
enumeration, verification), :mod:`selfrepair.tables.cover` (the fault-agnostic choice) and this
module (options, the fault-indexed shape, :func:`generate_table`).

Every entry is re-simulated (:func:`verify_entry`) before the table is built, and the table
value re-simulates it once more when constructed. Generation is deterministic: same options, same
bytes from :func:`selfrepair.tables.fileformat.dump_table`.
"""

from __future__ import annotations

from selfrepair.robots.domain import A, Domain, F
from selfrepair.tables.cover import fault_agnostic_entries
from selfrepair.tables.enumerate import (
    FaultScope,
    MotionClass,
    Objective,
    Path,
    Searcher,
    candidate_cost,
    class_costs,
    class_of,
    concrete_actions,
    cost_scale,
    domain_classes,
    enumerate_paths,
    motion_classes,
    scope_fault_sets,
    select_diverse,
    verify_entry,
)
from selfrepair.tables.model import (
    GenerateOptions,
    MadeBy,
    ReplacementTable,
    TableEntry,
    TableShape,
)

GENERATOR_SOURCE = "<generator>"
"""The source of a generated table (its :attr:`~selfrepair.tables.model.ReplacementTable.source`
and its label in traces and rows)."""

__all__ = [
    "GENERATOR_SOURCE",
    "FaultScope",
    "GenerateOptions",
    "MotionClass",
    "Objective",
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


# --- the two shapes ---------------------------------------------------------------------------


def _fault_indexed(
    domain: Domain[A, F], options: GenerateOptions, searcher: Searcher[A, F]
) -> list[TableEntry[A, F]]:
    info = domain_classes(domain)
    entries: list[TableEntry[A, F]] = []
    for faults in scope_fault_sets(domain, options.faults):
        costs = searcher.costs_under(faults)
        found = searcher.paths(costs)
        chosen: dict[int, tuple[tuple[A, ...], ...]] = {}
        for action in domain.actions:
            if domain.available(action, faults):
                continue
            ci = info.of_action[action]
            if ci not in chosen:
                motion = info.classes[ci]
                kept = select_diverse(found[motion.end], motion.footprint, options.per_action)
                chosen[ci] = tuple(concrete_actions(p, costs) for p in kept)
            verify_entry(domain, action, chosen[ci], faults)
            entries.append(TableEntry(action=action, candidates=chosen[ci], faults=faults))
    return entries


def generate_table(
    domain: Domain[A, F], options: GenerateOptions | None = None
) -> ReplacementTable[A, F]:
    """Generate a replacement table for ``domain`` (see the module docstring); deterministic in
    the domain and ``options``."""
    options = options or GenerateOptions()
    searcher = Searcher(domain, options.objective, options.max_length, {}, {})
    if options.shape is TableShape.FAULT_INDEXED:
        entries = _fault_indexed(domain, options, searcher)
    else:
        entries = fault_agnostic_entries(domain, options, searcher)
    return ReplacementTable(
        domain=domain,
        shape=options.shape,
        made_by=MadeBy.GENERATOR,
        entries=tuple(entries),
        parameters=options.parameters(),
        source=GENERATOR_SOURCE,
    )
