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

import json
import textwrap
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction

from selfrepair.experiment.stats import sign_test, wilcoxon_greater
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

NEGLIGIBLE = 0.1
"""Finding 1: repair compute counts as negligible at most this share of the replanner's (an order
of magnitude less)."""

FALLS = 0.9
"""Finding 1b: replanning time "falls" when it is at most this share of the replanner's (a 10%
margin, so timing noise around 1 cannot decide)."""

ALPHA = 0.05
"""Significance level of the one-sided paired tests."""

MIN_PAIRS = 10
"""Fewer usable pairs than this make a comparison INCONCLUSIVE, whatever the numbers say."""

MIN_EFFECT = 0.02
"""A rise of less than this share of missions (2 percentage points) is too small to count: a
comparison whose 95% interval stays below it is NOT HELD."""


class Outcome(StrEnum):
    """How a finding came out on the data."""

    HELD = "held"
    NOT_HELD = "not held"
    INCONCLUSIVE = "inconclusive"
    NOT_APPLICABLE = "not applicable"
    """The experiment runs none of the variants the claim compares (a plug-in robot has no
    hand-written table, a sweep without clearance weights): the finding is left out, with one
    line saying why, rather than judged INCONCLUSIVE on nothing."""


@dataclass(frozen=True, slots=True)
class Finding:
    """One claim, its outcome and the evidence: an introducing sentence, then one item per
    comparison (mission-level figures first)."""

    number: str
    claim: str
    outcome: Outcome
    lines: tuple[str, ...]

    @property
    def verdict(self) -> str:
        """The outcome's text (``held``, ``not held``, ``inconclusive``)."""
        return self.outcome.value

    @property
    def applies(self) -> bool:
        """Whether the experiment holds what the claim compares (else :attr:`lines` is the one
        line saying why it is left out)."""
        return self.outcome is not Outcome.NOT_APPLICABLE

    @property
    def evidence(self) -> str:
        """The evidence as one paragraph."""
        return " ".join(self.lines)

    @property
    def headline(self) -> str:
        """``Finding N: OUTCOME. Claim.``, or ``Finding N left out: why.`` when it does not
        apply."""
        if not self.applies:
            return f"Finding {self.number} left out: {self.lines[0]}"
        return f"Finding {self.number}: {self.outcome.value.upper()}. {_cap(self.claim)}."

    def paragraph(self, width: int = 96) -> str:
        """The headline, the introducing sentence and one item per comparison, wrapped to
        ``width`` for a terminal (the headline alone for a finding left out)."""
        out = [textwrap.fill(self.headline, width, subsequent_indent="  ")]
        if not self.applies:
            return out[0]
        intro, *items = self.lines
        out.append(textwrap.fill(intro, width, initial_indent="  ", subsequent_indent="  "))
        out += [
            textwrap.fill(item, width, initial_indent="  - ", subsequent_indent="    ")
            for item in items
        ]
        return "\n".join(out)

    def markdown(self) -> str:
        """The same as Markdown: the headline in bold, the items as a list (one line in italics
        for a finding left out)."""
        if not self.applies:
            return f"*{self.headline}*"
        intro, *items = self.lines
        head = f"**Finding {self.number}: {self.outcome.value.upper()}.** {_cap(self.claim)}."
        return "\n".join([head, "", intro, "", *(f"- {item}" for item in items)])


def _cap(text: str) -> str:
    return text[:1].upper() + text[1:]


CLAIMS = {
    "1": "with replacement, repair compute is negligible (at most 1/10 of the replanner's) "
    "whenever every faulty action found a substitute",
    "1r": "with whole-plan rewriting, repair compute is negligible (at most 1/10 of the "
    "replanner's) whenever every faulty action found a substitute",
    "1b": "replanning time falls when most faulty actions found a substitute",
    "2": "keeping plans away from walls (clearance weight > 0) raises the share of missions "
    "completed without a replan",
    "2t": "planning for tolerance (the tolerant planner) completes more missions without a "
    "replan than planning for clearance (the highest clearance weight run)",
    "3": "generated tables complete more missions without a replan than the hand-written one",
    "4": "the primitive/complex recursion scheme works badly with the hand-written table "
    "(fewer missions without a replan than guarded recursion)",
}


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


