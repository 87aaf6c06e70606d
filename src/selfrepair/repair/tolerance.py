"""Tolerance of a plan: which faults, appearing at which step, a plan survives by replacement.

Fault-tolerant planning (Jensen, Veloso and Bryant, ICAPS 2004) asks whether a plan stays
executable if a likely fault appears at any step. Here the question is asked of the
``replacement`` strategy itself: given a plan (its poses and actions), the mission's
:class:`~selfrepair.repair.strategies.MissionContext` (table, recursion mode, whole-plan rewriting
or not, the map as a free test) and a :class:`FaultModel` (a list of fault sets), a pair
``(step i, fault set F)`` is **covered** when ``F`` appearing permanently before step ``i``, and
detected at once, lets the robot reach the goal from there with replacements only: no replan.

How it is decided (exactly, by running the strategy):

* Before step ``i`` nothing is faulty, so the robot is at the plan's pose ``i`` with the plan's
  actions ``i..`` queued. From there :func:`runs_without_replan` runs the real repairer of the
  ``replacement`` strategy (:func:`~selfrepair.repair.strategies.get_strategy`) with ``F`` known:
  every action the faults forbid is sent to ``repairer.repair``; a repair that asks for a replan
  (``Repair.replans > 0``) means the pair is uncovered. Its planner is never run (the context's
  ``plan`` answers "no plan" at once), so the check costs table look-ups only.
* In a non-deferring recursion mode (``flat``, ``guarded``, ``layered``) a replacement ends where
  the replaced action ends and uses healthy actions only, so the robot stays on the plan's poses
  and each encounter is decided by the faulty step alone: step ``j`` **needs a replan** under
  ``F`` exactly when its action is unavailable under ``F`` and the strategy finds no valid
  replacement at pose ``j`` (:func:`needs_replan`, a local property of (pose, action, F)). Then
  ``(i, F)`` is covered exactly when no step ``j >= i`` needs a replan under ``F``; whole-plan
  rewriting substitutes the same replacements earlier, so it covers the same pairs. This is what
  :func:`plan_tolerance` computes (one look-up per faulty step and fault set), and what the
  tolerant planner's masks are made of (:mod:`selfrepair.repair.tolerance_masks`).
* In a deferring mode (``primitive``) a replacement may keep a faulty complex action for later,
  with a guard set carried over execution, so a step's answer depends on the replacement it came
  from: :func:`plan_tolerance` then runs the strategy from the first faulty step of each suffix
  (the pair's answer only depends on that step) and the local test is only an approximation.

Tests check both against a brute-force re-simulation with the executor (a mission whose fault
schedule makes ``F`` appear at step ``i``).
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from itertools import combinations, repeat

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.repair.queue import splice
from selfrepair.repair.replacement import DEFERRING
from selfrepair.repair.strategies import (
    MissionContext,
    Repairer,
    RepairRequest,
    RepairStatus,
    StrategyName,
    get_strategy,
)
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.astar import PlanResult, PlanStatus
from selfrepair.textio import JSONObject

__all__ = [
    "OPTIMAL",
    "FaultModel",
    "PlanObjective",
    "PlanTolerance",
    "StepTolerance",
    "fault_model",
    "needs_replan",
    "parse_objective",
    "plan_tolerance",
    "runs_without_replan",
    "without_replans",
]


@dataclass(frozen=True, slots=True)
class FaultModel:
    """The fault sets a plan should tolerate, in a fixed order (bit ``b`` of a tolerance mask is
    ``fault_sets[b]``). ``label`` names the model in tables (``"k=1"``, ``"k=2"`` or the sets)."""

    fault_sets: tuple[frozenset[object], ...]
    label: str

    def __post_init__(self) -> None:
        if not self.fault_sets:
            raise ProblemError("a fault model needs at least one fault set")
        if any(not f for f in self.fault_sets):
            raise ProblemError("a fault model's fault sets may not be empty")
        if len(set(self.fault_sets)) != len(self.fault_sets):
            raise ProblemError("a fault model lists a fault set twice")

    @property
    def max_size(self) -> int:
        """The largest fault set's size (the ``k`` of k-fault tolerance)."""
        return max(len(f) for f in self.fault_sets)


