"""The names of the strategies and of where repaired actions come from.

:class:`StrategyName` lists every strategy the package ships, for one robot and for a team alike
(the registry, :mod:`selfrepair.repair.strategies.registry`, may hold more: plug-ins register
theirs under any other name). Code names a built-in strategy through this enum, never by a string
literal, so that renaming one is one edit and a misspelling fails at import.
"""

from __future__ import annotations

from enum import StrEnum

from selfrepair.errors import ProblemError

__all__ = ["MissionKind", "RepairSource", "StrategyName"]


class MissionKind(StrEnum):
    """Which kind of mission a strategy serves: one robot's plan of primitive actions, or a
    team's plans of higher-level actions (drive, pick, drop, handover)."""

    ROBOT = "robot"
    TEAM = "team"


class StrategyName(StrEnum):
    """Every built-in strategy.

    For one robot: ``replan``, ``replacement`` and ``lookahead``
    (:mod:`selfrepair.repair.strategies`), ``dstar-lite`` (:mod:`selfrepair.repair.dstar_lite`) and
    ``lpg-adapt`` (:mod:`selfrepair.baselines.adapt`); for faults the robot is not told
    (:mod:`selfrepair.repair.strategies.diagnosing` and ``.trial``): ``oracle``, ``diagnose``,
    ``conformant``, ``active-diagnosis`` and ``trial-and-error``. For a team
    (:mod:`selfrepair.team.strategies`): ``team-replacement``, ``reallocation`` and ``alone``.
    """

    REPLAN = "replan"
    REPLACEMENT = "replacement"
    LOOKAHEAD = "lookahead"
    DSTAR_LITE = "dstar-lite"
    LPG_ADAPT = "lpg-adapt"
    ORACLE = "oracle"
    DIAGNOSE = "diagnose"
    CONFORMANT = "conformant"
    ACTIVE_DIAGNOSIS = "active-diagnosis"
    TRIAL_AND_ERROR = "trial-and-error"
    TEAM_REPLACEMENT = "team-replacement"
    REALLOCATION = "reallocation"
    ALONE = "alone"

    @property
    def kind(self) -> MissionKind:
        """The kind of mission the strategy serves."""
        return MissionKind.TEAM if self in _TEAM else MissionKind.ROBOT

    @classmethod
    def of_kind(cls, kind: MissionKind) -> tuple[StrategyName, ...]:
        """The built-in strategies of ``kind``, in declaration order."""
        return tuple(name for name in cls if name.kind is kind)

    @classmethod
    def of(cls, value: object, kind: MissionKind) -> StrategyName:
        """``value`` as the name of a built-in strategy of ``kind``; anything else raises
        :class:`~selfrepair.errors.ProblemError` naming the allowed values."""
        allowed = cls.of_kind(kind)
        for name in allowed:
            if value == name:
                return name
        what = "strategy" if kind is MissionKind.ROBOT else f"{kind} strategy"
        raise ProblemError(f"unknown {what} {value!r}; expected one of {', '.join(allowed)}")


_TEAM = frozenset({StrategyName.TEAM_REPLACEMENT, StrategyName.REALLOCATION, StrategyName.ALONE})


class RepairSource(StrEnum):
    """Where the actions of a robot's repair came from (named after the strategy that made
    them, but for ``plan-repair``: a plan repaired by LPG-adapt, ``detour``: a local detour
    round cells believed blocked, from the replacement strategy's detour table, and ``probe``:
    commands that active diagnosis runs to tell fault hypotheses apart)."""

    REPLACEMENT = StrategyName.REPLACEMENT.value
    LOOKAHEAD = StrategyName.LOOKAHEAD.value
    REPLAN = StrategyName.REPLAN.value
    PLAN_REPAIR = "plan-repair"
    DETOUR = "detour"
    PROBE = "probe"
    """A command chosen to tell fault hypotheses apart (active diagnosis)."""
