"""A changing world: cells that become blocked or free during a mission (a door that closes, a
box dropped, a person standing), and how the robot senses them.

A :class:`WorldSchedule` is a tuple of :class:`WorldEvent` values plus a sensing model. Each event
says that one cell becomes **blocked** or **free** at an integer time ``at`` in ticks (elapsed
mission time, failed attempts included, as a fault event's ``clock = "tick"``). The maze's walls
never change; an event blocks a free cell of the maze or frees a cell an earlier event blocked
(a free event on a cell that is not blocked changes nothing). Events at the same time apply in
schedule order. The true occupancy at time ``t`` is a pure function of the schedule
(:meth:`WorldSchedule.blocked_at`), so the simulator and a replay compute the same world without
sharing state.

Motion under a changing world: a motion is executable when every cell it sweeps is free at the
time it starts, **except the cell the robot stands on**: an obstacle that appears on the robot's
own cell (a person stepping up to it) never traps it; every other swept cell must be free. A
motion that would sweep a blocked cell does not happen: the robot **bumps** (it stays where it
is, one tick passes, as for a failed attempt) and learns the blocked cells it touched.

Sensing (:class:`Sensing`):

``range``
    Before every step the robot sees the true state of every cell within Chebyshev distance
    ``sensing_range`` of its cell (a ring of range sensors): cells that became blocked and cells
    that became free again. With a range at least the robot's reach (2 cells for the four-wheel
    robot) it never bumps.
``bump``
    The robot learns of a blocked cell only by bumping into it (a bumper), and never learns that
    it became free again: what it believes blocked stays blocked for the rest of the mission.

Text form (the command line's ``--events``, an experiment file's ``events``): events separated by
``;``, each ``X,Y@T`` (blocked from tick ``T`` on), ``X,Y@T..U`` (blocked from ``T``, free again
from ``U``) or ``-X,Y@T`` (free from ``T``). :func:`random_world` draws a schedule from a seeded
generator: obstacles appearing at a given rate near a route, each staying a given time.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction
from typing import Any

import numpy as np

from selfrepair.errors import InputError, choice
from selfrepair.geometry import Cell
from selfrepair.limits import DEFAULT_SENSING_RANGE
from selfrepair.textio import JSONObject

__all__ = [
    "DEFAULT_SENSING_RANGE",
    "Sensing",
    "WorldEvent",
    "WorldSchedule",
    "parse_events",
    "random_world",
]


class Sensing(StrEnum):
    """How the robot learns of blocked cells (see the module docstring)."""

    RANGE = "range"
    BUMP = "bump"


@dataclass(frozen=True, slots=True)
class WorldEvent:
    """Cell ``cell`` becomes blocked (``blocked``) or free again at tick ``at``."""

    cell: Cell
    blocked: bool = True
    at: int = 0

    def __post_init__(self) -> None:
        if self.at < 0:
            raise InputError(f"expected an event time >= 0, got {self.at}", source="<events>")
        x, y = self.cell
        if x < 0 or y < 0:
            raise InputError(f"expected a cell on the grid, got {self.cell}", source="<events>")

    def to_json(self) -> JSONObject:
        """A JSON-able dict."""
        return {"cell": [self.cell[0], self.cell[1]], "blocked": self.blocked, "at": self.at}

    @classmethod
    def from_json(cls, data: Mapping[str, Any], source: str = "<events>") -> WorldEvent:
        """Read what :meth:`to_json` wrote."""
        try:
            x, y = data["cell"]
            return cls((int(x), int(y)), bool(data.get("blocked", True)), int(data.get("at", 0)))
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, InputError):
                raise InputError(exc.reason, source=source) from None
            raise InputError(
                f"expected a world event with 'cell': [x, y], got {dict(data)!r}", source=source
            ) from None


@dataclass(frozen=True, slots=True)
class WorldSchedule:
    """Every world event of a mission, sorted by time (stably), and how the robot senses them."""

    events: tuple[WorldEvent, ...] = ()
    sensing: Sensing = Sensing.RANGE
    sensing_range: int = DEFAULT_SENSING_RANGE

    def __post_init__(self) -> None:
        sensing = choice(Sensing, self.sensing, "sensing", source="<events>")
        object.__setattr__(self, "sensing", sensing)
        if self.sensing_range < 0:
            raise InputError(
                f"expected a sensing range >= 0, got {self.sensing_range}", source="<events>"
            )
        object.__setattr__(
            self, "events", tuple(sorted(self.events, key=lambda e: e.at))
        )  # sorted() is stable: events at one time keep their order

    def __bool__(self) -> bool:
        return bool(self.events)

    def cells(self) -> tuple[Cell, ...]:
        """Every cell an event names, first mention first (the cells that can change)."""
        return tuple(dict.fromkeys(e.cell for e in self.events))

    def blocked_at(self, tick: float | Fraction) -> frozenset[Cell]:
        """The cells blocked at time ``tick`` (events at ``at <= tick`` applied in order): the
        reference the simulator's incremental world is tested against."""
        blocked: dict[Cell, None] = {}
        for event in self.events:
            if event.at > tick:
                break
            if event.blocked:
                blocked[event.cell] = None
            else:
                blocked.pop(event.cell, None)
        return frozenset(blocked)

    def describe(self) -> str:
        """A short summary such as ``"3 world events, sensing range 2"``."""
        if not self.events:
            return "no world events"
        how = f"range {self.sensing_range}" if self.sensing is Sensing.RANGE else "bump"
        return f"{len(self.events)} world events, sensing {how}"

    def to_json(self) -> JSONObject:
        """A JSON-able dict (for traces and rows)."""
        return {
            "events": [e.to_json() for e in self.events],
            "sensing": self.sensing.value,
            "range": self.sensing_range,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], source: str = "<events>") -> WorldSchedule:
        """Read what :meth:`to_json` wrote."""
        events = data.get("events", [])
        if not isinstance(events, list):
            raise InputError("expected 'events' to be a list", source=source)
        try:
            reach = int(data.get("range", DEFAULT_SENSING_RANGE))
        except (TypeError, ValueError):
            raise InputError(f"expected an integer range, got {data.get('range')!r}",
                             source=source) from None  # fmt: skip
        return cls(
            tuple(WorldEvent.from_json(e, source) for e in events),
            str(data.get("sensing", Sensing.RANGE.value)),  # type: ignore[arg-type]
            reach,
        )


