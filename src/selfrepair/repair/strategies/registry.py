"""The one registry of repair strategies, for every kind of mission.

An entry (:class:`StrategyEntry`) names a strategy, says which kind of mission it serves
(:class:`Kind`: one robot or a team, typed by the context the strategy starts with, what it is
asked and what it answers), holds its factory and says whether the caller must load a
replacement table for it. Every strategy registers itself where it is defined: the ``replan``,
``replacement`` and ``lookahead`` modules of this package, :mod:`selfrepair.repair.dstar_lite`,
:mod:`selfrepair.baselines.adapt` (``lpg-adapt``) and :mod:`selfrepair.team.strategies` (the team
strategies); a plug-in calls :func:`register_strategy` the same way. No module of a lower layer
names one of a higher layer: a strategy is in the registry once its module is imported, and the
layer that runs missions of its kind imports it (:mod:`selfrepair.execution` imports the
baselines, the team engine the team strategies).

Look-ups are by kind, so a robot mission cannot be given a team strategy by mistake:
:func:`get_strategy` for one robot, :func:`strategy_for` for any kind; :func:`strategy_names`
lists the names of a kind in the order they were registered (built-ins first).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, cast

from typing_extensions import TypeVar

from selfrepair.errors import ProblemError
from selfrepair.repair.strategies.names import MissionKind
from selfrepair.repair.strategies.protocol import (
    MissionContext,
    Repair,
    Repairer,
    RepairRequest,
    StrategyFactory,
)

__all__ = [
    "ROBOT",
    "Kind",
    "StrategyEntry",
    "get_strategy",
    "register",
    "register_strategy",
    "strategy_entries",
    "strategy_entry",
    "strategy_for",
    "strategy_names",
    "uses_table",
]

Context = TypeVar("Context", default=MissionContext)
Request = TypeVar("Request", default=RepairRequest)
Answer = TypeVar("Answer", default=Repair)


@dataclass(frozen=True, slots=True)
class Kind(Generic[Context, Request, Answer]):
    """A kind of mission, typed by what its strategies start with (``Context``), are asked
    (``Request``) and answer (``Answer``). Two kinds are equal when their names are."""

    name: MissionKind


ROBOT: Kind[MissionContext, RepairRequest, Repair] = Kind(MissionKind.ROBOT)
"""One robot's mission: started with a :class:`MissionContext`, asked :class:`RepairRequest`."""


@dataclass(frozen=True, slots=True)
class StrategyEntry(Generic[Context, Request, Answer]):
    """A registered strategy: its name, the kind of mission it serves, its factory, and whether
    the caller loads the mission's replacement table for it."""

    name: str
    kind: Kind[Context, Request, Answer]
    start: Callable[[Context], Repairer[Request, Answer]]
    uses_table: bool = False
    told: bool = False
    """Whether the strategy is an oracle: the robot is told its true faults before every
    command whatever the detection (the upper bound of diagnosis; see docs/diagnosis.md)."""
    hidden: bool = False
    """Whether the strategy is one for faults the robot is not told (detection ``hidden``): the
    diagnosing strategies and their oracle. A comparison runs these by default when the faults
    are hidden, and the others when they are not."""


_REGISTRY: dict[str, StrategyEntry[Any, Any, Any]] = {}
"""Every registered strategy by name, in the order registered."""


def register(entry: StrategyEntry[Context, Request, Answer], *, replace: bool = False) -> None:
    """Add ``entry`` to the registry. A name in use (by another factory) raises
    :class:`ProblemError` unless ``replace``."""
    known = _REGISTRY.get(entry.name)
    if known is not None and known != entry and not replace:
        raise ProblemError(f"a strategy named {entry.name!r} is already registered")
    _REGISTRY[entry.name] = entry


def register_strategy(
    name: str,
    factory: StrategyFactory,
    *,
    replace: bool = False,
    uses_table: bool = False,
    told: bool = False,
    hidden: bool = False,
) -> None:
    """Make ``factory`` available as the robot strategy ``name`` (``uses_table``: the executor
    loads the mission's table for it; ``told``: an oracle, told its true faults; ``hidden``: a
    strategy for faults the robot is not told). A name in use raises :class:`ProblemError`
    unless ``replace``."""
    register(StrategyEntry(name, ROBOT, factory, uses_table, told, hidden), replace=replace)


def strategy_entry(
    name: str, kind: Kind[Context, Request, Answer]
) -> StrategyEntry[Context, Request, Answer]:
    """The entry of strategy ``name`` of ``kind``; an unknown name, or one of another kind,
    raises :class:`ProblemError`."""
    entry = _REGISTRY.get(name)
    if entry is None or entry.kind != kind:
        serves = "" if entry is None else f" ({name!r} serves {entry.kind.name} missions)"
        what = "strategy" if kind == ROBOT else f"{kind.name} strategy"
        raise ProblemError(
            f"unknown {what} {name!r}{serves}; expected one of "
            f"{', '.join(strategy_names(kind))}"
        )
    return cast("StrategyEntry[Context, Request, Answer]", entry)


def strategy_for(
    name: str, kind: Kind[Context, Request, Answer]
) -> Callable[[Context], Repairer[Request, Answer]]:
    """The factory of strategy ``name`` of ``kind`` (see :func:`strategy_entry`)."""
    return strategy_entry(name, kind).start


def get_strategy(name: str) -> StrategyFactory:
    """The factory of robot strategy ``name``; unknown names raise :class:`ProblemError`."""
    return strategy_entry(name, ROBOT).start


def uses_table(name: str) -> bool:
    """Whether robot strategy ``name`` needs the mission's replacement table."""
    return strategy_entry(name, ROBOT).uses_table


def strategy_entries(kind: Kind[Any, Any, Any] = ROBOT) -> tuple[StrategyEntry[Any, Any, Any], ...]:
    """The registered strategies of ``kind``, in the order registered."""
    return tuple(e for e in _REGISTRY.values() if e.kind == kind)


def strategy_names(kind: Kind[Any, Any, Any] = ROBOT) -> tuple[str, ...]:
    """Every strategy name of ``kind`` that the registry holds, built-ins first."""
    return tuple(e.name for e in strategy_entries(kind))