# --- pairing ------------------------------------------------------------------------------------

SITUATION = ("maze", "route", "faults", "fault_at", "detection", "replicate")
"""What makes two missions of different strategies comparable."""


def situation(row: Row) -> tuple[Value, ...]:
    """The situation of a mission: the same for every strategy, variant and weight."""
    return tuple(row.get(c) for c in SITUATION)


def _weight(row: Row) -> Fraction:
    return Fraction(str(row.get("clearance_weight") or "0"))


def _by_situation(rows: Sequence[Row], keep: Callable[[Row], bool]) -> dict[tuple[Value, ...], Row]:
    return {situation(r): r for r in rows if keep(r)}


def _combine(outcomes: Sequence[Outcome]) -> Outcome:
    """A claim over several comparisons (see the module docstring)."""
    if Outcome.NOT_HELD in outcomes:
        return Outcome.NOT_HELD
    if outcomes and all(o is Outcome.HELD for o in outcomes):
        return Outcome.HELD
    return Outcome.INCONCLUSIVE


def _is_replacement(row: Row) -> bool:
    return row.get("strategy") == StrategyName.REPLACEMENT


def is_tolerant(row: Row) -> bool:
    """Whether a row's plan was made by the tolerant planner (objective ``tolerant ...``)."""
    return str(row.get("objective") or "").startswith("tolerant")


def is_rewrite(row: Row) -> bool:
    """Whether a row's variant rewrites the whole plan: its ``rewrite`` column (rows stored
    before that column existed: the ``rewrite`` option of the mission's stored configuration),
    never the variant label's text."""
    column = row.get("rewrite")
    if column is not None:
        return column == 1
    config = row.get("config")
    if not isinstance(config, str):
        return False
    options = json.loads(config).get("options")
    return isinstance(options, dict) and bool(options.get("rewrite"))


# --- finding 1: compute ------------------------------------------------------------------------


def ratio_outcome(interval: Interval | None, threshold: float) -> Outcome:
    """A ratio claim "at most ``threshold``": HELD when the interval lies at or below it, NOT HELD
    when it lies above, INCONCLUSIVE when it straddles it or the pairs are too few."""
    if interval is None or interval.n < MIN_PAIRS:
        return Outcome.INCONCLUSIVE
    if interval.high <= threshold:
        return Outcome.HELD
    if interval.low > threshold:
        return Outcome.NOT_HELD
    return Outcome.INCONCLUSIVE


