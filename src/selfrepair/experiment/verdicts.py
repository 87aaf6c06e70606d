"""What the findings (:mod:`selfrepair.experiment.findings`) are judged with: the thresholds,
outcomes and the value of a finding, pairing missions by situation, the paired yes/no
comparison of missions completed without a replan, and the verdict over several comparisons
(the rules are in the findings module's docstring)."""

from __future__ import annotations

import json
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction

from selfrepair.experiment.stats import sign_test, wilcoxon_greater
from selfrepair.experiment.store import Value
from selfrepair.experiment.summary import Row, met_fault, num
from selfrepair.repair.strategies import StrategyName
from selfrepair.stats import Interval, bootstrap_interval

__all__ = [
    "ALPHA",
    "CLAIMS",
    "FALLS",
    "MIN_EFFECT",
    "MIN_PAIRS",
    "NEGLIGIBLE",
    "PAIRED",
    "SITUATION",
    "Comparison",
    "Finding",
    "Outcome",
    "by_situation",
    "capital",
    "combine",
    "compare",
    "is_replacement",
    "is_rewrite",
    "is_tolerant",
    "judge",
    "pair_up",
    "ratio_outcome",
    "situation",
    "succeeded",
    "tick_cost",
    "weight_of",
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
        return f"Finding {self.number}: {self.outcome.value.upper()}. {capital(self.claim)}."

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
        head = f"**Finding {self.number}: {self.outcome.value.upper()}.** {capital(self.claim)}."
        return "\n".join([head, "", intro, "", *(f"- {item}" for item in items)])


def capital(text: str) -> str:
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

# --- pairing ------------------------------------------------------------------------------------

SITUATION = (
    "maze",
    "route",
    "faults",
    "fault_at",
    "detection",
    "replicate",
    "world_rate",
    "sensing",
    "observation_noise",
    "observers",
)
"""What makes two missions of different strategies comparable (the world columns are absent,
so equal, for an experiment whose maze never changes; the noise rate and observers likewise
for faults that are not hidden)."""


def situation(row: Row) -> tuple[Value, ...]:
    """The situation of a mission: the same for every strategy, variant and weight."""
    return tuple(row.get(c) for c in SITUATION)


def weight_of(row: Row) -> Fraction:
    return Fraction(str(row.get("clearance_weight") or "0"))


def by_situation(rows: Sequence[Row], keep: Callable[[Row], bool]) -> dict[tuple[Value, ...], Row]:
    return {situation(r): r for r in rows if keep(r)}


def combine(outcomes: Sequence[Outcome]) -> Outcome:
    """A claim over several comparisons (see the module docstring)."""
    if Outcome.NOT_HELD in outcomes:
        return Outcome.NOT_HELD
    if outcomes and all(o is Outcome.HELD for o in outcomes):
        return Outcome.HELD
    return Outcome.INCONCLUSIVE


def is_replacement(row: Row) -> bool:
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


def ratio_outcome(interval: Interval | None, threshold: float) -> Outcome:
    """A claim "at most ``threshold``" on a ratio or a share: HELD when the interval lies at or
    below it, NOT HELD when it lies above, INCONCLUSIVE when it straddles it or the pairs are too
    few."""
    if interval is None or interval.n < MIN_PAIRS:
        return Outcome.INCONCLUSIVE
    if interval.high <= threshold:
        return Outcome.HELD
    if interval.low > threshold:
        return Outcome.NOT_HELD
    return Outcome.INCONCLUSIVE


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
    ok = [(succeeded(b), succeeded(c)) for b, c in used]
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


def succeeded(row: Row) -> bool:
    return row.get("completed_without_replan") == 1


def pair_up(base: Sequence[Row], other: Sequence[Row]) -> list[tuple[Row, Row]]:
    index = {situation(r): r for r in base}
    return [(b, c) for c in other if (b := index.get(situation(c))) is not None]


def judge(
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
    return Finding(number, CLAIMS[number], combine(counted), (*lines, *extra))


PAIRED = (
    "Missions completed without a replan (candidate against baseline), over the situations "
    "where either met a fault:"
)


def tick_cost(label: str, pairs: Sequence[tuple[Row, Row]]) -> str:
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
