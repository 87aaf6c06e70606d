"""A four-wheel domain identified from physics: what each action really does, snapped to the
lattice, as a :class:`~selfrepair.robots.domain.Domain` like any other.

``selfrepair physics fidelity --write-domain FILE`` measures every action in MuJoCo (tracked,
from rest on an open floor) and writes a JSON file of the actions whose end pose snaps to a
lattice pose (within :data:`SNAP_POSITION` cells and :data:`SNAP_HEADING` degrees), each with the
motion it snapped to and the cells its centre passed, and of the actions dropped, each with why.
:func:`identified_domain` turns such a file into a domain (no MuJoCo needed): its actions are the
kept ones, its motion the identified one, its footprint the lattice footprint of that motion with
every cell the centre passed, its durations, faults and text forms the four-wheel robot's.
Register it (``examples/physics_robot.py`` does, as a plug-in) and tables are generated for it
like for any robot. The bundled file, :data:`BUNDLED`, was written with the default parameters,
with ``--in-sequence``: each kept action also says whether it holds in sequence.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from selfrepair.errors import InputError, ProblemError
from selfrepair.geometry import Cell, Pose, relative_cell
from selfrepair.robots import four_wheel
from selfrepair.robots.domain import Domain, check_domain
from selfrepair.robots.four_wheel import Action, Fault

__all__ = [
    "BUNDLED",
    "CONFIRMED_NAME",
    "IN_SEQUENCE_NAME",
    "SNAP_HEADING",
    "SNAP_POSITION",
    "IdentifiedMotion",
    "identified_domain",
    "load_identified",
]

SNAP_POSITION = 0.25
"""An end position within this many cells of a cell centre snaps to that cell."""
SNAP_HEADING = 15.0
"""An end heading within this many degrees of one of the four headings snaps to it."""
CONFIRMED_NAME = "four-wheel-confirmed"
"""The name of the bundled identified domain's confirmed-only variant."""
IN_SEQUENCE_NAME = "four-wheel-in-sequence"
"""The name of the bundled identified domain's variant with only the actions that hold in
sequence (``selfrepair physics fidelity --in-sequence``: within 5% of a cell and 3 degrees after
each of a few other actions, not only from rest)."""
BUNDLED = "four-wheel-physics.json"
"""The bundled identified domain (package data under ``selfrepair/data/physics``)."""


@dataclass(frozen=True, slots=True)
class IdentifiedMotion:
    """What one action does in physics, in the robot's frame from a north-facing start:
    ``forward``/``lateral`` (right) cells, ``rotation`` quarter turns clockwise, and ``swept``,
    the ``(forward, lateral)`` cells of its footprint, the start cell first."""

    forward: int
    lateral: int
    rotation: int
    swept: tuple[Cell, ...]


