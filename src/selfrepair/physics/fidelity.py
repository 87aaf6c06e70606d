"""The model fidelity report: every action run in MuJoCo against what the lattice says it does.

For every action of the four-wheel robot, :func:`measure` puts the robot at rest at the origin
facing north on an open floor, runs the action for its duration open loop and again tracked
(:mod:`selfrepair.physics.tracker`), and compares each end pose with the lattice's end pose: the
position error in cells and the heading error in degrees. Physics *confirms* an action when its
tracked end is within :data:`CONFIRM_POSITION` cells (5% of a cell) and :data:`CONFIRM_HEADING`
degrees of the lattice's. The tracked end also gives the action's identified motion (snapped to
the lattice, or dropped when it does not snap; see :mod:`selfrepair.physics.identified`), written
by :meth:`FidelityReport.identified`.

From rest is not how a mission runs an action: there it starts where the last one left the robot,
its wheels still turning. :func:`measure_in_sequence` runs every action tracked after each of a
few preceding actions (:data:`PREDECESSORS`, then the action itself) from the origin on the same
open floor, and reports the worst end error over them (a :class:`SequenceRow`): an action *holds
in sequence* when it is within the confirmation tolerances after every one.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass, replace
from typing import Any

from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.physics.identified import SNAP_HEADING, SNAP_POSITION
from selfrepair.physics.model import DEFAULT_PARAMS, RobotParams
from selfrepair.physics.simulator import lattice_motion, wheel_commands
from selfrepair.physics.tracker import ContinuousPose, wrap
from selfrepair.physics.world import PhysicsWorld, pose_error, snap
from selfrepair.robots.domain import SomeDomain
from selfrepair.robots.four_wheel import FOUR_WHEEL

__all__ = [
    "CONFIRM_HEADING",
    "CONFIRM_POSITION",
    "PREDECESSORS",
    "FidelityReport",
    "FidelityRow",
    "SequenceReport",
    "SequenceRow",
    "faulty_rows",
    "measure",
    "measure_in_sequence",
]

CONFIRM_POSITION = 0.05
"""Physics confirms an action whose tracked end lies within this many cells of the lattice's."""
CONFIRM_HEADING = 3.0
"""... and whose tracked end heading lies within this many degrees of the lattice's."""

_ORIGIN = Pose(0, 0, Heading.N)

PREDECESSORS = ("FFFF", "BBBB", "SFFS", "FBFB", "BFBF")
"""The actions :func:`measure_in_sequence` runs before each action (then the action itself):
forward and backward at full speed, an arc, and the spins on all four wheels both ways."""


@dataclass(frozen=True, slots=True)
class FidelityRow:
    """One action's run (see the module docstring). ``faults`` and ``behaviour`` are empty for
    the nominal robot; ``executed`` is the action physics ran (the commanded one unless a fault
    behaviour says the actuators do otherwise). ``snapped`` is the tracked end as ``(forward,
    lateral, rotation)`` from a north-facing start, ``None`` when it does not snap (``why``);
    ``swept`` the ``(forward, lateral)`` cells the robot's centre passed."""

    action: str
    motion: str
    faults: str
    behaviour: str
    executed: str
    open_position: float
    open_heading: float
    tracked_position: float
    tracked_heading: float
    snapped: tuple[int, int, int] | None
    swept: tuple[Cell, ...]
    why: str

    @property
    def confirmed(self) -> bool:
        """Whether the tracked end is within the confirmation tolerances."""
        return self.tracked_position < CONFIRM_POSITION and self.tracked_heading < CONFIRM_HEADING

    @property
    def open_confirmed(self) -> bool:
        """Whether the open-loop end is within the confirmation tolerances."""
        return self.open_position < CONFIRM_POSITION and self.open_heading < CONFIRM_HEADING