def fault_model(domain: SomeDomain, k: int) -> FaultModel:
    """Every fault set of the domain with 1 to ``k`` faults: ``domain.fault_sets`` (singles,
    then pairs) for ``k <= 2``, combinations of ``domain.faults`` (in their order) beyond."""
    if k < 1:
        raise ProblemError(f"k must be at least 1, got {k}")
    if k <= 2:
        sets = tuple(f for f in domain.fault_sets if len(f) <= k)
    else:
        sets = tuple(
            frozenset(c) for size in range(1, k + 1) for c in combinations(domain.faults, size)
        )
    return FaultModel(sets, f"k={k}")


OPTIMAL = "optimal"
"""The objective name of a plan made without the tolerance term (the plain optimum, or the
clearance objective when the mission has a clearance weight)."""


@dataclass(frozen=True, slots=True)
class PlanObjective:
    """The tolerant planner's objective for a mission's plan made before any fault is known: the
    fault model of every set of 1 to ``k`` faults, hard (``penalty`` ``None``: only steps that
    need no replan under any of them, see :mod:`selfrepair.repair.tolerance_masks`) or soft
    (``penalty`` ticks per (step, fault set) pair that needs a replan)."""

    k: int = 1
    penalty: Fraction | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.k, int) or self.k < 1:
            raise ProblemError(f"a tolerant objective needs k >= 1, got {self.k!r}")
        if self.penalty is not None:
            object.__setattr__(self, "penalty", Fraction(self.penalty))
            if self.penalty < 0:
                raise ProblemError(f"a soft penalty must be >= 0, got {self.penalty}")

    @property
    def label(self) -> str:
        """``tolerant k=1`` or ``tolerant soft 1/2 k=2`` (what :func:`parse_objective` reads)."""
        soft = "" if self.penalty is None else f" soft {self.penalty}"
        return f"tolerant{soft} k={self.k}"


_OBJECTIVE = re.compile(
    r"tolerant(?: soft (?P<penalty>[0-9]+(?:/[0-9]+|\.[0-9]+)?))? k=(?P<k>[0-9]+)"
)


def parse_objective(text: str) -> PlanObjective | None:
    """``optimal`` (``None``), ``tolerant k=K`` or ``tolerant soft L k=K`` (``L`` an exact
    number such as ``1``, ``1/2`` or ``0.5``); anything else raises :class:`ProblemError`."""
    if text == OPTIMAL:
        return None
    found = _OBJECTIVE.fullmatch(text)
    if found is None:
        raise ProblemError(
            f"expected an objective 'optimal', 'tolerant k=K' or 'tolerant soft L k=K', "
            f"got {text!r}"
        )
    penalty = found.group("penalty")
    return PlanObjective(int(found.group("k")), None if penalty is None else Fraction(penalty))


@dataclass(frozen=True, slots=True)
class StepTolerance:
    """One step of a plan under a fault model: ``needs_replan`` lists the fault sets (in the
    model's order) under which this step itself would need a replan (its action is faulty and
    has no valid replacement at its pose); ``uncovered`` those that, appearing before this step,
    lead to a replan at this step or later."""

    step: int
    pose: Pose
    action: object
    needs_replan: tuple[frozenset[object], ...]
    uncovered: tuple[frozenset[object], ...]


