"""The original study's findings, judged on stored rows by paired tests over missions.

Each finding compares two robots **in the same situations** (maze, route, faults, timing,
detection, replicate): the unit is the pair of missions, never the repair. *The replanner* in
findings 1 and 1b is the original study's baseline only: strategy ``replan`` with the default
planner backend (variant ``replan``, A* from scratch;
:func:`~selfrepair.experiment.summary.is_reference_replan`). Other replanning variants an
experiment may run (``replan[python]``, ``dstar-lite``, ``lpg-adapt``) never enter a finding; they
are compared on their own by :mod:`selfrepair.experiment.comparison`, and :func:`reference_note`
says so wherever findings are shown beside them. Outcomes
(:class:`Outcome`) are HELD, NOT HELD or INCONCLUSIVE; the thresholds are the constants below, and
docs/experiments.md states them with their reasons.

1. *With replacement, time per action is negligible whenever every faulty action found a
   substitute*: the median over pairs of (replacing robot's repair compute / replanning robot's
   repair compute), for replacing missions that met a fault and never replanned. HELD when the
   upper end of its 95% bootstrap interval is at most :data:`NEGLIGIBLE`; NOT HELD when the lower
   end is above it.
1r. The same as 1 for the robots that rewrite the whole plan once a fault is known
   (``replacement[...,rewrite]`` variants, judged only when there are such rows). Every other
   finding leaves the rewriting variants out: they are judged apart, never mixed with the robots
   that replace per encounter.
1b. *...and replanning time falls when most did*: the same for the time spent in replans, over
   missions where most but not all encounters were replaced; threshold :data:`FALLS`.
2. *Clearance weight > 0 raises the share of successful replacements*: per replacement variant
   and weight above 0, against weight 0, the missions completed without a replan (paired yes/no:
   exact sign test on the pairs that differ, and the 95% interval of the paired difference).
3. *Generated tables resolve more than the hand-written one*: the same test, per recursion mode
   at weight 0, each other table against the hand-written table.
4. *The primitive/complex scheme works badly with a small table* (the paper's section 4): the
   same test, guarded against primitive recursion with the hand-written table (generated tables
   are reported alongside).

A yes/no comparison is HELD when the sign test gives p < :data:`ALPHA`; NOT HELD when the
opposite direction does, or when the interval's upper end is below :data:`MIN_EFFECT` (a rise
that small is ruled out); INCONCLUSIVE otherwise or with fewer than :data:`MIN_PAIRS` pairs.
Pairs count only when at least one of the two missions met a faulty action. Comparisons whose
baseline already completes every such pair without a replan have no room to rise: they are
listed but count only if the other side falls significantly short. A claim over several
comparisons (several variants, tables or modes) is NOT HELD when any comparison is NOT HELD, HELD
when all are HELD, INCONCLUSIVE otherwise.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from fractions import Fraction

from selfrepair.experiment.store import Value
from selfrepair.experiment.summary import (
    Row,
    StrategySummary,
    group_label,
    is_reference_replan,
    local_share,
    met_fault,
    num,
    repairs_of,
    summarize,
)
from selfrepair.experiment.verdicts import (
    ALPHA,
    CLAIMS,
    FALLS,
    MIN_EFFECT,
    MIN_PAIRS,
    NEGLIGIBLE,
    PAIRED,
    Comparison,
    Finding,
    Outcome,
    by_situation,
    combine,
    compare,
    is_replacement,
    is_rewrite,
    is_tolerant,
    judge,
    pair_up,
    ratio_outcome,
    situation,
    tick_cost,
    weight_of,
)
from selfrepair.repair.strategies import RepairSource, StrategyName
from selfrepair.stats import Interval, bootstrap_interval, lower_median

__all__ = [
    "ALPHA",
    "FALLS",
    "MIN_EFFECT",
    "MIN_PAIRS",
    "NEGLIGIBLE",
    "Finding",
    "Outcome",
    "Row",
    "StrategySummary",
    "check_findings",
    "group_label",
    "is_rewrite",
    "local_share",
    "reference_note",
    "repairs_of",
    "summarize",
]

REPLANNERS = frozenset({StrategyName.REPLAN, StrategyName.DSTAR_LITE, StrategyName.LPG_ADAPT})
"""Strategies that answer a fault with a new plan to the goal (their variants, other than the
reference ``replan``, are named by :func:`reference_note`)."""


def reference_note(rows: Sequence[Row]) -> str | None:
    """When ``rows`` hold replanning variants besides the reference: one sentence saying that the
    findings compare with variant ``replan`` only, naming the variants left out (``None``
    otherwise)."""
    others = sorted(
        {
            group_label(r)
            for r in rows
            if r.get("strategy") in REPLANNERS and not is_reference_replan(r)
        }
    )
    if not others:
        return None
    return (
        "The replanner in these findings is variant replan only (A* from scratch, default "
        f"backend); {', '.join(others)} "
        + ("does" if len(others) == 1 else "do")
        + " not enter them (see the baselines comparison)."
    )


def check_findings(rows: Sequence[Row]) -> list[Finding]:
    """Every finding, each HELD / NOT HELD / INCONCLUSIVE, with the numbers behind it."""
    rows = [r for r in rows if not is_tolerant(r)]  # judged apart (tolerance_findings)
    rewriting = [r for r in rows if is_rewrite(r)]
    rows = [r for r in rows if not is_rewrite(r)]
    return [
        _finding_1(rows),
        *([_finding_1(rows + rewriting, "1r")] if rewriting else []),
        _finding_1b(rows),
        _finding_2(rows),
        _finding_3(rows),
        _finding_4(rows),
    ]


# --- finding 1: compute ------------------------------------------------------------------------


def _finding_1(rows: Sequence[Row], number: str = "1") -> Finding:
    """Finding 1 over the replacing robots of ``rows`` that replace per encounter, or, as
    finding ``1r``, over those that rewrite the whole plan."""
    rewriting = number == "1r"
    replan = by_situation(rows, is_reference_replan)
    variants: dict[str, list[Row]] = defaultdict(list)
    for r in rows:
        if (
            is_replacement(r)
            and is_rewrite(r) == rewriting
            and weight_of(r) == 0
            and met_fault(r)
            and num(r, "replans") == 0
        ):
            variants[group_label(r)].append(r)
    lacking = _lacking(rows, replan)
    if lacking is not None:
        return Finding(number, CLAIMS[number], Outcome.NOT_APPLICABLE, (lacking,))
    if not variants:
        return Finding(number, CLAIMS[number], Outcome.INCONCLUSIVE, (_NEEDS_BOTH,))
    outcomes = []
    lines = []
    for label, group in sorted(variants.items()):
        pairs = [(r, p) for r in group if (p := replan.get(situation(r))) is not None]
        ratios = [
            num(r, "repair_compute_ns") / num(p, "repair_compute_ns")
            for r, p in pairs
            if num(p, "repair_compute_ns") > 0
        ]
        interval = bootstrap_interval(ratios)
        outcome = ratio_outcome(interval, NEGLIGIBLE)
        outcomes.append(outcome)
        lines.append(_ratio_line(label, interval, outcome, pairs))
    return Finding(number, CLAIMS[number], combine(outcomes), (_ONE_INTRO, *lines))


_NEEDS_BOTH = "Needs replan (variant replan) and replacing missions in the same situations."


def _lacking(rows: Sequence[Row], replan: dict[tuple[Value, ...], Row]) -> str | None:
    """Why a finding that sets replacement against variant replan does not apply: the
    experiment runs one of them not at all (``None`` when it runs both)."""
    if replan and any(is_replacement(r) for r in rows):
        return None
    what = "no variant replan" if not replan else "no replacement strategy"
    return f"it sets replacement against variant replan, and this experiment runs {what}."


_ONE_INTRO = (
    "Paired missions that met a fault, the replacing robot without any replan; "
    "median of (its repair compute / that of variant replan), 95% interval:"
)


def _ratio_line(
    label: str, interval: Interval | None, outcome: Outcome, pairs: Sequence[tuple[Row, Row]]
) -> str:
    if interval is None:
        return f"{label}: no pair: {outcome.value}."
    ours = lower_median([num(r, "repair_count") for r, _ in pairs]) if pairs else 0
    theirs = lower_median([num(p, "repair_count") for _, p in pairs]) if pairs else 0
    return (
        f"{label}: {interval.text(3)} over {interval.n} pairs ({ours:g} repairs per mission "
        f"against {theirs:g}): {outcome.value}."
    )


def _finding_1b(rows: Sequence[Row]) -> Finding:
    replan = by_situation(rows, is_reference_replan)
    lacking = _lacking(rows, replan)
    if lacking is not None:
        return Finding("1b", CLAIMS["1b"], Outcome.NOT_APPLICABLE, (lacking,))
    variants: dict[str, list[float]] = defaultdict(list)
    for r in rows:
        if (
            is_replacement(r)
            and weight_of(r) == 0
            and num(r, "replans") > 0
            and num(r, "replacements") > num(r, "faulty_encounters") / 2
            and (p := replan.get(situation(r))) is not None
            and _replan_ns(p) > 0
        ):
            variants[group_label(r)].append(_replan_ns(r) / _replan_ns(p))
    intro = (
        "Missions where most but not all faulty encounters were replaced: median of (time in "
        f"replans / that of variant replan), 95% interval; falling means at most {FALLS:g}:"
    )
    if not variants:
        return Finding("1b", CLAIMS["1b"], Outcome.INCONCLUSIVE, (intro, "No such mission."))
    outcomes, lines = [], []
    for label, ratios in sorted(variants.items()):
        interval = bootstrap_interval(ratios)
        outcome = ratio_outcome(interval, FALLS)
        outcomes.append(outcome)
        assert interval is not None
        lines.append(f"{label}: {interval.text(2)} over {interval.n} pairs: {outcome.value}.")
    return Finding("1b", CLAIMS["1b"], combine(outcomes), (intro, *lines))


def _replan_ns(row: Row) -> float:
    """Time a mission spent in repairs that ended in a replan (table misses included)."""
    return float(sum(lat for src, lat in repairs_of(row) if src == RepairSource.REPLAN))


# --- finding 2: clearance ----------------------------------------------------------------------


def _finding_2(rows: Sequence[Row]) -> Finding:
    by_variant: dict[str, dict[Fraction, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for r in rows:
        if is_replacement(r):
            by_variant[str(r.get("variant"))][weight_of(r)].append(r)
    comparisons = []
    costs = []
    for variant, weights in sorted(by_variant.items()):
        if 0 not in weights:
            continue
        for weight, group in sorted(weights.items()):
            if weight == 0:
                continue
            pairs = pair_up(weights[Fraction(0)], group)
            comparisons.append(compare(f"{variant} w={weight} vs w=0", pairs))
            costs.append(tick_cost(f"{variant} w={weight}", pairs))
    intro = PAIRED
    shares = _encounter_shares(by_variant)
    missing = (
        "it compares a replacement variant at clearance weight 0 with the same variant at a "
        "weight above 0, and this experiment runs "
        + ("no replacement strategy." if not by_variant else "each at one weight only.")
    )
    return judge("2", comparisons, intro, [c for c in (*costs, shares) if c], missing=missing)


def _encounter_shares(by_variant: dict[str, dict[Fraction, list[Row]]]) -> str:
    parts = []
    for variant, weights in sorted(by_variant.items()):
        if 0 in weights and len(weights) > 1:
            listed = ", ".join(
                f"w={w}: {_pct(local_share(rs)[0])}" for w, rs in sorted(weights.items())
            )
            parts.append(f"{variant} {listed}")
    return ("Resolved locally, per encounter: " + "; ".join(parts) + ".") if parts else ""


def _pct(share: float | None) -> str:
    return "-" if share is None else f"{100 * share:.2f}%"


# --- finding 3: tables --------------------------------------------------------------------------

HANDWRITTEN = "handwritten"


def _finding_3(rows: Sequence[Row]) -> Finding:
    groups: dict[str, dict[str, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for r in rows:
        if is_replacement(r) and weight_of(r) == 0:
            groups[str(r.get("recursion"))][str(r.get("table"))].append(r)
    comparisons = []
    for mode, tables in sorted(groups.items()):
        if HANDWRITTEN not in tables:
            continue
        for table, group in sorted(tables.items()):
            if table != HANDWRITTEN:
                pairs = pair_up(tables[HANDWRITTEN], group)
                comparisons.append(compare(f"{table} vs {HANDWRITTEN}, {mode}", pairs))
    used = {table for tables in groups.values() for table in tables}
    return judge("3", comparisons, PAIRED, missing=_no_handwritten(rows, used, "another table"))


def _robots(rows: Sequence[Row]) -> str:
    names = sorted({str(r.get("domain") or "four-wheel") for r in rows})
    return ", ".join(names) or "no"


def _no_handwritten(rows: Sequence[Row], tables: set[str], other: str) -> str:
    """Why a finding about the hand-written table does not apply (``tables``: those the
    replacing missions use; ``other``: what the claim sets the hand-written table against)."""
    if HANDWRITTEN in tables:
        return f"it sets the hand-written table against {other}, which this experiment lacks."
    if all(str(r.get("domain") or "four-wheel") != "four-wheel" for r in rows):
        return (
            "it is about the paper's hand-written table, which is the four-wheel robot's; this "
            f"experiment's robot is {_robots(rows)}."
        )
    return "it is about the hand-written table, which this experiment's replacement never uses."


# --- finding 4: primitive/complex recursion ---------------------------------------------------

PRIMITIVE, GUARDED = "primitive", "guarded"


def _finding_4(rows: Sequence[Row]) -> Finding:
    groups: dict[str, dict[str, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for r in rows:
        if is_replacement(r) and weight_of(r) == 0:
            groups[str(r.get("table"))][str(r.get("recursion"))].append(r)
    judged: list[Comparison] = []
    others: list[Comparison] = []
    for table, modes in sorted(groups.items()):
        if PRIMITIVE in modes and GUARDED in modes:
            pairs = pair_up(modes[PRIMITIVE], modes[GUARDED])  # guarded is the candidate
            found = compare(f"{table}: guarded against primitive", pairs, room=False)
            (judged if table == HANDWRITTEN else others).append(found)
    extra = [f"For comparison, {c.line()}" for c in others]
    missing = _no_handwritten(rows, set(groups), "itself under guarded and primitive recursion")
    return judge("4", judged, PAIRED, extra, missing=missing)