@dataclass(frozen=True, slots=True)
class FidelityReport:
    """Every row, the parameters they were measured with, and the summary figures."""

    rows: tuple[FidelityRow, ...]
    params: RobotParams

    def nominal(self) -> tuple[FidelityRow, ...]:
        """The rows of the fault-free robot."""
        return tuple(r for r in self.rows if not r.faults)

    def summary(self) -> dict[str, Any]:
        """Counts and shares of confirmed actions, open loop and tracked, nominal and faulty."""
        out: dict[str, Any] = {}
        groups = [("nominal", self.nominal())]
        for behaviour in dict.fromkeys(r.behaviour for r in self.rows if r.faults):
            rows = tuple(r for r in self.rows if r.faults and r.behaviour == behaviour)
            groups.append((f"faulty ({behaviour})", rows))
        for label, rows in groups:
            if not rows:
                continue
            n = len(rows)
            tracked = sum(r.confirmed for r in rows)
            opened = sum(r.open_confirmed for r in rows)
            out[label] = {
                "actions": n,
                "tracked_confirmed": tracked,
                "tracked_share": round(tracked / n, 4),
                "open_loop_confirmed": opened,
                "open_loop_share": round(opened / n, 4),
                "snapped": sum(r.snapped is not None for r in rows),
                "tracked_position_median": round(_median([r.tracked_position for r in rows]), 4),
                "tracked_heading_median": round(_median([r.tracked_heading for r in rows]), 3),
                "open_position_median": round(_median([r.open_position for r in rows]), 4),
                "open_heading_median": round(_median([r.open_heading for r in rows]), 3),
            }
        return out

    def identified(
        self, name: str = "four-wheel-physics", sequence: SequenceReport | None = None
    ) -> dict[str, Any]:
        """The identified-domain file's content (:mod:`selfrepair.physics.identified`) from the
        nominal rows: the actions that snap, then the dropped ones with why. With ``sequence``
        (:func:`measure_in_sequence` of the same actions), each kept action is also marked
        ``in_sequence`` (it holds after every predecessor) with its worst errors there, and the
        predecessors are recorded."""
        held = {} if sequence is None else {r.action: r for r in sequence.rows}
        kept, dropped = [], []
        for row in self.nominal():
            if row.snapped is None:
                dropped.append({"action": row.action, "reason": row.why})
                continue
            forward, lateral, rotation = row.snapped
            kept.append({
                "action": row.action,
                "forward": forward,
                "lateral": lateral,
                "rotation": rotation,
                "swept": [list(c) for c in row.swept],
                "position_error": round(row.tracked_position, 4),
                "heading_error": round(row.tracked_heading, 3),
                "confirmed": row.confirmed,
            })  # fmt: skip
            if sequence is not None:
                seq = held.get(row.action)
                kept[-1]["in_sequence"] = seq is not None and seq.holds
                if seq is not None:
                    kept[-1]["in_sequence_position_error"] = round(seq.worst_position, 4)
                    kept[-1]["in_sequence_heading_error"] = round(seq.worst_heading, 3)
        out: dict[str, Any] = {
            "domain": name,
            "made_by": "selfrepair physics fidelity --write-domain",
            "snap": {"position_cells": SNAP_POSITION, "heading_degrees": SNAP_HEADING},
            "params": asdict(self.params),
            "actions": kept,
            "dropped": dropped,
        }
        if sequence is not None:
            out["in_sequence_after"] = [*sequence.predecessors, "itself"]
        return out


def _median(values: list[float]) -> float:
    ordered = sorted(values)
    if not ordered:
        return 0.0
    mid = len(ordered) // 2
    return ordered[mid] if len(ordered) % 2 else (ordered[mid - 1] + ordered[mid]) / 2