@dataclass(frozen=True, slots=True)
class PlanTolerance:
    """A plan's tolerance: per step, and over all ``(step, fault set)`` pairs.

    ``covered`` of ``pairs`` pairs are covered; ``met`` counts the pairs whose fault set forbids
    some action of the rest of the plan (the others are covered trivially). ``tolerant``: every
    pair is covered (the plan is ``model.max_size``-fault tolerant for the model's sets).
    ``exact_local``: whether the local per-step test decides every pair exactly (non-deferring
    recursion modes, see the module docstring)."""

    model: FaultModel
    steps: tuple[StepTolerance, ...]
    pairs: int
    covered: int
    met: int
    exact_local: bool

    @property
    def share(self) -> Fraction:
        """Covered pairs over all pairs (1 for an empty plan)."""
        return Fraction(self.covered, self.pairs) if self.pairs else Fraction(1)

    @property
    def tolerant(self) -> bool:
        """Whether every (step, fault set) pair is covered."""
        return self.covered == self.pairs

    @property
    def replan_steps(self) -> int:
        """The (step, fault set) pairs at which the step itself would need a replan: what the
        tolerant planner's soft mode counts."""
        return sum(len(s.needs_replan) for s in self.steps)

    def to_json(self, domain: SomeDomain) -> JSONObject:
        """The tolerance as JSON (faults and actions in ``domain``'s text form): the summary and,
        per step, the uncovered fault sets and those under which the step needs a replan (what
        ``selfrepair tolerance --json`` prints and the viewer draws as a heat strip)."""
        share = self.share
        return {
            "model": self.model.label,
            "fault_sets": [domain.format_faults(f) for f in self.model.fault_sets],
            "pairs": self.pairs,
            "covered": self.covered,
            "met": self.met,
            "share": int(share) if share.denominator == 1 else float(share),
            "share_exact": str(share),
            "tolerant": self.tolerant,
            "replan_steps": self.replan_steps,
            "exact_local": self.exact_local,
            "steps": [
                {
                    "step": s.step,
                    "pose": [s.pose.x, s.pose.y, s.pose.heading.name],
                    "action": domain.format_action(s.action),
                    "uncovered": [domain.format_faults(f) for f in s.uncovered],
                    "needs_replan": [domain.format_faults(f) for f in s.needs_replan],
                }
                for s in self.steps
            ],
        }


def _no_plan(
    start: Pose, goal: Cell, heading: Heading | None, known: frozenset[object], budget: int | None
) -> PlanResult:
    """A planner that finds nothing: a repair that falls back to replanning is seen at once."""
    return PlanResult(PlanStatus.UNSOLVABLE, (), (), None, Fraction(0), 0, 0)


def without_replans(context: MissionContext) -> MissionContext:
    """``context`` with a planner that answers "no plan" at once: a strategy run on it shows a
    fall-back to replanning (``Repair.replans``) without paying for the search."""
    return replace(context, plan=_no_plan, replan_budget=0)


def _repairer(context: MissionContext) -> Repairer:
    if context.table is None:
        raise ProblemError("plan tolerance needs the replacement strategy's table")
    return get_strategy(StrategyName.REPLACEMENT)(without_replans(context))


def needs_replan(
    context: MissionContext, pose: Pose, action: object, faults: frozenset[object],
    repairer: Repairer | None = None,
) -> bool:  # fmt: skip
    """Whether the ``replacement`` strategy of ``context`` would replan when it meets ``action``
    at ``pose`` with ``faults`` known: the action is unavailable and no valid replacement exists
    there (the local test; exact per encounter in non-deferring recursion modes)."""
    if context.domain.available(action, faults):
        return False
    fixer = repairer if repairer is not None else _repairer(context)
    repair = fixer.repair(RepairRequest(pose, (action,), faults, 0))
    return repair.replans > 0 or repair.status is not RepairStatus.REPAIRED


