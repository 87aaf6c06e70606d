"""Strategies for faults the robot is not told: it diagnoses them from what it observes.

All of them run in the one stepper loop (:mod:`selfrepair.execution.stepper`): the stepper hands
every observation to the repairer (``observe``), takes the faults the repairer assumes
(``assumption``) and checks the queue against them, so the replacement table is used as always,
under the assumed faults. They differ in what they assume and in what they do when the belief
leaves a choice (docs/diagnosis.md):

``oracle``
    The upper bound: the ``replacement`` strategy, told the true faults before every command
    (registered ``told``), whatever the detection.
``diagnose`` (diagnose-then-replace)
    Assumes the fault set of the most probable hypothesis of the most probable class; the table
    under it replaces what it forbids; a new surprise re-diagnoses.
``conformant``
    After the first surprise, assumes every fault of the classes that hold posterior mass
    ``1 - confidence`` (exactly: every class still possible, when that is what the mass needs):
    an action available under that union is available, and so does the same thing, under every
    such hypothesis, so a table candidate or plan of such actions reaches the same end pose under
    all of them. When none exists it falls back to ``diagnose``'s assumption until the belief
    changes.
``active-diagnosis``
    ``conformant``, but when no conformant repair exists and more than one class remains (the
    ambiguity blocks progress), it first runs the probe that isolates in the fewest commands
    (:func:`selfrepair.diagnosis.isolating_probe`: one command, or two), then comes back. The
    probe planner counts the readings a probe will get as the belief will: the robot's own with
    its odometry's noise and those of the observing teammates (``MissionContext.observers``,
    where they stand as they follow the robot) that will see the motion.

When a command takes the robot elsewhere than it should have (a *surprise*), the queue no longer
starts where the robot is: the repairer is asked before the next command and *rejoins* the
queue, by the cheapest path (bounded A*, ``lookahead_expansions``) from where it is to where the
queue starts, under the faults it now assumes; a probe is rejoined the same way. When no path is
found it replans to the goal. Every strategy here keeps, for the result row, when the first
surprise came, how many commands it took to isolate the class (and which), the probes run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from enum import StrEnum
from typing import Any

from selfrepair.diagnosis import (
    FaultBelief,
    Observation,
    ProbePlanner,
    fault_model,
    isolating_probe,
)
from selfrepair.diagnosis.belief import CONFIRMATIONS
from selfrepair.diagnosis.cooperative import following
from selfrepair.geometry import Pose
from selfrepair.repair.strategies.names import RepairSource, StrategyName
from selfrepair.repair.strategies.protocol import (
    Assumption,
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    chained,
)
from selfrepair.repair.strategies.registry import register_strategy
from selfrepair.repair.strategies.replacement import start_replacement, table_hit
from selfrepair.repair.strategies.replan import replan
from selfrepair.status import PlanStatus, RepairStatus

__all__ = ["MAX_PROBES", "DiagnosingRepairer", "Policy", "diagnosis_report"]

MAX_PROBES = 12
"""Probes one mission runs at most (active diagnosis)."""

_REJOIN = "rejoin"
"""The attempt name of a rejoin (in ``Repair.attempts``)."""


class Policy(StrEnum):
    """What a diagnosing repairer assumes and does when the belief leaves a choice."""

    MOST_PROBABLE = "most-probable"
    CONFORMANT = "conformant"
    ACTIVE = "active"


class DiagnosingRepairer:
    """A diagnosing strategy started for one mission (see the module docstring). Mutable: its
    belief, the blocks of probe or rejoin commands at the front of the queue, and its record."""

    __slots__ = (
        "_after",
        "_anchor",
        "_context",
        "_drop",
        "_error",
        "_known",
        "_margin",
        "_noise",
        "_planner",
        "_policy",
        "_probing",
        "_rejoining",
        "_relaxed",
        "_switch",
        "_table",
        "_trail",
        "_wanted",
        "belief",
        "isolated_class",
        "isolation_actions",
        "model",
        "probes",
        "surprise_step",
    )

    def __init__(self, context: MissionContext, policy: Policy) -> None:
        options = context.options
        self._context = context
        self._policy = policy
        self.model = fault_model(
            context.domain, context.behaviour, options.max_faults, options.fault_prior
        )
        self.belief = FaultBelief(self.model, context.grid)
        self._table = start_replacement(context)
        self._error = options.confidence
        self._margin = 0.0  # the mass left out of what is possible: 0 while readings are exact
        self._known: frozenset[object] = frozenset()
        self._probing = 0  # probe commands still at the front of the queue
        self._rejoining = 0  # rejoin commands still at the front of the queue
        self._anchor: Pose | None = None  # where the queue after those blocks starts
        self._drop = 0  # front commands of a block gone astray, to drop at the next repair
        self._wanted = False  # the stepper will ask for a rejoin
        self._relaxed = False  # no conformant repair: the most probable class until news
        self._after = 0
        self._switch = True  # the robot reads a bump switch (its observations say)
        self._noise = 0.0  # the error rate of its odometry (its observations say)
        self._trail: list[Pose] = []  # where each command started (the observers follow)
        self._planner: ProbePlanner | None = None  # made at the first probe
        self.surprise_step: int | None = None
        """The step of the first surprise (a command that went elsewhere, bumped or failed)."""
        self.isolation_actions: int | None = None
        """Commands executed after the first surprise until one class was isolated."""
        self.isolated_class: int | None = None
        """The class isolated (an index into the model's classes)."""
        self.probes = 0
        """Probes run."""

    # --- the stepper's side ----------------------------------------------------------------

    def assumption(self) -> Assumption:
        """The faults the queue is checked against (none while a probe runs: its commands go out
        as they are)."""
        return Assumption(frozenset() if self._probing else self._known)

    hears_teammates = True
    """Observing teammates' readings enter the belief (see :meth:`observe`)."""

    def observe(
        self,
        observation: Observation,
        deviated: bool,
        moved: bool,
        seen: Sequence[Observation] = (),
    ) -> bool:
        """Take ``observation`` in, and the readings ``seen`` of the same command by observing
        teammates (:mod:`selfrepair.diagnosis.cooperative`; the same update, each with its
        sensor's noise) (see the module docstring); whether to be asked for a rejoin before the
        next command."""
        before = self.belief.alive
        belief = self.belief
        belief.update(observation)
        self._switch = observation.bumped is not None
        self._noise = observation.noise
        if self._context.observers:
            self._trail.append(observation.start)
        noisy = observation.noise > 0
        for reading in seen:
            belief.update(reading)
            noisy = noisy or reading.noise > 0
        if noisy:
            self._margin = self._error
        calm = self.surprise_step is None
        self._record(observation, deviated or not moved)
        if belief.alive != before or noisy or (calm and self.surprise_step is not None):
            self._relaxed = False
            self._known = self._assume()
        rejoin = False
        if self._probing or self._rejoining:
            if moved and not deviated:
                if self._probing:
                    self._probing -= 1
                    rejoin = not self._probing  # the probe is done: back to the queue
                else:
                    self._rejoining -= 1
                    if not self._rejoining:
                        self._anchor = None  # back where the queue starts
            else:  # the block went astray: drop what is left of it at the next repair
                self._drop = max(0, (self._probing or self._rejoining) - int(moved))
                self._probing = self._rejoining = 0
                rejoin = True
        elif deviated:
            domain = self._context.domain
            self._anchor = domain.apply(observation.start, observation.action)
            rejoin = True
        if not (self._probing or self._rejoining) and self._should_probe():
            rejoin = True  # active diagnosis: probe before the next command
        self._wanted = rejoin
        return rejoin

    def _should_probe(self) -> bool:
        """Active diagnosis after a surprise: whether no class is isolated yet (the robot does
        not know what its commands do) and probes are left."""
        return (
            self._policy is Policy.ACTIVE
            and self.surprise_step is not None
            and self.probes < MAX_PROBES
            and self._ambiguous()
        )

    def _record(self, observation: Observation, deviated: bool) -> None:
        if self.surprise_step is None:
            if not (deviated or self._fault_ruled_out()):
                return
            self.surprise_step = observation.step
        elif self.isolation_actions is not None:
            return
        else:
            self._after += 1
        found = self.belief.isolated(self._margin)
        if found is not None:
            self.isolated_class, self.isolation_actions = found, self._after

    def _fault_ruled_out(self) -> bool:
        """Whether the readings rule out the fault-free class (class 0): with exact readings,
        no hypothesis of it is still possible; with noisy ones, it is no longer in the running
        (:meth:`FaultBelief.contenders`: neither credible nor within
        :data:`~selfrepair.diagnosis.belief.CONFIRMATIONS` contradictions of the best). The
        robot may learn of a fault without going astray: a teammate with the wheel view sees a
        wheel that did not do what it was told, where the motion ends where it should."""
        healthy = self.model.classes[0] & self.belief.alive
        if not healthy:
            return True
        if self._margin == 0:
            return False
        misses = self.belief.misses
        if min(misses[i] for i in self.model.members(healthy)) < CONFIRMATIONS:
            return False  # within CONFIRMATIONS of any best: in the running (a shortcut)
        return not self._contenders() & healthy

    def _assume(self) -> frozenset[object]:
        """The faults assumed now (see the module docstring): none before the first surprise
        (one noisy reading that a fault explains better is not yet evidence of one)."""
        if self.surprise_step is None:
            return frozenset()
        faults = self.belief.most_probable()[1]
        if not faults or self._policy is Policy.MOST_PROBABLE or self._relaxed:
            return faults
        out: set[object] = set()
        for hypothesis in self.model.faults_of(self.belief.credible(self._margin)):
            out |= hypothesis
        return frozenset(out)

    def _ambiguous(self) -> bool:
        """Whether more than one class is still in the running (not yet isolated)."""
        return self.belief.isolated(self._margin) is None

    def _contenders(self) -> int:
        """What a probe must split: every hypothesis still in the running."""
        if self._margin > 0:
            return self.belief.contenders(self._margin)
        return self.belief.alive

    # --- repairs -----------------------------------------------------------------------------

    def repair(self, request: RepairRequest) -> Repair:
        """A rejoin when asked for one, a plan to the goal for an empty queue, else a repair of
        the front under the assumed faults."""
        if not self._wanted and not request.queue:
            return self._replan(request)
        if self._wanted:
            self._wanted = False
            if self._should_probe():
                drop, self._drop = self._drop, 0
                probe = self._probe(request, drop)
                if probe is not None:
                    return probe
                self._drop = drop
            return self._rejoin(request)
        return self._fix(request)

    def _fix(self, request: RepairRequest) -> Repair:
        """The front is unavailable under the assumed faults (before any surprise, when the
        faults are not hidden: they were sensed, the table repairs as ``replacement``)."""
        if self.surprise_step is None:
            return self._table.repair(request)
        if self._policy is Policy.ACTIVE and not self._relaxed:
            hit = table_hit(self._context, request)
            if hit is not None:
                return hit
            if self._ambiguous() and (probe := self._probe(request, 0)) is not None:
                return probe
            return self._relax(request)
        found = self._table.repair(request)
        if found.status is not RepairStatus.REPAIRED and self._policy is not Policy.MOST_PROBABLE:
            return self._relax(request)
        return found

    def _relax(self, request: RepairRequest) -> Repair:
        """No conformant repair: assume the most probable class until the belief changes."""
        if not self._relaxed:
            self._relaxed = True
            self._known = self.belief.most_probable()[1]
        return self._table.repair(request._replace(known=self._known))

    def _probe(self, request: RepairRequest, drop: int) -> Repair | None:
        """The best probe from the pose, spliced in front of the queue (``drop`` stale commands
        replaced), or ``None`` when none splits the classes or the budget is spent."""
        if self.probes >= MAX_PROBES:
            return None
        planner = self._planner
        if planner is None or planner.switch != self._switch or planner.noise != self._noise:
            planner = self._planner = ProbePlanner(
                self.model, self.belief.grid, self._switch, self._noise
            )
        observers = self._context.observers
        stands = following([*self._trail, request.pose], len(observers)) if observers else ()
        found = isolating_probe(
            self.belief,
            request.pose,
            self._contenders(),
            planner=planner,
            watchers=tuple(zip(observers, stands, strict=True)),
        )
        if found is None:
            return None
        self.probes += 1
        self._probing = len(found.actions)
        if self._anchor is None:
            self._anchor = request.pose  # the queue starts here
        return Repair(
            RepairStatus.REPAIRED,
            RepairSource.PROBE,
            found.actions,
            drop,
            attempts=(StrategyName.ACTIVE_DIAGNOSIS,),
        )

    def _rejoin(self, request: RepairRequest) -> Repair:
        """The cheapest path from the pose back to where the queue starts (see the module
        docstring), after the ``drop`` stale commands of a block gone astray."""
        drop, self._drop = self._drop, 0
        context, target = self._context, self._anchor
        queue_left = len(request.queue) - drop
        if target is None or queue_left <= 0:
            self._anchor = None
            return self._replan(request)
        if request.pose == target:
            self._anchor = None
            return Repair(RepairStatus.REPAIRED, RepairSource.LOOKAHEAD, (), drop,
                          attempts=(_REJOIN,))  # fmt: skip
        budget = context.options.lookahead_expansions
        found = context.plan(request.pose, target.cell, target.heading, self._known, budget)
        if (
            found.status is not PlanStatus.SOLVED
            and self._policy is Policy.ACTIVE
            and self._ambiguous()
            and (probe := self._probe(request, drop)) is not None
        ):
            return probe
        if found.status is not PlanStatus.SOLVED and self._policy is not Policy.MOST_PROBABLE:
            if not self._relaxed:
                self._relaxed = True
                self._known = self.belief.most_probable()[1]
            found = context.plan(request.pose, target.cell, target.heading, self._known, budget)
        if found.status is not PlanStatus.SOLVED:
            self._anchor = None
            return chained(self._replan(request), (_REJOIN,), expansions=found.expansions)
        self._rejoining = len(found.actions)
        return Repair(
            RepairStatus.REPAIRED,
            RepairSource.LOOKAHEAD,
            found.actions,
            drop,
            expansions=found.expansions,
            attempts=(_REJOIN,),
        )

    def _replan(self, request: RepairRequest) -> Repair:
        """Plan from scratch to the goal under the assumed faults (the whole queue goes); when no
        plan exists under a conformant assumption, under the most probable class's."""
        self._probing = self._rejoining = 0
        found = replan(self._context, request._replace(known=self._known))
        if found.status is RepairStatus.REPAIRED or self._policy is Policy.MOST_PROBABLE:
            return found
        if not self._relaxed:
            self._relaxed = True
            self._known = self.belief.most_probable()[1]
        again = replan(self._context, request._replace(known=self._known))
        return chained(again, found.attempts, expansions=found.expansions)

    def report(self) -> dict[str, Any]:
        """What the result row records of the diagnosis (see :func:`diagnosis_report`)."""
        members = (
            ()
            if self.isolated_class is None
            else self.model.faults_of(self.model.classes[self.isolated_class])
        )
        return {
            "surprise_step": self.surprise_step,
            "isolation_actions": self.isolation_actions,
            "isolated": members,
            "probes": self.probes,
            "hypotheses_left": bin(self.belief.alive).count("1"),
            "classes_left": len(self.belief.classes_alive()),
            "inexplicable": self.belief.inexplicable,
        }


def diagnosis_report(repairer: object) -> dict[str, Any] | None:
    """The diagnosis record of a repairer that keeps one (``report()``), else ``None``."""
    report = getattr(repairer, "report", None)
    return None if report is None else dict(report())


def _starter(policy: Policy) -> Callable[[MissionContext], Repairer]:
    def start(context: MissionContext) -> Repairer:
        return DiagnosingRepairer(context, policy)

    start.__doc__ = f"A :class:`DiagnosingRepairer` with policy {policy.value!r}."
    return start


register_strategy(StrategyName.ORACLE, start_replacement, uses_table=True, told=True, hidden=True)
for _name, _policy in (
    (StrategyName.DIAGNOSE, Policy.MOST_PROBABLE),
    (StrategyName.CONFORMANT, Policy.CONFORMANT),
    (StrategyName.ACTIVE_DIAGNOSIS, Policy.ACTIVE),
):
    register_strategy(_name, _starter(_policy), uses_table=True, hidden=True)
