"""The findings of faults the robot is not told (``experiment diagnosis``, docs/diagnosis.md).

Judged on missions with detection ``hidden``, paired by situation (maze, route, faults, fault
step, replicate, odometry noise and observers: the same true faults and the same random
readings for every strategy), with the rules of :mod:`selfrepair.experiment.verdicts` (HELD /
NOT HELD / INCONCLUSIVE, at least :data:`~selfrepair.experiment.verdicts.MIN_PAIRS` pairs):

``G1``
    With exact observations, each diagnosing strategy (``diagnose``, ``conformant``,
    ``active-diagnosis``) reaches the goal in every mission the ``oracle`` (told its faults)
    reaches, with median ticks at most :data:`TICKS` times the oracle's: NOT HELD when one such
    mission is missed or the 95% interval of the median paired ratio lies above, HELD when none
    is missed and the interval lies at or below. Per strategy and number of observers.
``G1t``
    Trial and error without a fault model reaches the goal in at least :data:`TRIAL_REACH` of
    the missions the oracle reaches (exact observations): the Wilson interval of the share, HELD
    when its low end is at least the target, NOT HELD when its high end is below.
``G2``
    Active diagnosis isolates the class of the true faults in fewer commands after the first
    surprise than the passive strategies (``diagnose``, ``conformant``), per noise rate and number
    of observers: over the pairs where either was surprised, a pair is *better* when active
    isolated and the passive one did not or needed more commands, *worse* the other way; exact
    sign test (HELD: better significantly more often; NOT HELD: worse significantly more often).
    The shares isolated within 3 commands (single faults) and 5 (double), the issue's targets,
    are stated with their Wilson intervals.
``G3``
    Observing teammates cut the commands to isolate by at least :data:`OBSERVER_CUT` with noisy
    odometry: per diagnosing strategy and noise rate above 0, the robot with observers against
    the same robot alone in the same situation, over the pairs where both isolated; HELD when
    the 95% interval of the mean of ``team - (1 - cut) * alone`` lies at or below 0, NOT HELD when
    it lies above (the sign test of fewer commands and the isolations alone and with the team
    are stated with it).
``G4``
    Wrong isolations (an isolated class that does not hold the true faults) are at most
    :data:`WRONG` of the isolations at 1% odometry noise (:data:`WRONG_NOISE`), per diagnosing
    strategy and number of observers: the Wilson interval of the rate (the other noise rates
    are stated, not judged).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence

from selfrepair.experiment.stats import sign_test
from selfrepair.experiment.summary import Row, num
from selfrepair.experiment.verdicts import (
    ALPHA,
    MIN_PAIRS,
    SITUATION,
    Finding,
    Outcome,
    combine,
    ratio_outcome,
    situation,
)
from selfrepair.repair.strategies import StrategyName
from selfrepair.stats import Interval, bootstrap_interval, wilson_interval

__all__ = [
    "CLAIMS",
    "OBSERVER_CUT",
    "TICKS",
    "TRIAL_REACH",
    "WRONG",
    "WRONG_NOISE",
    "diagnosis_findings",
]

TICKS = 1.25
"""G1: the diagnosing robot's median ticks over the oracle's, at most (the issue's target)."""

TRIAL_REACH = 0.9
"""G1t: the share of the oracle's reached missions trial and error reaches, at least."""

OBSERVER_CUT = 0.3
"""G3: the cut in commands to isolate that two observers must bring, at least."""

WRONG = 0.01
"""G4: the wrong isolations' share at :data:`WRONG_NOISE`, at most."""

WRONG_NOISE = 0.01
"""G4: the odometry noise rate it is judged at."""

WITHIN = {1: 3, 2: 5}
"""Commands after the first surprise within which a single (double) fault counts as isolated
in time (the issue's targets: 95% and 90% with active diagnosis)."""

DIAGNOSING = (StrategyName.DIAGNOSE, StrategyName.CONFORMANT, StrategyName.ACTIVE_DIAGNOSIS)
PASSIVE = (StrategyName.DIAGNOSE, StrategyName.CONFORMANT)

CLAIMS = {
    "G1": f"with exact observations, the diagnosing robot reaches the goal in every mission the "
    f"oracle reaches, with median ticks at most {TICKS:g} times the oracle's",
    "G1t": f"trial and error without a fault model reaches the goal in at least "
    f"{TRIAL_REACH:.0%} of the missions the oracle reaches (exact observations)",
    "G2": "active diagnosis isolates the faults' class in fewer commands after the first "
    "surprise than passive diagnosis",
    "G3": f"with noisy odometry, observing teammates cut the commands to isolate the faults' "
    f"class by at least {OBSERVER_CUT:.0%}",
    "G4": f"at 1% odometry noise, at most {WRONG:.0%} of the isolations name a class without "
    "the true faults",
}
"""The claims of the diagnosis findings."""


def _is(strategy: StrategyName) -> Callable[[Row], bool]:
    return lambda row: row.get("strategy") == strategy


def _hidden(row: Row) -> bool:
    return row.get("observation_noise") is not None


def diagnosis_findings(rows: Sequence[Row]) -> list[Finding]:
    """Findings G1 to G4 when ``rows`` hold missions with hidden faults (else none)."""
    hidden = [r for r in rows if _hidden(r)]
    if not hidden:
        return []
    return [_g1(hidden), _g1t(hidden), _g2(hidden), _g3(hidden), _g4(hidden)]


def _oracle_pairs(rows: Sequence[Row], keep: Callable[[Row], bool]) -> list[tuple[Row, Row]]:
    """(oracle, candidate) pairs of the same situation, the candidate's rows chosen by ``keep``."""
    oracle = {situation(r): r for r in rows if _is(StrategyName.ORACLE)(r)}
    return [(o, r) for r in rows if keep(r) and (o := oracle.get(situation(r))) is not None]


def _exact(row: Row) -> bool:
    return num(row, "observation_noise") == 0


def _not_applicable(number: str, why: str) -> Finding:
    return Finding(number, CLAIMS[number], Outcome.NOT_APPLICABLE, (why,))


def _observers(row: Row) -> int:
    return int(num(row, "observers"))


def _g1(rows: Sequence[Row]) -> Finding:
    groups: dict[tuple[str, int], list[tuple[Row, Row]]] = defaultdict(list)
    for o, r in _oracle_pairs(rows, lambda r: r.get("strategy") in DIAGNOSING and _exact(r)):
        groups[str(r.get("variant")), _observers(r)].append((o, r))
    if not groups:
        return _not_applicable(
            "G1", "it needs the oracle and a diagnosing strategy with exact observations."
        )
    lines = [
        "Pairs with the oracle (exact observations): the oracle's reached missions the "
        "candidate reaches, and the median paired ratio of ticks (candidate / oracle) over "
        f"those both reach, 95% interval; at most {TICKS:g}:"
    ]
    outcomes = []
    for (variant, observers), pairs in sorted(groups.items()):
        base = [(o, r) for o, r in pairs if o.get("reached") == 1]
        both = [(o, r) for o, r in base if r.get("reached") == 1]
        ratios = [num(r, "ticks_float") / num(o, "ticks_float") for o, r in both if
                  num(o, "ticks_float") > 0]  # fmt: skip
        interval = bootstrap_interval(ratios)
        ticks = ratio_outcome(interval, TICKS)
        missed = len(base) - len(both)
        outcome = Outcome.NOT_HELD if missed else ticks
        outcomes.append(outcome)
        ratio = "-" if interval is None else interval.text(3)
        lines.append(
            f"{variant}, {observers} observers: reaches {len(both)} of {len(base)}; ticks "
            f"ratio {ratio}; bumps per mission {_mean(r for _, r in pairs):.2f} (oracle "
            f"{_mean(o for o, _ in pairs):.2f}): {outcome.value}."
        )
    return Finding("G1", CLAIMS["G1"], combine(outcomes), tuple(lines))


def _mean(rows: Iterable[Row]) -> float:
    """Mean bumps per mission."""
    values = [num(r, "bumps") for r in rows]
    return sum(values) / len(values) if values else 0.0


def _g1t(rows: Sequence[Row]) -> Finding:
    groups: dict[int, list[tuple[Row, Row]]] = defaultdict(list)
    trial = _is(StrategyName.TRIAL_AND_ERROR)
    for o, r in _oracle_pairs(rows, lambda r: trial(r) and _exact(r)):
        if o.get("reached") == 1:
            groups[_observers(r)].append((o, r))
    if not groups:
        return _not_applicable("G1t", "it needs the oracle and trial-and-error, exact readings.")
    lines = [
        "Missions the oracle reaches (exact observations), the share trial-and-error reaches "
        f"with its Wilson 95% interval; at least {TRIAL_REACH:.0%}:"
    ]
    outcomes = []
    for observers, pairs in sorted(groups.items()):
        reached = sum(r.get("reached") == 1 for _, r in pairs)
        interval = wilson_interval(reached, len(pairs))
        outcome = _share_at_least(interval, TRIAL_REACH)
        outcomes.append(outcome)
        lines.append(
            f"{observers} observers: {reached} of {len(pairs)}, {_share(interval)}; bumps per "
            f"mission {_mean(r for _, r in pairs):.2f}: {outcome.value}."
        )
    return Finding("G1t", CLAIMS["G1t"], combine(outcomes), tuple(lines))


def _share_at_least(interval: Interval | None, target: float) -> Outcome:
    if interval is None or interval.n < MIN_PAIRS:
        return Outcome.INCONCLUSIVE
    if interval.low >= target:
        return Outcome.HELD
    if interval.high < target:
        return Outcome.NOT_HELD
    return Outcome.INCONCLUSIVE


def _share(interval: Interval | None) -> str:
    if interval is None:
        return "-"
    return f"{100 * interval.estimate:.1f}% [{100 * interval.low:.1f}%, {100 * interval.high:.1f}%]"


def _actions(row: Row) -> float | None:
    """Commands after the first surprise until isolation (``None``: never isolated)."""
    value = row.get("isolation_actions")
    return float(value) if isinstance(value, int | float) else None


def _surprised(row: Row) -> bool:
    return row.get("surprise_step") is not None


def _faster(first: Row, second: Row) -> bool:
    """Whether ``first`` isolated and ``second`` did not, or needed more commands."""
    a, b = _actions(first), _actions(second)
    return a is not None and (b is None or a < b)


def _g2(rows: Sequence[Row]) -> Finding:
    index = {(situation(r), r.get("strategy")): r for r in rows}
    groups: dict[tuple[str, float, int], list[tuple[Row, Row]]] = defaultdict(list)
    for r in rows:
        if _is(StrategyName.ACTIVE_DIAGNOSIS)(r):
            for passive in PASSIVE:
                b = index.get((situation(r), passive))
                if b is not None and (_surprised(b) or _surprised(r)):
                    key = (str(passive), num(r, "observation_noise"), _observers(r))
                    groups[key].append((b, r))
    if not groups:
        return _not_applicable(
            "G2", "it needs active-diagnosis and diagnose or conformant in the same situations."
        )
    lines = [
        "Pairs where either was surprised: active isolates sooner in 'better' pairs, later (or "
        "not at all) in 'worse' ones (exact sign test); then the shares of surprised missions "
        "isolated in time (single faults within 3 commands, double within 5), Wilson 95%:"
    ]
    outcomes = []
    for (baseline, noise, observers), pairs in sorted(groups.items()):
        better = sum(_faster(c, b) for b, c in pairs)
        worse = sum(_faster(b, c) for b, c in pairs)
        p_better, p_worse = sign_test(better, worse), sign_test(worse, better)
        if len(pairs) < MIN_PAIRS:
            outcome = Outcome.INCONCLUSIVE
        elif p_better < ALPHA:
            outcome = Outcome.HELD
        elif p_worse < ALPHA:
            outcome = Outcome.NOT_HELD
        else:
            outcome = Outcome.INCONCLUSIVE
        outcomes.append(outcome)
        lines.append(
            f"active-diagnosis vs {baseline}, noise {noise:g}, {observers} observers: better in "
            f"{better} of {len(pairs)} pairs, worse in {worse} (p = {p_better:.2g}); in time "
            f"{_in_time([c for _, c in pairs])} against {_in_time([b for b, _ in pairs])}: "
            f"{outcome.value}."
        )
    return Finding("G2", CLAIMS["G2"], combine(outcomes), tuple(lines))


def _in_time(rows: Sequence[Row]) -> str:
    """The shares of surprised missions isolated in time, single and double faults."""
    parts = []
    for size, limit in WITHIN.items():
        surprised = [r for r in rows if _surprised(r) and num(r, "fault_count") == size]
        on_time = sum((a := _actions(r)) is not None and a <= limit for r in surprised)
        interval = wilson_interval(on_time, len(surprised))
        parts.append(f"{'single' if size == 1 else 'double'} {_share(interval)}")
    return ", ".join(parts)


def _g3(rows: Sequence[Row]) -> Finding:
    alone_at = SITUATION.index("observers")

    def key(row: Row) -> tuple[object, ...]:
        place = situation(row)
        return (*place[:alone_at], *place[alone_at + 1 :], row.get("variant"))

    alone = {key(r): r for r in rows if _observers(r) == 0}
    groups: dict[tuple[str, float, int], list[tuple[Row, Row]]] = defaultdict(list)
    for r in rows:
        noise = num(r, "observation_noise")
        if not (r.get("strategy") in DIAGNOSING and noise > 0 and _observers(r) > 0):
            continue
        if (b := alone.get(key(r))) is not None and (_surprised(b) or _surprised(r)):
            groups[str(r.get("variant")), noise, _observers(r)].append((b, r))
    if not groups:
        return _not_applicable(
            "G3", "it needs noisy missions of a diagnosing robot alone and with observers."
        )
    keep = 1.0 - OBSERVER_CUT
    lines = [
        "Pairs of the same robot alone and with observers where either was surprised; over "
        f"those where both isolated, mean commands to isolate and the mean of (team - {keep:g} x "
        "alone), 95% interval (at most 0: the cut is reached); fewer commands by sign test:"
    ]
    outcomes = []
    for (variant, noise, observers), pairs in sorted(groups.items()):
        both = [(b, c) for b, c in pairs if _actions(b) is not None and _actions(c) is not None]
        diffs = [float(_actions(c) or 0) - keep * float(_actions(b) or 0) for b, c in both]
        interval = bootstrap_interval(diffs, "mean")
        outcome = ratio_outcome(interval, 0.0)
        outcomes.append(outcome)
        fewer = sum(_faster(c, b) for b, c in pairs)
        more = sum(_faster(b, c) for b, c in pairs)
        mean_alone = _mean_actions(b for b, _ in both)
        mean_team = _mean_actions(c for _, c in both)
        excess = "-" if interval is None else interval.text(2)
        lines.append(
            f"{variant}, noise {noise:g}, {observers} observers: isolated {_isolated(pairs, 0)} "
            f"alone, {_isolated(pairs, 1)} with the team of {len(pairs)}; mean commands "
            f"{mean_alone} alone, {mean_team} with the team over {len(both)} pairs; excess "
            f"{excess}; fewer in {fewer} pairs, more in {more} (p = {sign_test(fewer, more):.2g})"
            f": {outcome.value}."
        )
    return Finding("G3", CLAIMS["G3"], combine(outcomes), tuple(lines))


def _isolated(pairs: Sequence[tuple[Row, Row]], side: int) -> int:
    return sum(_actions(pair[side]) is not None for pair in pairs)


def _mean_actions(rows: Iterable[Row]) -> str:
    values = [float(a) for r in rows if (a := _actions(r)) is not None]
    interval = bootstrap_interval(values, "mean")
    return "-" if interval is None else interval.text(2)


def _g4(rows: Sequence[Row]) -> Finding:
    groups: dict[tuple[float, str, int], list[Row]] = defaultdict(list)
    for r in rows:
        if r.get("strategy") in DIAGNOSING and r.get("isolated_right") is not None:
            groups[num(r, "observation_noise"), str(r.get("variant")), _observers(r)].append(r)
    judged = {k: v for k, v in groups.items() if k[0] == WRONG_NOISE}
    if not judged:
        return _not_applicable("G4", "it needs diagnosing missions at 1% odometry noise.")
    lines = [f"Wrong isolations among isolations, Wilson 95% interval; at most {WRONG:.0%}:"]
    outcomes = []
    for (noise, variant, observers), group in sorted(groups.items()):
        wrong = sum(r.get("isolated_right") == 0 for r in group)
        interval = wilson_interval(wrong, len(group))
        text = f"{variant}, noise {noise:g}, {observers} observers: {wrong} of {len(group)}, "
        if noise != WRONG_NOISE:
            lines.append(f"For comparison, {text}{_share(interval)}.")
            continue
        outcome = ratio_outcome(interval, WRONG)
        outcomes.append(outcome)
        lines.append(f"{text}{_share(interval)}: {outcome.value}.")
    return Finding("G4", CLAIMS["G4"], combine(outcomes), tuple(lines))
