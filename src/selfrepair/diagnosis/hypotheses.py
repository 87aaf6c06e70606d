"""The fault hypotheses of a domain and what each makes of every command.

A :class:`FaultModel` holds, for one domain, one fault-behaviour model and a bound ``k``:

- the hypotheses: "none" first, then every fault set of ``Domain.fault_sets`` with at most ``k``
  faults, in that order (79 for the four-wheel robot with ``k = 2``: 12 singles, 66 doubles);
- per hypothesis and action, the action really performed (:meth:`Domain.effective
  <selfrepair.robots.domain.Domain.effective>`; ``-1`` where the domain has no fault-behaviour
  model and the command fails);
- per (action, heading), the *groups*: the hypotheses that perform the same motion, each group as
  a bit set over hypotheses (bit ``i`` is hypothesis ``i``) with the motion's end offset, end
  heading and footprint; an observation is compared with a group, never with each hypothesis;
- the prior: each fault present independently with probability ``prior`` (``P(h) ∝ q^|h| (1 -
  q)^(n - |h|)`` over the hypotheses, normalised);
- the classes: hypotheses that perform the same motion (end pose and swept cells, or failure)
  for every action from every heading behave identically everywhere, so no observation of the
  robot can tell them apart; a class is the unit of isolation.

Everything is computed once per (domain, behaviour, k, prior) and kept (:func:`fault_model`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.limits import DEFAULT_FAULT_PRIOR, DEFAULT_MAX_FAULTS
from selfrepair.robots.domain import SomeDomain

__all__ = [
    "DEFAULT_FAULT_PRIOR",
    "DEFAULT_MAX_FAULTS",
    "FAILS",
    "FaultModel",
    "Group",
    "fault_model",
]

FAILS = -1
"""The performed-action index of a command that fails (a domain without a behaviour model)."""


@dataclass(frozen=True, slots=True)
class Group:
    """The hypotheses (bit set ``mask``, indices ``members``) that perform action ``performed``
    (an index into ``Domain.actions``, or :data:`FAILS`) for one commanded action from one
    heading: end offset ``(dx, dy)`` and heading ``heading``, footprint ``cells`` as offsets from
    the start cell (start cell first)."""

    performed: int
    mask: int
    members: tuple[int, ...]
    dx: int
    dy: int
    heading: Heading
    cells: tuple[Cell, ...]


@dataclass(frozen=True, slots=True, eq=False)
class FaultModel:
    """The hypotheses of one domain and what they do (see the module docstring). Build one with
    :func:`fault_model`."""

    domain: SomeDomain
    behaviour: str | None
    k: int
    prior_rate: float
    sets: tuple[frozenset[object], ...]
    performed: tuple[tuple[int, ...], ...]
    """``performed[h][a]``: the index of the action hypothesis ``h`` performs for action ``a``."""
    groups: tuple[tuple[tuple[Group, ...], ...], ...]
    """``groups[a][heading]``: the :class:`Group` values of action ``a`` from ``heading``."""
    prior: npt.NDArray[np.float64]
    classes: tuple[int, ...]
    """The class bit sets, in order of their first hypothesis (class 0 holds "none")."""
    class_of: tuple[int, ...]
    """``class_of[h]``: the index of hypothesis ``h``'s class."""
    index: dict[object, int] = field(repr=False)
    """Action -> its index in ``Domain.actions``."""

    @property
    def size(self) -> int:
        """The number of hypotheses."""
        return len(self.sets)

    @property
    def all(self) -> int:
        """The bit set of every hypothesis."""
        return (1 << len(self.sets)) - 1

    def members(self, mask: int) -> tuple[int, ...]:
        """The hypotheses of bit set ``mask``, in order."""
        return tuple(i for i in range(len(self.sets)) if mask >> i & 1)

    def faults_of(self, mask: int) -> tuple[frozenset[object], ...]:
        """The fault sets of the hypotheses of ``mask``, in order."""
        return tuple(self.sets[i] for i in self.members(mask))

    def classes_in(self, mask: int) -> tuple[int, ...]:
        """The indices of the classes that hold a hypothesis of ``mask``, in order."""
        return tuple(c for c, bits in enumerate(self.classes) if bits & mask)

    def describe(self, mask: int) -> str:
        """The fault sets of ``mask`` in the domain's text (``none`` for the empty set)."""
        fmt = self.domain.format_faults
        return " | ".join(fmt(s) or "none" for s in self.faults_of(mask))