def _snap(
    end: ContinuousPose, cells: list[Cell], lattice: Pose
) -> tuple[tuple[int, int, int] | None, tuple[Cell, ...], str]:
    """The identified motion of an end pose from the origin facing north, the cells its centre
    passed (robot frame, the start first, the lattice footprint added when the motion matches)
    and, when it does not snap, why."""
    near = snap(end)
    off = math.hypot(end.x - near.x, end.y + near.y)
    yaw_off = abs(math.degrees(wrap(end.yaw - (math.pi / 2 - int(near.heading) * math.pi / 2))))
    if off > SNAP_POSITION:
        return None, (), f"ends {off:.2f} cells from the nearest cell centre"
    if yaw_off > SNAP_HEADING:
        return None, (), f"ends {yaw_off:.1f} degrees off the nearest heading"
    motion = (-near.y, near.x, (int(near.heading) + 2) % 4 - 2)
    swept = list(dict.fromkeys([(0, 0), *cells, (motion[0], motion[1])]))
    if near == lattice:
        return motion, tuple(swept), ""
    return motion, tuple(swept), f"snaps to {near}, not the lattice's {lattice}"


def measure(
    domain: SomeDomain = FOUR_WHEEL,
    params: RobotParams = DEFAULT_PARAMS,
    actions: Iterable[object] | None = None,
    *,
    faulty: bool = True,
) -> FidelityReport:
    """Run every action of ``domain`` (or ``actions``) nominally, open loop and tracked, and
    report each against the lattice (see the module docstring); with ``faulty``, also every
    action under every single fault that forbids it, for each of the domain's fault-behaviour
    models (:func:`faulty_rows`)."""
    world = PhysicsWorld(None, _ORIGIN, params)
    centre: list[Cell] = []

    def visit(w: PhysicsWorld) -> None:
        p = w.pose()
        cell = (round(p.y), round(p.x))  # (forward, lateral) from the origin facing north
        if not centre or centre[-1] != cell:
            centre.append(cell)

    rows = []
    for action in domain.actions if actions is None else actions:
        commands = wheel_commands(domain, action)
        target = domain.apply(_ORIGIN, action)
        ticks = domain.duration(action)
        world.observer = None
        world.place(_ORIGIN)
        opened = pose_error(world.run(commands, ticks).end, target)
        world.place(_ORIGIN)
        centre.clear()
        world.observer = visit
        end = world.run(
            commands, ticks, motion=lattice_motion(domain, action), reference_start=_ORIGIN
        ).end
        tracked = pose_error(end, target)
        lattice_cells = [c for c in domain.footprint(_ORIGIN, action)]
        snapped, swept, why = _snap(end, centre, target)
        if snapped is not None and snap(end) == target:
            lattice_rf = [(-y, x) for x, y in lattice_cells]
            swept = tuple(dict.fromkeys([*lattice_rf, *swept]))
        text = domain.format_action(action)
        rows.append(
            FidelityRow(
                text,
                domain.motion_class(action),
                "",
                "",
                text,
                opened[0],
                opened[1],
                tracked[0],
                tracked[1],
                snapped,
                swept,
                why,
            )
        )
    world.observer = None
    if faulty:
        rows += faulty_rows(domain, rows)
    return FidelityReport(tuple(rows), params)


def faulty_rows(domain: SomeDomain, nominal: list[FidelityRow]) -> list[FidelityRow]:
    """The rows of every action under every single fault that forbids it, per fault-behaviour
    model of ``domain`` (behaviour by behaviour, fault by fault, action by action).

    A fault acts on the actuators: the wheels perform the action
    :meth:`Domain.effective <selfrepair.robots.domain.Domain.effective>` says, and physics runs
    exactly those wheel commands (the tracker, which knows only the wheels' signs, follows that
    action's lattice motion), from the same rest pose. So a faulty row carries the measurement
    of the performed action (when it was measured: rows of actions not in ``nominal`` are left
    out), compared with the lattice's end pose of that action: whether physics confirms what the
    fault model says the faulty robot does."""
    by_action = {row.action: row for row in nominal}
    out = []
    for behaviour in domain.behaviours:
        for fault in domain.faults:
            faults = frozenset((fault,))
            for action in domain.actions:
                if domain.available(action, faults):
                    continue
                performed = domain.format_action(domain.effective(action, faults, behaviour.name))
                row = by_action.get(performed)
                if row is None:
                    continue
                out.append(
                    replace(
                        row,
                        action=domain.format_action(action),
                        motion=domain.motion_class(action),
                        faults=domain.format_faults(faults),
                        behaviour=behaviour.name,
                        executed=performed,
                    )
                )
    return out