def runs_without_replan(
    context: MissionContext,
    pose: Pose,
    actions: Sequence[object],
    faults: frozenset[object],
    max_steps: int | None = None,
) -> bool:
    """Whether the ``replacement`` strategy of ``context``, started at ``pose`` with ``actions``
    queued and ``faults`` known (permanent), reaches the goal without a replan: the strategy's own
    repairer is asked at every faulty action, as the executor does. ``max_steps`` bounds the
    executed steps (default: ``20 * len(actions) + 100``)."""
    domain = context.domain
    repairer = _repairer(context)
    queue: deque[tuple[object, None]] = deque(zip(actions, repeat(None)))
    limit = 20 * len(actions) + 100 if max_steps is None else max_steps
    executed = 0
    while queue:
        action = queue[0][0]
        if not domain.available(action, faults):
            queued = tuple(a for a, _ in queue)
            repair = repairer.repair(RepairRequest(pose, queued, faults, executed))
            if repair.replans or repair.status is not RepairStatus.REPAIRED:
                return False
            splice(queue, repair.consumed, repair.actions, None)
            continue
        if executed >= limit or not context.free(domain.footprint(pose, action)):
            return False
        pose = domain.apply(pose, action)
        queue.popleft()
        executed += 1
    return context.at_goal(pose)


def plan_tolerance(
    context: MissionContext,
    poses: Sequence[Pose],
    actions: Sequence[object],
    model: FaultModel,
) -> PlanTolerance:
    """The tolerance of the plan ``actions`` (from ``poses[0]``; ``poses[j]`` is the pose before
    step ``j``) for the ``replacement`` strategy of ``context`` under ``model`` (see the module
    docstring): exact for every recursion mode."""
    if len(poses) < len(actions):
        raise ProblemError(f"a plan of {len(actions)} actions needs {len(actions)} poses")
    if context.options.recursion in DEFERRING:
        return _by_runs(context, poses, actions, model)
    repairer = _repairer(context)
    n = len(actions)
    local = [
        tuple(f for f in model.fault_sets if needs_replan(context, poses[j], a, f, repairer))
        for j, a in enumerate(actions)
    ]
    bad_from: list[tuple[frozenset[object], ...]] = [()] * n
    later: dict[frozenset[object], None] = {}  # insertion-ordered: fault sets failing at j or later
    for j in range(n - 1, -1, -1):
        later.update(dict.fromkeys(local[j]))
        bad_from[j] = tuple(f for f in model.fault_sets if f in later)
    return _summary(context.domain, poses, actions, model, local, bad_from, exact_local=True)


def _by_runs(
    context: MissionContext, poses: Sequence[Pose], actions: Sequence[object], model: FaultModel
) -> PlanTolerance:
    """Deferring recursion modes: the strategy run from the first faulty step of each suffix."""
    domain = context.domain
    n = len(actions)
    local = [  # a fresh repairer each time: a deferring one keeps state between repairs
        tuple(f for f in model.fault_sets if needs_replan(context, poses[j], actions[j], f))
        for j in range(n)
    ]
    verdict: dict[tuple[int, frozenset[object]], bool] = {}
    bad_from: list[tuple[frozenset[object], ...]] = []
    for i in range(n):
        bad = []
        for f in model.fault_sets:
            first = next((j for j in range(i, n) if not domain.available(actions[j], f)), None)
            if first is None:
                continue
            key = (first, f)
            if key not in verdict:
                verdict[key] = runs_without_replan(context, poses[first], actions[first:], f)
            if not verdict[key]:
                bad.append(f)
        bad_from.append(tuple(bad))
    return _summary(domain, poses, actions, model, local, bad_from, exact_local=False)


def _summary(
    domain: SomeDomain,
    poses: Sequence[Pose],
    actions: Sequence[object],
    model: FaultModel,
    local: list[tuple[frozenset[object], ...]],
    bad_from: list[tuple[frozenset[object], ...]],
    *,
    exact_local: bool,
) -> PlanTolerance:
    n = len(actions)
    steps = tuple(StepTolerance(j, poses[j], actions[j], local[j], bad_from[j]) for j in range(n))
    met = 0
    faulty_later: set[frozenset[object]] = set()
    for j in range(n - 1, -1, -1):
        faulty_later.update(f for f in model.fault_sets if not domain.available(actions[j], f))
        met += len(faulty_later)
    pairs = n * len(model.fault_sets)
    uncovered = sum(len(b) for b in bad_from)
    return PlanTolerance(model, steps, pairs, pairs - uncovered, met, exact_local)
