"""The three-action robot of the original paper's Table 1.

``F`` moves one cell forward, ``L`` turns left and ``R`` turns right in place, each taking one
tick. A fault disables one action by name, so a fault is the action's name (``"L"``) and a fault
set a frozenset of names. Every action is primitive (level 0). The paper's example replacements,
``R -> L L L`` and ``L -> R R R``, are the bundled table ``three-action``.
"""

from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction

from selfrepair.errors import InputError
from selfrepair.geometry import Cell, Pose
from selfrepair.robots.domain import Domain

__all__ = ["THREE_ACTION", "THREE_ACTIONS"]

THREE_ACTIONS: tuple[str, ...] = ("F", "L", "R")
"""The three actions: forward one cell, turn left, turn right."""

_CLASS = {"F": "forward", "L": "turn-left", "R": "turn-right"}


def _apply(pose: Pose, action: str) -> Pose:
    if action == "F":
        dx, dy = pose.heading.vector
        return Pose(pose.x + dx, pose.y + dy, pose.heading)
    return Pose(pose.x, pose.y, pose.heading.rotated(-1 if action == "L" else 1))


def _footprint(pose: Pose, action: str) -> tuple[Cell, ...]:
    if action == "F":
        dx, dy = pose.heading.vector
        return (pose.cell, (pose.x + dx, pose.y + dy))
    return (pose.cell,)


def _duration(action: str) -> Fraction:
    return Fraction(1)


def _available(action: str, faults: frozenset[str]) -> bool:
    return action not in faults


def _parse_action(text: str) -> str:
    name = text.strip().upper()
    if name not in THREE_ACTIONS:
        raise InputError(
            f"expected a three-action robot action F, L or R, got {text!r}", source="<action>"
        )
    return name


def _format_action(action: str) -> str:
    return action


def _parse_faults(text: str) -> frozenset[str]:
    if not text.strip():
        return frozenset()
    return frozenset(_parse_action(p) for p in text.split(","))


def _format_faults(faults: Iterable[str]) -> str:
    return ",".join(sorted(faults, key=THREE_ACTIONS.index))


THREE_ACTION: Domain[str, str] = Domain(
    name="three-action",
    actions=THREE_ACTIONS,
    apply=_apply,
    footprint=_footprint,
    duration=_duration,
    available=_available,
    parse_action=_parse_action,
    format_action=_format_action,
    faults=THREE_ACTIONS,
    parse_faults=_parse_faults,
    format_faults=_format_faults,
    motion_class=_CLASS.__getitem__,
    footprint_connected=True,
    description="the three-action robot of the original paper's Table 1 (F, L, R)",
)
"""The three-action robot of the original paper's Table 1."""