def fault_model(
    domain: SomeDomain,
    behaviour: str | None = None,
    k: int = DEFAULT_MAX_FAULTS,
    prior: float = DEFAULT_FAULT_PRIOR,
) -> FaultModel:
    """The :class:`FaultModel` of ``domain`` with fault-behaviour model ``behaviour`` (``None``:
    the default; a domain without one: failing commands), hypotheses of up to ``k`` faults and
    per-fault prior probability ``prior`` (kept per arguments)."""
    if k < 0:
        raise ProblemError(f"expected a fault bound k >= 0, got {k}")
    if not 0.0 < prior < 1.0:
        raise ProblemError(f"expected a per-fault prior in (0, 1), got {prior}")
    if domain.behaviours:
        behaviour = domain.behaviour(behaviour).name  # fails on an unknown name
    elif behaviour is not None:
        domain.behaviour(behaviour)  # raises: the domain has no model
    key = (domain, behaviour, k, prior)
    return _MODELS.get(key, lambda: _build(domain, behaviour, k, prior))


_MODELS: BoundedCache[tuple[SomeDomain, str | None, int, float], FaultModel] = BoundedCache(
    "diagnosis fault models", 16, kind=CacheKind.PREFILLED
)


def _build(domain: SomeDomain, behaviour: str | None, k: int, prior: float) -> FaultModel:
    actions = domain.actions
    index = {a: i for i, a in enumerate(actions)}
    sets = (frozenset(), *(s for s in domain.fault_sets if len(s) <= k))
    performed = tuple(
        tuple(
            index[domain.effective(a, s, behaviour)]
            if domain.behaviours or domain.available(a, s)
            else FAILS
            for a in actions
        )
        for s in sets
    )
    motions = [
        [
            (end.x, end.y, end.heading, tuple(domain.footprint(origin, a)))
            for origin in (Pose(0, 0, h) for h in Heading)
            for end in (domain.apply(origin, a),)
        ]
        for a in actions
    ]
    groups = []
    for a in range(len(actions)):
        per_heading = []
        for h in Heading:
            by_performed: dict[int, list[int]] = {}
            for hyp in range(len(sets)):
                by_performed.setdefault(performed[hyp][a], []).append(hyp)
            made = []
            for done, members in by_performed.items():  # in order of first hypothesis
                cells: tuple[Cell, ...]
                if done == FAILS:
                    dx, dy, heading, cells = 0, 0, h, ((0, 0),)
                else:
                    dx, dy, heading, cells = motions[done][h]
                mask = sum(1 << m for m in members)
                made.append(Group(done, mask, tuple(members), dx, dy, heading, cells))
            per_heading.append(tuple(made))
        groups.append(tuple(per_heading))
    n = len(domain.faults)
    weights = np.array([prior ** len(s) * (1 - prior) ** (n - len(s)) for s in sets])
    classes, class_of = _classes(sets, performed, motions)
    return FaultModel(
        domain,
        behaviour,
        k,
        prior,
        sets,
        performed,
        tuple(groups),
        weights / weights.sum(),
        classes,
        class_of,
        index,
    )


def _classes(
    sets: tuple[frozenset[object], ...],
    performed: tuple[tuple[int, ...], ...],
    motions: list[list[tuple[int, int, Heading, tuple[Cell, ...]]]],
) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """The classes of hypotheses with the same motion (end pose and swept cells, or failure) for
    every action from every heading, in order of their first hypothesis."""
    signature_class: dict[tuple[object, ...], int] = {}
    class_of: list[int] = []
    masks: list[int] = []
    for hyp in range(len(sets)):
        signature = tuple(
            "fails" if p == FAILS else tuple((x, y, h, frozenset(c)) for x, y, h, c in motions[p])
            for p in performed[hyp]
        )
        c = signature_class.setdefault(signature, len(masks))
        if c == len(masks):
            masks.append(0)
        masks[c] |= 1 << hyp
        class_of.append(c)
    return tuple(masks), tuple(class_of)
