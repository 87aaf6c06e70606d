"""What a robot is, to the rest of selfrepair: the :class:`Domain` value.

Every layer above (planner, simulator, executor, tables, coverage, traces, experiments) works on a
``Domain`` and never looks inside a robot model. A domain is a frozen value of plain functions (not
a subclass tower), so a new robot is one more value, registered by name with
:func:`selfrepair.robots.registry.register_domain`.

Robots live on a square grid: a robot's state is a :class:`~selfrepair.geometry.Pose` (its cell and
one of four headings; a robot without a heading simply keeps ``N``). A domain supplies

* its ``actions`` and their text form (``parse_action``/``format_action``);
* what an action does, on an unbounded open plane: ``apply`` (the end pose), ``footprint`` (every
  cell that must be free for the action to be executable, the start cell first) and ``duration``
  (exact, in ticks);
* its fault vocabulary: ``faults`` (every single fault), ``available(action, faults)`` (whether no
  fault in the set forbids the action), ``parse_faults``/``format_faults`` (a fault set's canonical
  text, ``""`` for none) and ``fault_sets`` (the fault sets in scope for table generation and
  coverage, singles first, then doubles);
* ``motion_class`` (actions of one class have the same effect: the planner keeps only the fastest
  available one of each) and ``level`` (0 for primitive actions, higher for complex ones; see the
  ``layered`` and ``primitive`` recursion modes);
* ``footprint_connected``: whether every action's footprint, from every heading, contains a
  4-connected path from its start cell to its end cell that is no longer than their Manhattan
  distance (a shortest grid path: each step goes from a footprint cell to an edge-adjacent
  footprint cell; an action that stays in its cell passes trivially). Only then is the
  grid-distance heuristic admissible for it (see docs/planner.md); without it the planner refuses
  that heuristic.

A domain may also say what its actuators really do when given a command that a fault forbids:
``behaviours``, a tuple of named :class:`FaultBehaviour` models (the first is the default; empty:
the domain has no such model, and a forbidden command simply fails without moving).
:meth:`Domain.effective` is the one definition of that: ``effective(action, faults, behaviour)``
is the action the robot really performs when commanded ``action`` under ``faults``, and it is
``action`` itself whenever ``available(action, faults)``. It is a pure function of its three
arguments, so callers (the simulator, the diagnoser, the compiled loop, the physics model)
tabulate it per fault set and never define it a second time.

Derived from these: ``waits``, the actions that keep every pose and sweep only the robot's own
cell (the four-wheel robot's all-stop ``SSSS`` and the wheel pairs that cancel out), those the
domain names in ``wait_actions`` first (optional: its preferred ones), then the others fastest
first. A robot with one can
spend time in place: the executor's stepper waits with it when no plan exists under the faults it
knows and they may clear (see :mod:`selfrepair.execution.stepper`). A robot without one never
waits.

The contract, checked by :func:`check_domain` when a domain is registered: ``apply`` and
``footprint`` commute with translation (an action does the same thing in every cell), the footprint
starts at the start cell, durations are positive, the text forms round-trip, and a domain that
declares ``footprint_connected`` has such footprints, and every fault behaviour maps each action,
under every fault set in scope, to an action of the domain, the action itself when it is available.
Nothing else is assumed: actions and faults
may be any hashable values.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Generic, TypeAlias, TypeVar

from selfrepair.errors import InputError, ProblemError
from selfrepair.geometry import Cell, Heading, Pose

__all__ = [
    "CANONICAL",
    "A",
    "Domain",
    "F",
    "FaultBehaviour",
    "SomeDomain",
    "check_domain",
    "primitive_by_motion",
    "progress_rate",
    "run_open",
    "singles_and_doubles",
]

A = TypeVar("A")
"""The action type of a domain, in code generic over robots (the four-wheel robot: ``Action``)."""
F = TypeVar("F")
"""The fault type of a domain, in code generic over robots (the four-wheel robot: ``Fault``)."""

CANONICAL = Pose(0, 0, Heading.N)
"""The state candidates of a replacement table are stored relative to (origin, facing north)."""


def _no_level(action: object) -> int:
    return 0


@dataclass(frozen=True, slots=True)
class FaultBehaviour(Generic[A, F]):
    """One model of what a robot's actuators do under faults: ``effective(action, faults)`` is
    the action really performed when ``action`` is commanded while ``faults`` are active.

    The contract (checked by :func:`check_domain`): the result is an action of the domain, and it
    is ``action`` itself whenever no fault in ``faults`` forbids it. ``name`` is how options,
    experiment files and traces name the model; ``description`` says in one sentence what it
    assumes (and why)."""

    name: str
    description: str
    effective: Callable[[A, frozenset[F]], A]


@dataclass(frozen=True, slots=True, eq=False)
class Domain(Generic[A, F]):
    """Everything selfrepair needs to know about one robot (see the module docstring).

    Domains compare by identity: two registrations of equal-looking functions are different robots.
    """

    name: str
    actions: tuple[A, ...]
    apply: Callable[[Pose, A], Pose]
    footprint: Callable[[Pose, A], tuple[Cell, ...]]
    duration: Callable[[A], Fraction]
    available: Callable[[A, frozenset[F]], bool]
    parse_action: Callable[[str], A]
    format_action: Callable[[A], str]
    faults: tuple[F, ...]
    parse_faults: Callable[[str], frozenset[F]]
    format_faults: Callable[[Iterable[F]], str]
    motion_class: Callable[[A], str]
    level: Callable[[A], int] = _no_level
    fault_sets: tuple[frozenset[F], ...] = ()
    footprint_connected: bool = False
    description: str = ""
    canonical: Pose = field(default=CANONICAL)
    fault_parts: Callable[[F], tuple[str, ...]] | None = None
    wait_actions: tuple[A, ...] = ()
    """The wait actions the robot prefers, in order (each must stay in place: checked by
    :func:`check_domain`); the other waits follow them in :attr:`waits`."""
    """What one fault is made of, for spreading chosen fault sets over them (the four-wheel
    robot: its wheel and its mode); ``None``: each fault is its own single part (see
    :meth:`parts_of`)."""
    behaviours: tuple[FaultBehaviour[A, F], ...] = ()
    """What the actuators do under a forbidden command, as named models (the first is the
    default; empty: no model, a forbidden command fails; see :meth:`effective`)."""
    actuators: Callable[[A], tuple[object, ...]] | None = None
    """What a teammate watching the robot sees of an action: the state of each actuator, in a
    fixed order (the four-wheel robot: each wheel's mode, FL FR RL RR); the wheel view of
    cooperative diagnosis reads it (docs/diagnosis.md). Every combination of the states each
    actuator takes must be exactly one action (checked), so a misread actuator still names an
    action. ``None``: no actuator a teammate can see."""
    action_set: frozenset[A] = field(init=False, repr=False)
    waits: tuple[A, ...] = field(init=False, repr=False)
    """The actions that keep every pose and sweep only the start cell, ``wait_actions`` first,
    then the others fastest first (ties in ``actions`` order): what the robot can wait with (see
    the module docstring)."""
    time_unit: int = field(init=False, repr=False)
    """Units per tick in which every duration is a whole number: the least common multiple of
    the denominators of the actions' durations (3 for the four-wheel robot, whose durations are
    multiples of 1/3 tick; 1 for a robot of whole-tick actions). The simulator, the planner's
    integer costs, table enumeration and the team engine all count time in these units."""

    def __post_init__(self) -> None:
        if not self.fault_sets:
            object.__setattr__(self, "fault_sets", singles_and_doubles(self.faults))
        object.__setattr__(self, "action_set", frozenset(self.actions))
        object.__setattr__(self, "waits", _waits(self))
        unit = math.lcm(1, *(Fraction(self.duration(a)).denominator for a in self.actions))
        object.__setattr__(self, "time_unit", unit)

    def __repr__(self) -> str:
        return f"Domain({self.name!r}, {len(self.actions)} actions, {len(self.faults)} faults)"

    def step(self, pose: Pose, action: A) -> tuple[Pose, tuple[Cell, ...], Fraction]:
        """End pose, footprint and duration of ``action`` at ``pose`` on an open plane."""
        return self.apply(pose, action), self.footprint(pose, action), self.duration(action)

    def parts_of(self, fault: F) -> tuple[str, ...]:
        """The parts of ``fault`` (:attr:`fault_parts`; by default its own text)."""
        if self.fault_parts is None:
            return (self.format_faults((fault,)),)
        return self.fault_parts(fault)

    def behaviour(self, name: str | None = None) -> FaultBehaviour[A, F]:
        """The fault-behaviour model called ``name`` (``None``: the default, the first).

        A domain without models, or an unknown name, raises :class:`ProblemError` naming the
        models there are."""
        if not self.behaviours:
            raise ProblemError(
                f"domain {self.name!r} has no fault-behaviour model (a forbidden command fails)"
            )
        if name is None:
            return self.behaviours[0]
        for model in self.behaviours:
            if model.name == name:
                return model
        names = ", ".join(m.name for m in self.behaviours)
        raise ProblemError(
            f"unknown fault behaviour {name!r} for domain {self.name!r}; expected one of {names}"
        )

    def behaviour_names(self) -> tuple[str, ...]:
        """The names of the fault-behaviour models, the default first."""
        return tuple(m.name for m in self.behaviours)

    def effective(self, action: A, faults: frozenset[F], behaviour: str | None = None) -> A:
        """What the actuators really do when commanded ``action`` under ``faults`` in the
        fault-behaviour model ``behaviour`` (``None``: the default): ``action`` itself whenever it
        is available; otherwise the model's answer. A forbidden action in a domain without a
        model raises :class:`ProblemError` (there, a forbidden command fails)."""
        if self.available(action, faults):
            return action
        return self.behaviour(behaviour).effective(action, faults)

    def blocking(self, action: A, faults: Iterable[F]) -> frozenset[F]:
        """The faults of ``faults`` that each forbid ``action`` on their own."""
        return frozenset(f for f in faults if not self.available(action, frozenset((f,))))


SomeDomain: TypeAlias = "Domain[Any, Any]"
"""A domain whose action and fault types are known only at run time: what the registry gives for
a name read from a file or the command line. Code that takes a domain *and* its actions is
generic in :data:`A` and :data:`F` instead; this is for what truly holds any robot (the registry,
an experiment's configuration, a cache keyed by domain)."""


def _waits(domain: Domain[A, F]) -> tuple[A, ...]:
    """The actions of ``domain`` that stay in place from every heading (:attr:`Domain.waits`)."""
    probes = tuple(Pose(0, 0, heading) for heading in Heading)
    stay = [
        a
        for a in domain.actions
        if all(domain.apply(p, a) == p and set(domain.footprint(p, a)) <= {p.cell} for p in probes)
    ]
    rest = sorted(
        (a for a in stay if a not in domain.wait_actions),
        key=lambda a: Fraction(domain.duration(a)),
    )
    return tuple(a for a in domain.wait_actions if a in stay) + tuple(rest)


def singles_and_doubles(faults: Iterable[F]) -> tuple[frozenset[F], ...]:
    """Every single fault, then every unordered pair of distinct faults."""
    singles = tuple(faults)
    return tuple(frozenset((f,)) for f in singles) + tuple(
        frozenset(pair) for pair in itertools.combinations(singles, 2)
    )


def run_open(domain: Domain[A, F], state: Pose, actions: Iterable[A]) -> Pose:
    """The state reached by applying ``actions`` in turn from ``state`` on an open plane."""
    for action in actions:
        state = domain.apply(state, action)
    return state


def primitive_by_motion(domain: Domain[A, F], faults: frozenset[F]) -> dict[str, A]:
    """For each motion class still possible under ``faults``, its fastest available action.

    Ties go to the action that comes first in ``domain.actions``, and classes keep the order in
    which they first appear among the available actions, so the choice is deterministic. Every
    other action of a class is dominated: same effect, no shorter.
    """
    best: dict[str, A] = {}
    for action in domain.actions:
        if not domain.available(action, faults):
            continue
        key = domain.motion_class(action)
        current = best.get(key)
        if current is None or domain.duration(action) < domain.duration(current):
            best[key] = action
    return best


_PROBES = tuple(Pose(0, 0, heading) for heading in Heading)
"""The origin facing each heading: where the open-plane checks start an action."""


def progress_rate(domain: Domain[A, F], actions: Iterable[A]) -> Fraction:
    """The least ticks per cell of Manhattan displacement over ``actions``, from any heading (0 if
    none moves): ``rate * manhattan(a, b)`` never exceeds the duration of getting from ``a`` to
    ``b`` with those actions, which is what makes the planners' heuristics admissible."""
    rates = []
    for action in actions:  # per action its best heading: the one that moves it furthest
        moved = max(abs(end.x) + abs(end.y) for end in (domain.apply(p, action) for p in _PROBES))
        if moved:
            rates.append(Fraction(domain.duration(action)) / moved)
    return min(rates, default=Fraction(0))


def check_domain(domain: Domain[A, F]) -> None:
    """Raise :class:`ProblemError` naming the first way ``domain`` breaks the contract of the
    module docstring (checked on every action from every heading and one shifted cell)."""

    def fail(what: str) -> ProblemError:
        return ProblemError(f"domain {domain.name!r}: {what}")

    if not domain.name or not domain.actions:
        raise fail("expected a name and at least one action")
    if len(set(domain.actions)) != len(domain.actions):
        raise fail("expected distinct actions")
    for action in domain.actions:
        text = domain.format_action(action)
        try:
            back = domain.parse_action(text)
        except InputError as exc:
            raise fail(f"action text {text!r} does not parse back: {exc.reason}") from None
        if back != action:
            raise fail(f"action text {text!r} parses to another action")
        duration = domain.duration(action)
        if not isinstance(duration, Fraction | int) or duration <= 0:
            raise fail(f"action {text} has duration {duration!r}; expected a positive Fraction")
        for probe in _PROBES:
            _check_motion(domain, action, text, probe, fail)
    for action in domain.wait_actions:
        if action not in domain.waits:
            raise fail(
                f"wait action {domain.format_action(action)} does not stay in place (expected an "
                "action of the domain that keeps every pose and sweeps only its own cell)"
            )
    for faults in (frozenset(), *domain.fault_sets):
        text = domain.format_faults(faults)
        if domain.parse_faults(text) != faults:
            raise fail(f"fault text {text!r} does not parse back to the same set")
    _check_behaviours(domain, fail)
    _check_actuators(domain, fail)


def _check_actuators(domain: Domain[A, F], fail: Callable[[str], ProblemError]) -> None:
    """Fail unless the actuator states (when declared) have one length, and every combination of
    the states each actuator takes is exactly one action of the domain."""
    if domain.actuators is None:
        return
    states = [tuple(domain.actuators(a)) for a in domain.actions]
    if len({len(s) for s in states}) != 1 or not states[0]:
        raise fail("expected the same, non-zero number of actuator states for every action")
    if len(set(states)) != len(states):
        raise fail("expected each action to have its own actuator states")
    per = [set(column) for column in zip(*states, strict=True)]
    if math.prod(len(values) for values in per) != len(states):
        raise fail(
            f"expected every combination of actuator states to be an action: {len(states)} "
            f"actions, {math.prod(len(values) for values in per)} combinations"
        )


def _check_behaviours(domain: Domain[A, F], fail: Callable[[str], ProblemError]) -> None:
    """Fail unless every fault-behaviour model has a distinct, non-empty name and maps every
    action, under every fault set in scope (and none), to an action of the domain: the action
    itself when it is available."""
    names = [m.name for m in domain.behaviours]
    if any(not n for n in names) or len(set(names)) != len(names):
        raise fail(f"expected distinct, non-empty fault-behaviour names, got {names}")
    for model in domain.behaviours:
        for faults in (frozenset(), *domain.fault_sets):
            for action in domain.actions:
                got = model.effective(action, faults)
                text = domain.format_action(action)
                where = f"fault behaviour {model.name!r} under {domain.format_faults(faults)!r}"
                if got not in domain.action_set:
                    raise fail(f"{where} turns {text} into {got!r}, not an action of the domain")
                if got != action and domain.available(action, faults):
                    raise fail(
                        f"{where} turns the available action {text} into "
                        f"{domain.format_action(got)} (expected the action itself)"
                    )


def _check_motion(
    domain: Domain[A, F],
    action: A,
    text: str,
    probe: Pose,
    fail: Callable[[str], ProblemError],
) -> None:
    """Fail unless ``action`` from ``probe`` acts the same in every cell (translation) and, for a
    domain that declares ``footprint_connected``, its footprint holds a 4-connected path from the
    start cell to the end cell of exactly their Manhattan length (breadth-first inside the
    footprint, neighbours in a fixed order)."""
    end, cells = domain.apply(probe, action), domain.footprint(probe, action)
    if not cells or cells[0] != probe.cell:
        raise fail(f"the footprint of {text} must start with the start cell")
    dx, dy = 7, -5
    shifted = Pose(probe.x + dx, probe.y + dy, probe.heading)
    want_end = Pose(end.x + dx, end.y + dy, end.heading)
    want_cells = tuple((x + dx, y + dy) for x, y in cells)
    if domain.apply(shifted, action) != want_end or domain.footprint(shifted, action) != want_cells:
        raise fail(f"action {text} does not act the same in every cell (translation)")
    if not domain.footprint_connected:
        return
    start, goal = probe.cell, end.cell
    footprint = set(cells)
    want = abs(goal[0] - start[0]) + abs(goal[1] - start[1])
    frontier, seen = [start], {start}
    for _ in range(want):
        reached: list[Cell] = []
        for x, y in frontier:
            for nxt in ((x, y - 1), (x + 1, y), (x, y + 1), (x - 1, y)):
                if nxt in footprint and nxt not in seen:
                    seen.add(nxt)
                    reached.append(nxt)
        frontier = reached
    if goal not in seen:
        raise fail(
            f"footprint_connected=True, but the footprint of action {text} from "
            f"{probe.heading.name} holds no 4-connected path of {want} steps from its start cell "
            f"{start} to its end cell {goal} (footprint {domain.footprint(probe, action)})"
        )