@dataclass(frozen=True, slots=True)
class SequenceRow:
    """One action run tracked after each predecessor (``after``: the predecessor's text, then
    the action's end position error in cells and heading error in degrees there) and the worst
    of them. ``from_rest`` is whether :func:`measure` confirms it from rest."""

    action: str
    motion: str
    after: tuple[tuple[str, float, float], ...]
    from_rest: bool

    @property
    def worst_position(self) -> float:
        """The largest end position error (cells) over the predecessors."""
        return max(p for _, p, _ in self.after)

    @property
    def worst_heading(self) -> float:
        """The largest end heading error (degrees) over the predecessors."""
        return max(h for _, _, h in self.after)

    @property
    def holds(self) -> bool:
        """Whether the action is within the confirmation tolerances after every predecessor."""
        return all(p < CONFIRM_POSITION and h < CONFIRM_HEADING for _, p, h in self.after)


@dataclass(frozen=True, slots=True)
class SequenceReport:
    """The in-sequence rows and the predecessors they were run after."""

    rows: tuple[SequenceRow, ...]
    predecessors: tuple[str, ...]

    def summary(self) -> dict[str, Any]:
        """Per motion kind (the motion class's first word) and in all: actions, how many
        physics confirms from rest, how many hold in sequence, and the median worst error."""
        groups: dict[str, list[SequenceRow]] = {"all": list(self.rows)}
        for row in self.rows:
            groups.setdefault(row.motion.split("-")[0], []).append(row)
        return {
            kind: {
                "actions": len(rows),
                "from_rest": sum(r.from_rest for r in rows),
                "in_sequence": sum(r.holds for r in rows),
                "worst_position_median": round(_median([r.worst_position for r in rows]), 4),
                "worst_heading_median": round(_median([r.worst_heading for r in rows]), 3),
            }
            for kind, rows in groups.items()
        }


def measure_in_sequence(
    domain: SomeDomain = FOUR_WHEEL,
    params: RobotParams = DEFAULT_PARAMS,
    actions: Iterable[object] | None = None,
    predecessors: Iterable[str] = PREDECESSORS,
    *,
    from_rest: FidelityReport | None = None,
) -> SequenceReport:
    """Run every action of ``domain`` (or ``actions``) tracked after each of ``predecessors``
    (action texts) and after itself, each pair from rest at the origin facing north on an open
    floor, the action's reference starting at the predecessor's lattice end (as in a mission,
    where the robot is localised on the lattice); see the module docstring. ``from_rest`` is the
    from-rest report to mark confirmed actions from (measured when not given)."""
    chosen = list(domain.actions if actions is None else actions)
    rest = from_rest if from_rest is not None else measure(domain, params, chosen, faulty=False)
    confirmed = {r.action for r in rest.nominal() if r.confirmed}
    before = [domain.parse_action(text) for text in predecessors]
    world = PhysicsWorld(None, _ORIGIN, params)
    rows = []
    for action in chosen:
        text = domain.format_action(action)
        after = []
        for first in (*before, action):
            world.place(_ORIGIN)
            pose = _ORIGIN
            for a in (first, action):
                run = world.run(
                    wheel_commands(domain, a), domain.duration(a),
                    motion=lattice_motion(domain, a), reference_start=pose,
                )  # fmt: skip
                pose = domain.apply(pose, a)
            position, heading = pose_error(run.end, pose)
            after.append((domain.format_action(first), position, heading))
        rows.append(SequenceRow(text, domain.motion_class(action), tuple(after), text in confirmed))
    return SequenceReport(tuple(rows), tuple(predecessors))
