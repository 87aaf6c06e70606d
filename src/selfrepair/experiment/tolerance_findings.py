"""Finding 2 restated on the exact basis: planning for tolerance against planning for clearance.

Finding 2 asks whether keeping plans off walls (a clearance weight) raises the missions completed
without a replan. The exact question is whether the plan is tolerant of the faults that may
appear (:mod:`selfrepair.repair.tolerance`). Finding **2t** compares, per replacement variant
(table, recursion mode) and tolerant objective, the robot whose first plan the tolerant planner
made (clearance weight 0) with the same variant planned for clearance at the highest weight
the rows hold. The comparison is paired over situations (maze, route, faults, fault step),
by missions completed without a replan, with the rule of :mod:`selfrepair.experiment.findings`
(sign test, 95% interval of the paired difference; HELD / NOT HELD / INCONCLUSIVE). The price of
each, in ticks to the goal over the w=0 optimum, is stated next to it, and so are the comparisons
with the lower weights (as evidence, not counted).
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Sequence
from fractions import Fraction

from selfrepair.experiment.summary import Row
from selfrepair.experiment.variants import variant_label
from selfrepair.experiment.verdicts import (
    PAIRED,
    Comparison,
    Finding,
    compare,
    is_replacement,
    is_rewrite,
    is_tolerant,
    judge,
    pair_up,
    tick_cost,
    weight_of,
)

__all__ = ["base_variant", "tolerance_findings"]


def base_variant(row: Row) -> str:
    """The row's variant without its tolerant objective: ``replacement[handwritten,flat,tolerant
    k=1]`` becomes ``replacement[handwritten,flat]``. Read from the ``base_variant`` column (rows
    stored before that column existed: made from the strategy and options of the mission's
    stored configuration), never from the variant label's text."""
    column = row.get("base_variant")
    if column is not None:
        return str(column)
    settings = json.loads(str(row.get("config") or "{}"))
    options = settings.get("options")
    if "strategy" not in settings or not isinstance(options, dict):
        return str(row.get("variant") or "")
    plain = {k: v for k, v in options.items() if k != "objective"}
    return variant_label(str(settings["strategy"]), plain)


def tolerance_findings(rows: Sequence[Row]) -> list[Finding]:
    """Finding 2t when ``rows`` hold missions planned by the tolerant planner (else none)."""
    replacing = [r for r in rows if is_replacement(r) and not is_rewrite(r)]
    tolerant: dict[tuple[str, str], list[Row]] = defaultdict(list)
    clearance: dict[str, dict[Fraction, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for r in replacing:
        if is_tolerant(r):
            if weight_of(r) == 0:
                tolerant[base_variant(r), str(r.get("objective"))].append(r)
        else:
            clearance[str(r.get("variant"))][weight_of(r)].append(r)
    if not tolerant:
        return []
    judged: list[Comparison] = []
    extra: list[str] = []
    for (base, objective), group in sorted(tolerant.items()):
        weights = clearance.get(base, {})
        top = max(weights, default=Fraction(0))
        if top == 0:
            continue
        judged.append(compare(f"{base} {objective} vs w={top}", pair_up(weights[top], group)))
        for weight in sorted(w for w in weights if 0 < w < top):
            found = compare(f"{base} {objective} vs w={weight}", pair_up(weights[weight], group))
            extra.append(f"For comparison, {found.line()}")
        if 0 in weights:
            extra.append(tick_cost(f"{base} {objective}", pair_up(weights[Fraction(0)], group)))
            extra.append(tick_cost(f"{base} w={top}", pair_up(weights[Fraction(0)], weights[top])))
    missing = (
        "No variant run with a tolerant objective is also run at a clearance weight above 0, "
        "so tolerance cannot be compared with clearance."
    )
    return [judge("2t", judged, PAIRED, [line for line in extra if line], missing=missing)]
