"""Domain-independent description of a robot for the replacement machinery.

The replacement core (:mod:`selfrepair.replacement`, :mod:`selfrepair.table`) never looks inside a
robot model. It needs only what a :class:`Domain` provides: the actions, what an action does to a
state on an open plane (``apply``), which cells must be free for it (``footprint``), its cost, and
whether it is available under a set of faults. A domain is a frozen value of plain functions (not a
subclass tower), so a new robot is one more entry in :data:`DOMAINS`.

Two domains ship:

``four-wheel``
    The skid-steer robot of :mod:`selfrepair.robot`, built only from ``robot.step``,
    ``robot.swept_cells``, ``robot.duration`` and ``robot.available``. States are
    :class:`~selfrepair.robot.Pose`, actions :class:`~selfrepair.robot.Action`, faults
    :class:`~selfrepair.robot.Fault` (wheel, mode).

``three-action``
    The robot of the original paper's Table 1: ``F`` moves one cell forward, ``L`` turns left and
    ``R`` turns right in place, each taking one tick. A fault disables one action by name, so a
    fault is the action's name (``"L"``) and a fault set a frozenset of names.

Levels (used by the ``layered`` recursion mode): ``level(action)`` is 0 for primitive actions and
higher for complex ones. A faulty action inside a candidate may be replaced recursively only when
its level is below the level of the action being replaced. Four-wheel: waits, straight moves and
in-place turns are primitive (0); arcs, which combine a move and a turn, are complex (1).
Three-action: every action is primitive (0), so layered mode never recurses there.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Generic, TypeVar

from selfrepair import robot
from selfrepair.errors import InputError
from selfrepair.robot import Cell, Heading, Pose

__all__ = [
    "DOMAINS",
    "FOUR_WHEEL",
    "THREE_ACTION",
    "THREE_ACTIONS",
    "Domain",
    "get_domain",
    "run_open",
]

S = TypeVar("S")
A = TypeVar("A")


@dataclass(frozen=True, slots=True)
class Domain(Generic[S, A]):
    """Everything the replacement machinery needs to know about one robot.

    ``apply`` is the effect on an unbounded open plane; ``footprint`` the cells that must be free
    for the action to be executable from a state (the start cell included). ``available(action,
    faults)`` says whether no fault in ``faults`` forbids the action. ``fault_sets`` lists the
    fault sets in scope, singles first, then doubles. ``parse_faults``/``format_faults`` read and
    write a fault set in canonical text (``""`` for none), used as keys in fault-indexed tables.
    ``motion_class`` names the class an action belongs to (actions of one class have the same
    effect); ``level`` is the action's layer for the ``layered`` recursion mode.
    """

    name: str
    actions: tuple[A, ...]
    canonical: S
    apply: Callable[[S, A], S]
    footprint: Callable[[S, A], tuple[Cell, ...]]
    cost: Callable[[A], Fraction]
    available: Callable[[A, frozenset[Any]], bool]
    parse_action: Callable[[str], A]
    format_action: Callable[[A], str]
    parse_faults: Callable[[str], frozenset[Any]]
    format_faults: Callable[[Iterable[Any]], str]
    fault_sets: tuple[frozenset[Any], ...]
    motion_class: Callable[[A], str]
    level: Callable[[A], int]


def run_open(domain: Domain[S, A], state: S, actions: Iterable[A]) -> S:
    """The state reached by applying ``actions`` in turn from ``state`` on an open plane."""
    for action in actions:
        state = domain.apply(state, action)
    return state


# --- four-wheel -------------------------------------------------------------------------------


def _fw_apply(pose: Pose, action: robot.Action) -> Pose:
    return robot.step(pose, action)[0]


def _fw_level(action: robot.Action) -> int:
    return 1 if action.motion.kind is robot.MotionKind.ARC else 0


def _fw_parse_action(text: str) -> robot.Action:
    return robot.parse_action(text)


def _fw_format_action(action: robot.Action) -> str:
    return action.code


def _fw_parse_faults(text: str) -> frozenset[robot.Fault]:
    return robot.parse_faults(text)


def _fw_format_faults(faults: Iterable[robot.Fault]) -> str:
    return robot.format_faults(faults)


def _fw_motion_class(action: robot.Action) -> str:
    return action.motion.name


FOUR_WHEEL: Domain[Pose, robot.Action] = Domain(
    name="four-wheel",
    actions=robot.ACTIONS,
    canonical=Pose(0, 0, Heading.N),
    apply=_fw_apply,
    footprint=robot.swept_cells,
    cost=robot.duration,
    available=robot.available,
    parse_action=_fw_parse_action,
    format_action=_fw_format_action,
    parse_faults=_fw_parse_faults,
    format_faults=_fw_format_faults,
    fault_sets=tuple(frozenset({f}) for f in robot.SINGLE_FAULTS) + robot.DOUBLE_FAULTS,
    motion_class=_fw_motion_class,
    level=_fw_level,
)
"""The four-wheel skid-steer robot, straight from :mod:`selfrepair.robot`."""


# --- three-action (the original paper's Table 1) ----------------------------------------------

THREE_ACTIONS: tuple[str, ...] = ("F", "L", "R")
"""The three actions: forward one cell, turn left, turn right."""

_THREE_CLASS = {"F": "forward", "L": "turn-left", "R": "turn-right"}


def _ta_apply(pose: Pose, action: str) -> Pose:
    if action == "F":
        dx, dy = pose.heading.vector
        return Pose(pose.x + dx, pose.y + dy, pose.heading)
    return Pose(pose.x, pose.y, pose.heading.rotated(-1 if action == "L" else 1))


def _ta_footprint(pose: Pose, action: str) -> tuple[Cell, ...]:
    if action == "F":
        dx, dy = pose.heading.vector
        return (pose.cell, (pose.x + dx, pose.y + dy))
    return (pose.cell,)


def _ta_cost(action: str) -> Fraction:
    return Fraction(1)


def _ta_available(action: str, faults: frozenset[Any]) -> bool:
    return action not in faults


def _ta_parse_action(text: str) -> str:
    name = text.strip().upper()
    if name not in THREE_ACTIONS:
        raise InputError(
            f"expected a three-action robot action F, L or R, got {text!r}", source="<action>"
        )
    return name


def _ta_format_action(action: str) -> str:
    return action


def _ta_parse_faults(text: str) -> frozenset[str]:
    return frozenset(_ta_parse_action(p) for p in text.split(",") if p.strip())


def _ta_format_faults(faults: Iterable[str]) -> str:
    return ",".join(sorted(faults, key=THREE_ACTIONS.index))


def _ta_level(action: str) -> int:
    return 0


THREE_ACTION: Domain[Pose, str] = Domain(
    name="three-action",
    actions=THREE_ACTIONS,
    canonical=Pose(0, 0, Heading.N),
    apply=_ta_apply,
    footprint=_ta_footprint,
    cost=_ta_cost,
    available=_ta_available,
    parse_action=_ta_parse_action,
    format_action=_ta_format_action,
    parse_faults=_ta_parse_faults,
    format_faults=_ta_format_faults,
    fault_sets=tuple(frozenset({a}) for a in THREE_ACTIONS)
    + tuple(frozenset(p) for p in itertools.combinations(THREE_ACTIONS, 2)),
    motion_class=_THREE_CLASS.__getitem__,
    level=_ta_level,
)
"""The three-action robot of the original paper's Table 1."""


DOMAINS: dict[str, Domain[Any, Any]] = {
    FOUR_WHEEL.name: FOUR_WHEEL,
    THREE_ACTION.name: THREE_ACTION,
}
"""Every domain by name."""


def get_domain(name: str) -> Domain[Any, Any]:
    """The domain called ``name``; an unknown name raises :class:`InputError` listing them."""
    try:
        return DOMAINS[name]
    except KeyError:
        known = ", ".join(sorted(DOMAINS))
        raise InputError(
            f"expected a domain name ({known}), got {name!r}", source="<domain>"
        ) from None
