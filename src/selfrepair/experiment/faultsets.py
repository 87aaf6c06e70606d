"""Which fault sets an experiment runs: named profiles and the rule behind the paper's 12.

The paper's 12 fault sets (:data:`PAPER_FAULT_SETS`) are explained in ``docs/experiments.md``.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Sequence

from selfrepair.errors import ConfigError
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL

__all__ = ["PAPER_FAULT_SETS", "biting_fault_sets", "fault_profile"]

PAPER_FAULT_SETS: tuple[str, ...] = (
    # chosen by biting_fault_sets (the rule in docs/experiments.md): each disables at least one
    # action of the initial plan of every one of the 16 bundled routes; singles first, then
    # doubles that spread the faults over wheels and modes
    "FL:F",
    "RL:F",
    "FR:B,RL:S",
    "RR:B,RR:F",
    "FL:S,FL:F",
    "FR:S,FR:F",
    "RL:B,RL:S",
    "FL:F,RR:B",
    "RL:S,RR:B",
    "FR:B,FR:F",
    "FL:F,RR:S",
    "FL:B,RL:S",
)
"""The reference experiment's 12 fault sets; see :func:`biting_fault_sets` and
docs/experiments.md (a test checks that the rule gives exactly these)."""


def biting_fault_sets(
    domain: SomeDomain, plans: Iterable[Sequence[object]], count: int
) -> tuple[str, ...]:
    """The rule behind :data:`PAPER_FAULT_SETS`: among ``domain.fault_sets``, those that disable
    at least one action of **every** plan of ``plans`` (so every mission meets a faulty action
    unless a repair steers round it), at most ``count`` of them, smallest sets first, then greedily
    the set whose fault parts (:meth:`~selfrepair.robots.domain.Domain.parts_of`: for the
    four-wheel robot, wheels and modes) were used least by the sets chosen so far, ties to the
    earlier in ``domain.fault_sets``."""
    plans = [tuple(p) for p in plans]
    biting = [
        faults
        for faults in domain.fault_sets
        if all(any(not domain.available(a, faults) for a in p) for p in plans)
    ]
    used: Counter[str] = Counter()

    def parts(faults: frozenset[object]) -> list[str]:
        return [part for f in domain.faults if f in faults for part in domain.parts_of(f)]

    chosen: list[str] = []
    while biting and len(chosen) < count:
        best = min(biting, key=lambda fs: (len(fs), sum(used[p] for p in parts(fs))))
        biting.remove(best)
        used.update(parts(best))
        chosen.append(domain.format_faults(best))
    return tuple(chosen)


def fault_profile(
    sets: str | tuple[str, ...], domain: SomeDomain = FOUR_WHEEL
) -> tuple[str, ...]:
    """The fault sets of a profile name or an explicit list, each in ``domain``'s canonical text.

    ``singles``, ``doubles`` and ``all`` come from ``domain.fault_sets``; ``paper`` is the
    four-wheel robot's 12 (:data:`PAPER_FAULT_SETS`)."""
    if isinstance(sets, tuple):
        return sets
    singles = tuple(domain.format_faults(f) for f in domain.fault_sets if len(f) == 1)
    doubles = tuple(domain.format_faults(f) for f in domain.fault_sets if len(f) == 2)
    if sets == "paper":
        if domain is not FOUR_WHEEL:
            raise ConfigError(
                f'the "paper" fault profile is for the four-wheel robot, not {domain.name!r}'
            )
        return tuple(domain.format_faults(domain.parse_faults(s)) for s in PAPER_FAULT_SETS)
    profiles = {"singles": singles, "doubles": doubles, "all": singles + doubles}
    return profiles[sets]
