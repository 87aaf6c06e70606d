"""The findings of a changing world (``experiment dynamic``, :mod:`selfrepair.world.events`).

Three claims, each judged per (maze, fault set) group (where it holds) and over all groups with
:func:`~selfrepair.experiment.verdicts.ratio_outcome`, on missions paired by situation (maze,
route, faults, world rate and sensing, replicate: the same obstacles for every strategy):

``D1``
    Local detours answer faster than A* replanning from scratch: the paired ratio of the
    per-mission median repair latency (the robot's response time), replacing robot over
    replanner, lies below 1 (its median with a 95% bootstrap interval). Missions where either
    robot made no repair are left out.
``D2``
    Local detours answer faster than D* Lite kept between changes (the same ratio against
    ``dstar-lite``).
``D3``
    D* Lite answers faster than A* from scratch in a changing world (its home ground).
``D4``
    Local detours answer faster than LPG-adapt (AI planning's plan repair, told the
    believed-blocked cells), judged only where LPG-adapt ran (the mazes it can take).
``D1r``, ``D2r``
    D1 and D2 for the replacing robot that rewrites the whole plan (``rewrite``: one repair
    replaces every blocked window ahead by its detour), judged only when there are such rows.
    D1 and D2 leave the rewriting robot out, so the two are never mixed in one pairing.

With each comparison the plan-quality price is stated: the paired difference in ticks to the
goal (mean with its interval, over pairs where both reached it), and the missions each robot
completed without a replan.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Sequence

from selfrepair.experiment.summary import Row, num
from selfrepair.experiment.verdicts import (
    Finding,
    Outcome,
    combine,
    is_rewrite,
    ratio_outcome,
    situation,
    succeeded,
)
from selfrepair.repair.strategies import StrategyName
from selfrepair.stats import bootstrap_interval

__all__ = ["CLAIMS", "dynamic_findings"]

CLAIMS = {
    "D1": "in a changing world, local detours answer faster than A* replanning from scratch "
    "(paired ratio of the response time below 1)",
    "D2": "in a changing world, local detours answer faster than D* Lite kept between "
    "changes (paired ratio of the response time below 1)",
    "D3": "in a changing world, D* Lite kept between changes answers faster than A* "
    "replanning from scratch (paired ratio of the response time below 1)",
    "D4": "in a changing world, local detours answer faster than LPG-adapt's plan repair "
    "(paired ratio of the response time below 1)",
    "D1r": "in a changing world, local detours with whole-plan rewriting answer faster than A* "
    "replanning from scratch (paired ratio of the response time below 1)",
    "D2r": "in a changing world, local detours with whole-plan rewriting answer faster than "
    "D* Lite kept between changes (paired ratio of the response time below 1)",
}
"""The claims of the changing world's findings."""

INTRO = (
    "Response time (median repair latency per mission), paired ratio candidate / baseline, "
    "median with 95% interval, per maze and fault set (every world rate):"
)


def _is(strategy: StrategyName, rewrite: bool = False) -> Callable[[Row], bool]:
    """Rows of ``strategy`` (for the replacing robot: those that rewrite, or those that do
    not)."""
    if strategy is not StrategyName.REPLACEMENT:
        return lambda row: row.get("strategy") == strategy
    return lambda row: row.get("strategy") == strategy and is_rewrite(row) == rewrite


def dynamic_findings(rows: Sequence[Row]) -> list[Finding]:
    """Findings D1 to D3 (D4 when LPG-adapt ran, D1r and D2r when the replacing robot also
    rewrites) when ``rows`` hold missions in a changing world (else none)."""
    changing = [r for r in rows if r.get("world_rate") is not None]
    if not changing:
        return []
    replace, rewriting, replan, dstar, lpg = (
        _is(StrategyName.REPLACEMENT),
        _is(StrategyName.REPLACEMENT, rewrite=True),
        _is(StrategyName.REPLAN),
        _is(StrategyName.DSTAR_LITE),
        _is(StrategyName.LPG_ADAPT),
    )
    found = [
        _finding("D1", changing, replan, replace, "detours vs A*"),
        _finding("D2", changing, dstar, replace, "detours vs D* Lite"),
        _finding("D3", changing, replan, dstar, "D* Lite vs A*"),
    ]
    if any(map(lpg, changing)):
        found.append(_finding("D4", changing, lpg, replace, "detours vs LPG-adapt"))
    if any(map(rewriting, changing)):
        found += [
            _finding("D1r", changing, replan, rewriting, "rewriting detours vs A*"),
            _finding("D2r", changing, dstar, rewriting, "rewriting detours vs D* Lite"),
        ]
    return found


def _finding(
    number: str,
    rows: Sequence[Row],
    base: Callable[[Row], bool],
    candidate: Callable[[Row], bool],
    label: str,
) -> Finding:
    groups: dict[tuple[str, str], list[tuple[Row, Row]]] = defaultdict(list)
    index = {situation(r): r for r in rows if base(r)}
    for row in rows:
        if candidate(row) and (other := index.get(situation(row))) is not None:
            groups[str(row.get("maze")), str(row.get("faults") or "none")].append((other, row))
    if not groups:
        why = f"the experiment does not run both robots of {label} on the same situations."
        return Finding(number, CLAIMS[number], Outcome.NOT_APPLICABLE, (why,))
    lines, outcomes, ratios_all = [INTRO], [], []
    for (maze, faults), pairs in sorted(groups.items()):
        ratios = _ratios(pairs)
        ratios_all += ratios
        interval = bootstrap_interval(ratios, "median")
        outcome = ratio_outcome(interval, 1.0)
        outcomes.append(outcome)
        ratio = "no pair with repairs" if interval is None else interval.text(3)
        lines.append(
            f"{label}, {maze}, faults {faults}: ratio {ratio} over {len(ratios)} pairs "
            f"({outcome.value}); {_price(pairs)}"
        )
    overall = bootstrap_interval(ratios_all, "median")
    if overall is not None:
        lines.append(f"All groups: ratio {overall.text(3)} over {overall.n} pairs.")
    return Finding(number, CLAIMS[number], combine(outcomes), tuple(lines))


def _ratios(pairs: Sequence[tuple[Row, Row]]) -> list[float]:
    """Candidate over baseline median repair latency, for pairs where both repaired."""
    out = []
    for b, c in pairs:
        lb, lc = b.get("repair_latency_median_ns"), c.get("repair_latency_median_ns")
        if isinstance(lb, int | float) and isinstance(lc, int | float) and lb > 0:
            out.append(float(lc) / float(lb))
    return out


def _price(pairs: Sequence[tuple[Row, Row]]) -> str:
    """The plan-quality price: paired extra ticks to the goal and missions without a replan."""
    diffs = [
        num(c, "ticks_float") - num(b, "ticks_float")
        for b, c in pairs
        if b.get("reached") == 1 and c.get("reached") == 1
    ]
    interval = bootstrap_interval(diffs, "mean")
    ticks = "-" if interval is None else interval.text(1)
    calm = sum(succeeded(c) for _, c in pairs), sum(succeeded(b) for b, _ in pairs)
    reached = (
        sum(c.get("reached") == 1 for _, c in pairs),
        sum(b.get("reached") == 1 for b, _ in pairs),
    )
    return (
        f"ticks to the goal {ticks} more (mean paired difference); without a replan "
        f"{calm[0]} against {calm[1]}, reached {reached[0]} against {reached[1]} of {len(pairs)}"
    )