def _finding_1(rows: Sequence[Row], number: str = "1") -> Finding:
    """Finding 1 over the replacing robots of ``rows`` that replace per encounter, or, as
    finding ``1r``, over those that rewrite the whole plan."""
    rewriting = number == "1r"
    replan = _by_situation(rows, is_reference_replan)
    variants: dict[str, list[Row]] = defaultdict(list)
    for r in rows:
        if (
            _is_replacement(r)
            and is_rewrite(r) == rewriting
            and _weight(r) == 0
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
    return Finding(number, CLAIMS[number], _combine(outcomes), (_ONE_INTRO, *lines))


_NEEDS_BOTH = "Needs replan (variant replan) and replacing missions in the same situations."


def _lacking(rows: Sequence[Row], replan: dict[tuple[Value, ...], Row]) -> str | None:
    """Why a finding that sets replacement against variant replan does not apply: the
    experiment runs one of them not at all (``None`` when it runs both)."""
    if replan and any(_is_replacement(r) for r in rows):
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
    replan = _by_situation(rows, is_reference_replan)
    lacking = _lacking(rows, replan)
    if lacking is not None:
        return Finding("1b", CLAIMS["1b"], Outcome.NOT_APPLICABLE, (lacking,))
    variants: dict[str, list[float]] = defaultdict(list)
    for r in rows:
        if (
            _is_replacement(r)
            and _weight(r) == 0
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
    return Finding("1b", CLAIMS["1b"], _combine(outcomes), (intro, *lines))


def _replan_ns(row: Row) -> float:
    """Time a mission spent in repairs that ended in a replan (table misses included)."""
    return float(sum(lat for src, lat in repairs_of(row) if src == RepairSource.REPLAN))


# --- paired yes/no comparisons -----------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Comparison:
    """Two robots on the same situations, by "completed without a replan" (a yes/no per mission).

    ``better``/``worse``: pairs where only the candidate / only the baseline succeeded;
    ``difference``: the paired difference of success (candidate - baseline) with its interval.
    """

    label: str
    pairs: int
    base_successes: int
    successes: int
    better: int
    worse: int
    difference: Interval | None
    p_better: float
    p_worse: float
    outcome: Outcome
    ceiling: bool

    def line(self) -> str:
        """One sentence with the counts, the interval and the tests."""
        if not self.pairs:
            return f"{self.label}: no mission met a fault: {self.outcome.value}."
        diff = "-" if self.difference is None else self.difference.text(3)
        return (
            f"{self.label}: {self.successes} against {self.base_successes} of {self.pairs}; "
            f"better in {self.better} pairs, worse in {self.worse} (sign test p = "
            f"{self.p_better:.2g}); difference {diff}: {self.outcome.value}."
        )


def compare(label: str, pairs: Sequence[tuple[Row, Row]], *, room: bool = True) -> Comparison:
    """The paired yes/no comparison of ``(baseline, candidate)`` mission pairs (see the module
    docstring for the rule). With ``room`` (claims that something *rises*), a baseline that
    already succeeds in every pair leaves no room: such a comparison is INCONCLUSIVE unless the
    candidate falls short significantly. Without it (claims that the baseline is *bad*), a
    baseline at 100% simply refutes the claim."""
    used = [(b, c) for b, c in pairs if met_fault(b) or met_fault(c)]
    ok = [(_success(b), _success(c)) for b, c in used]
    better = sum(1 for b, c in ok if c and not b)
    worse = sum(1 for b, c in ok if b and not c)
    difference = bootstrap_interval([float(c) - float(b) for b, c in ok], "mean")
    p_better, p_worse = sign_test(better, worse), sign_test(worse, better)
    ceiling = room and bool(ok) and all(b for b, _ in ok)
    if len(ok) < MIN_PAIRS or difference is None:
        outcome = Outcome.INCONCLUSIVE
    elif p_worse < ALPHA:
        outcome = Outcome.NOT_HELD
    elif ceiling:
        outcome = Outcome.INCONCLUSIVE  # nothing can rise above 100%
    elif p_better < ALPHA:
        outcome = Outcome.HELD
    elif difference.high < MIN_EFFECT:
        outcome = Outcome.NOT_HELD
    else:
        outcome = Outcome.INCONCLUSIVE
    return Comparison(
        label,
        len(ok),
        sum(b for b, _ in ok),
        sum(c for _, c in ok),
        better,
        worse,
        difference,
        p_better,
        p_worse,
        outcome,
        ceiling,
    )


def _success(row: Row) -> bool:
    return row.get("completed_without_replan") == 1


def _pairs(base: Sequence[Row], other: Sequence[Row]) -> list[tuple[Row, Row]]:
    index = {situation(r): r for r in base}
    return [(b, c) for c in other if (b := index.get(situation(c))) is not None]


def _judge(
    number: str,
    comparisons: Sequence[Comparison],
    intro: str,
    extra: Sequence[str] = (),
    *,
    missing: str,
) -> Finding:
    """The finding from its comparisons; without any, the finding does not apply and
    ``missing`` says why (one sentence: what the claim compares that the experiment lacks)."""
    if not comparisons:
        return Finding(number, CLAIMS[number], Outcome.NOT_APPLICABLE, (missing,))
    full = [c for c in comparisons if c.ceiling and c.outcome is not Outcome.NOT_HELD]
    counted = [c.outcome for c in comparisons if c not in full]
    lines = [intro, *(c.line() for c in comparisons if c not in full)]
    if full:
        listed = "; ".join(f"{c.label} ({c.pairs} pairs)" for c in full)
        lines.append(f"No room to rise (the baseline completes every pair already): {listed}.")
    return Finding(number, CLAIMS[number], _combine(counted), (*lines, *extra))


# --- finding 2: clearance ----------------------------------------------------------------------


def _finding_2(rows: Sequence[Row]) -> Finding:
    by_variant: dict[str, dict[Fraction, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for r in rows:
        if _is_replacement(r):
            by_variant[str(r.get("variant"))][_weight(r)].append(r)
    comparisons = []
    costs = []
    for variant, weights in sorted(by_variant.items()):
        if 0 not in weights:
            continue
        for weight, group in sorted(weights.items()):
            if weight == 0:
                continue
            pairs = _pairs(weights[Fraction(0)], group)
            comparisons.append(compare(f"{variant} w={weight} vs w=0", pairs))
            costs.append(_tick_cost(f"{variant} w={weight}", pairs))
    intro = _PAIRED
    shares = _encounter_shares(by_variant)
    missing = (
        "it compares a replacement variant at clearance weight 0 with the same variant at a "
        "weight above 0, and this experiment runs "
        + ("no replacement strategy." if not by_variant else "each at one weight only.")
    )
    return _judge("2", comparisons, intro, [c for c in (*costs, shares) if c], missing=missing)


_PAIRED = (
    "Missions completed without a replan (candidate against baseline), over the situations "
    "where either met a fault:"
)


def _tick_cost(label: str, pairs: Sequence[tuple[Row, Row]]) -> str:
    """What a weight costs in time to goal against the common optimum (paired, reached both)."""
    diffs = [
        num(c, "ticks_over_optimum") - num(b, "ticks_over_optimum")
        for b, c in pairs
        if isinstance(b.get("ticks_over_optimum"), int | float)
        and isinstance(c.get("ticks_over_optimum"), int | float)
    ]
    interval = bootstrap_interval(diffs, "mean")
    if interval is None:
        return ""
    return (
        f"Price of {label}: {interval.text(1)} ticks more than at w=0 to the goal (mean "
        f"paired difference; Wilcoxon p = {wilcoxon_greater(diffs):.2g})."
    )


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
        if _is_replacement(r) and _weight(r) == 0:
            groups[str(r.get("recursion"))][str(r.get("table"))].append(r)
    comparisons = []
    for mode, tables in sorted(groups.items()):
        if HANDWRITTEN not in tables:
            continue
        for table, group in sorted(tables.items()):
            if table != HANDWRITTEN:
                pairs = _pairs(tables[HANDWRITTEN], group)
                comparisons.append(compare(f"{table} vs {HANDWRITTEN}, {mode}", pairs))
    used = {table for tables in groups.values() for table in tables}
    return _judge("3", comparisons, _PAIRED, missing=_no_handwritten(rows, used, "another table"))


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
        if _is_replacement(r) and _weight(r) == 0:
            groups[str(r.get("table"))][str(r.get("recursion"))].append(r)
    judged: list[Comparison] = []
    others: list[Comparison] = []
    for table, modes in sorted(groups.items()):
        if PRIMITIVE in modes and GUARDED in modes:
            pairs = _pairs(modes[PRIMITIVE], modes[GUARDED])  # guarded is the candidate
            found = compare(f"{table}: guarded against primitive", pairs, room=False)
            (judged if table == HANDWRITTEN else others).append(found)
    extra = [f"For comparison, {c.line()}" for c in others]
    missing = _no_handwritten(rows, set(groups), "itself under guarded and primitive recursion")
    return _judge("4", judged, _PAIRED, extra, missing=missing)