def _int(text: str, what: str, source: str) -> int:
    try:
        value = int(text.strip())
    except ValueError:
        raise InputError(f"expected {what} as an integer, got {text.strip()!r}",
                         source=source) from None  # fmt: skip
    if value < 0:
        raise InputError(f"expected {what} >= 0, got {value}", source=source)
    return value


def parse_events(text: str, *, source: str = "--events") -> tuple[WorldEvent, ...]:
    """The events of the text form (see the module docstring); errors name ``source`` and the
    event (by its number, from 1) that is wrong."""
    out: list[WorldEvent] = []
    for number, raw in enumerate(text.split(";"), start=1):
        part = raw.strip()
        if not part:
            continue
        where = f"{source}, event {number}"
        free = part.startswith("-")
        body = part[1:] if free else part
        cell_text, at_sign, when = body.partition("@")
        if not at_sign:
            raise InputError(f"expected X,Y@T, X,Y@T..U or -X,Y@T, got {part!r}", source=where)
        coords = cell_text.split(",")
        if len(coords) != 2:
            raise InputError(f"expected a cell X,Y before '@', got {cell_text!r}", source=where)
        cell = (_int(coords[0], "x", where), _int(coords[1], "y", where))
        start, dots, end = when.partition("..")
        at = _int(start, "the time T", where)
        if free and dots:
            raise InputError(f"a free event takes one time, got {when!r}", source=where)
        out.append(WorldEvent(cell, not free, at))
        if dots:
            until = _int(end, "the time U", where)
            if until <= at:
                raise InputError(f"expected U > T in X,Y@T..U, got {when!r}", source=where)
            out.append(WorldEvent(cell, False, until))
    return tuple(out)


def random_world(
    route: Sequence[Cell],
    free: Iterable[Cell],
    *,
    seed: int | Sequence[int],
    rate: float,
    duration: int | None,
    distance: int,
    horizon: int,
    exclude: Iterable[Cell] = (),
    sensing: Sensing = Sensing.RANGE,
    sensing_range: int = DEFAULT_SENSING_RANGE,
) -> WorldSchedule:
    """A seeded random schedule: obstacles appear at ``rate`` per 100 ticks (a Poisson process,
    over ``[0, horizon)`` ticks), each on a cell drawn uniformly from the ``free`` cells within
    Chebyshev ``distance`` of a cell of ``route`` (but not in ``exclude``, e.g. the start and
    goal cells), and stay ``duration`` ticks (``None``: for good). A cell still blocked is not
    drawn again until it is free. The generator is ``numpy.random.default_rng(seed)``: the same
    seed gives the same schedule."""
    if rate < 0 or distance < 0 or horizon < 0 or (duration is not None and duration < 1):
        raise InputError(
            "expected rate >= 0, distance >= 0, horizon >= 0 and duration >= 1",
            source="<random world>",
        )
    near = {c for x, y in route for c in _ball(x, y, distance)}
    banned = set(exclude)
    cells = [c for c in free if c in near and c not in banned]  # in the order of ``free``
    rng = np.random.default_rng(seed)
    events: list[WorldEvent] = []
    if not cells or rate == 0:
        return WorldSchedule((), sensing, sensing_range)
    until: dict[Cell, float] = {}
    t = float(rng.exponential(100.0 / rate))
    while t < horizon:
        cell = cells[int(rng.integers(len(cells)))]
        at = int(t)
        if until.get(cell, -1.0) <= at:
            events.append(WorldEvent(cell, True, at))
            if duration is None:
                until[cell] = float("inf")
            else:
                events.append(WorldEvent(cell, False, at + duration))
                until[cell] = at + duration
        t += float(rng.exponential(100.0 / rate))
    return WorldSchedule(tuple(events), sensing, sensing_range)


def _ball(x: int, y: int, r: int) -> Iterable[Cell]:
    return ((x + dx, y + dy) for dy in range(-r, r + 1) for dx in range(-r, r + 1))