def _motion_of(entry: Mapping[str, Any], source: str) -> tuple[Action, IdentifiedMotion]:
    try:
        action = four_wheel.parse_action(str(entry["action"]), source=source)
        swept = tuple((int(f), int(lat)) for f, lat in entry["swept"])
        motion = IdentifiedMotion(
            int(entry["forward"]), int(entry["lateral"]), int(entry["rotation"]), swept
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(
            f"expected an action entry with action, forward, lateral, rotation and swept, got "
            f"{entry!r} ({exc})",
            source=source,
        ) from None
    if not swept or swept[0] != (0, 0) or (motion.forward, motion.lateral) not in swept:
        raise InputError(
            f"action {action}: swept must start at [0, 0] and hold the end cell", source=source
        )
    return action, motion


def identified_domain(
    data: Mapping[str, Any],
    *,
    name: str | None = None,
    source: str = "<identified>",
    confirmed_only: bool = False,
    in_sequence_only: bool = False,
) -> Domain[Action, Fault]:
    """The domain of an identified-motion file's content (see the module docstring). With
    ``confirmed_only``, only the actions physics confirms (entries marked ``confirmed``: tracked
    within 5% of a cell and 3 degrees of the lattice), the robot that avoids what physics does
    not do as the lattice says. With ``in_sequence_only``, only the confirmed actions also marked
    ``in_sequence`` (within the same tolerances after each of a few other actions; the file must
    have been written with ``selfrepair physics fidelity --in-sequence --write-domain``)."""
    entries = data.get("actions")
    if not isinstance(entries, list) or not entries:
        raise InputError("expected a non-empty list 'actions'", source=source)
    if confirmed_only or in_sequence_only:  # in sequence: confirmed from rest, and after others
        entries = [e for e in entries if isinstance(e, Mapping) and e.get("confirmed") is True]
        if not entries:
            raise InputError("expected at least one action marked confirmed", source=source)
    if in_sequence_only:
        if not all(isinstance(e, Mapping) and "in_sequence" in e for e in entries):
            raise InputError(
                "expected every action marked in_sequence (a file written with the "
                "in-sequence fidelity measured)",
                source=source,
            )
        entries = [e for e in entries if e["in_sequence"] is True]
        if not entries:
            raise InputError("expected at least one action marked in_sequence", source=source)
    motions: dict[Action, IdentifiedMotion] = {}
    for entry in entries:
        action, motion = _motion_of(entry, source)
        motions[action] = motion
    actions = tuple(a for a in four_wheel.ACTIONS if a in motions)
    lattice = {a: (a.motion.forward, a.motion.lateral, a.motion.rotation, a.motion.swept)
               for a in actions}  # fmt: skip

    def apply(pose: Pose, action: Action) -> Pose:
        m = motions[action]
        x, y = relative_cell(pose, m.forward, m.lateral)
        return Pose(x, y, pose.heading.rotated(m.rotation))

    def footprint(pose: Pose, action: Action) -> tuple[Cell, ...]:
        return tuple(relative_cell(pose, f, lat) for f, lat in motions[action].swept)

    def motion_class(action: Action) -> str:
        m = motions[action]
        if (m.forward, m.lateral, m.rotation, m.swept) == lattice[action]:
            return action.motion.name
        cells = " ".join(f"{f},{lat}" for f, lat in m.swept)
        return f"moves {m.forward},{m.lateral},{m.rotation} via {cells}"

    def parse(text: str) -> Action:
        action = four_wheel.parse_action(text)
        if action not in motions:
            raise InputError(
                f"action {action} is not in the identified domain (physics dropped it)",
                source="<action>",
            )
        return action

    def level(action: Action) -> int:
        m = motions[action]
        return 1 if m.rotation and (m.forward or m.lateral) else 0

    waits = tuple(a for a in (four_wheel.parse_action("SSSS"),) if a in motions)
    kwargs: dict[str, Any] = {
        "name": name or str(data.get("domain", "four-wheel-physics")),
        "actions": actions,
        "apply": apply,
        "footprint": footprint,
        "duration": four_wheel.duration,
        "available": four_wheel.available,
        "parse_action": parse,
        "format_action": lambda a: a.code,
        "faults": four_wheel.SINGLE_FAULTS,
        "parse_faults": four_wheel.parse_faults,
        "format_faults": four_wheel.format_faults,
        "motion_class": motion_class,
        "level": level,
        "fault_sets": four_wheel.FOUR_WHEEL.fault_sets,
        "fault_parts": lambda fault: (fault.wheel.name, fault.mode.letter),
        "wait_actions": waits,
        "description": "four-wheel robot as MuJoCo drives it: "
        f"{len(actions)} of 81 actions (identified from physics)",
    }
    if in_sequence_only:
        kwargs["description"] = (
            f"four-wheel robot, only the {len(actions)} actions MuJoCo confirms in sequence "
            "(identified from physics)"
        )
    elif confirmed_only:
        kwargs["description"] = (
            f"four-wheel robot, only the {len(actions)} actions MuJoCo confirms (identified from "
            "physics)"
        )
    domain: Domain[Action, Fault] = Domain(footprint_connected=True, **kwargs)
    try:
        check_domain(domain)
    except ProblemError:  # some identified footprint is not a shortest 4-connected path
        domain = Domain(footprint_connected=False, **kwargs)
    return domain


def load_identified(
    path: str | Path | None = None,
    *,
    name: str | None = None,
    confirmed_only: bool = False,
    in_sequence_only: bool = False,
) -> Domain[Action, Fault]:
    """The identified domain of the JSON file ``path`` (``None``: the bundled one); see
    :func:`identified_domain` for ``confirmed_only`` and ``in_sequence_only``."""
    if path is None:
        text = resources.files("selfrepair").joinpath("data", "physics", BUNDLED).read_text("utf-8")
        source = f"<bundled {BUNDLED}>"
    else:
        source = str(path)
        try:
            text = Path(path).read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(
                f"cannot read the identified domain: {exc.strerror}", source=source
            ) from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"expected JSON: {exc.msg}", source=source, line=exc.lineno) from None
    if not isinstance(data, dict):
        raise InputError("expected a JSON object", source=source)
    return identified_domain(
        data,
        name=name,
        source=source,
        confirmed_only=confirmed_only,
        in_sequence_only=in_sequence_only,
    )
