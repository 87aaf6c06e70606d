"""Repair strategies: what a mission does when the next action cannot go on.

The package is split by responsibility; this module exports the public names, so callers import
from ``selfrepair.repair.strategies`` alone:

- :mod:`~.names`: :class:`StrategyName` (every built-in strategy, for a robot and for a team),
  :class:`MissionKind`, :class:`RepairSource`;
- :mod:`~.options`: :class:`StrategyOptions`;
- :mod:`~.protocol`: the lifecycle (a factory started with the mission's context gives a
  :class:`Repairer`, asked once per repair), :class:`MissionContext`, :class:`RepairRequest`,
  :class:`Repair`;
- :mod:`~.registry`: the one registry of every kind of strategy (:func:`register_strategy`,
  :func:`get_strategy`, :func:`strategy_for`, :func:`strategy_names`);
- one module per built-in robot strategy (each registers itself on import):

``replan`` (:mod:`~.replan`)
    The original baseline: plan from scratch from the current pose with the known faults.
``replacement`` (:mod:`~.replacement`)
    Look the faulty action up in the replacement table and take the first valid candidate (in the
    chosen recursion mode); fall back to ``replan`` when none is valid (compiled look-ups; with
    ``StrategyOptions.rewrite``, whole-plan rewriting).
``lookahead`` (:mod:`~.lookahead`)
    Replace a window of the plan by the cheapest sub-plan to the window's end pose, found by a
    bounded A*; fall back to ``replacement``, then ``replan``.

Two baselines from neighbouring fields register themselves where they are built:
``dstar-lite``, incremental replanning (:mod:`selfrepair.repair.dstar_lite`, imported by
:mod:`selfrepair.repair`), and ``lpg-adapt``, plan repair with LPG-adapt
(:mod:`selfrepair.baselines.adapt`, needs the ``pddl`` extra; imported by
:mod:`selfrepair.execution`). The team strategies register in the same registry
(:mod:`selfrepair.team.strategies`).

This package is domain-generic and knows no maze: everything about the world comes in through the
context as values and functions, so the same strategies run any robot on any map.
"""

from __future__ import annotations

from selfrepair.repair.strategies.diagnosing import (  # registers
    DiagnosingRepairer,
    diagnosis_report,
)
from selfrepair.repair.strategies.lookahead import lookahead, start_lookahead
from selfrepair.repair.strategies.names import MissionKind, RepairSource, StrategyName
from selfrepair.repair.strategies.options import StrategyOptions
from selfrepair.repair.strategies.protocol import (
    Assumption,
    Belief,
    FunctionRepairer,
    MissionContext,
    PlanFn,
    Repair,
    Repairer,
    RepairRequest,
    StrategyFactory,
    chained,
    stateless,
)
from selfrepair.repair.strategies.registry import (
    ROBOT,
    Kind,
    StrategyEntry,
    get_strategy,
    register,
    register_strategy,
    strategy_entries,
    strategy_entry,
    strategy_for,
    strategy_names,
    uses_table,
)
from selfrepair.repair.strategies.replacement import (
    DeferringRepairer,
    ReplacementRepairer,
    replacement,
    start_replacement,
)
from selfrepair.repair.strategies.replan import replan
from selfrepair.repair.strategies.trial import TrialRepairer  # registers
from selfrepair.status import RepairStatus

__all__ = [
    "ROBOT",
    "Assumption",
    "Belief",
    "DeferringRepairer",
    "DiagnosingRepairer",
    "FunctionRepairer",
    "Kind",
    "MissionContext",
    "MissionKind",
    "PlanFn",
    "Repair",
    "RepairRequest",
    "RepairSource",
    "RepairStatus",
    "Repairer",
    "ReplacementRepairer",
    "StrategyEntry",
    "StrategyFactory",
    "StrategyName",
    "StrategyOptions",
    "TrialRepairer",
    "chained",
    "diagnosis_report",
    "get_strategy",
    "lookahead",
    "register",
    "register_strategy",
    "replacement",
    "replan",
    "start_lookahead",
    "start_replacement",
    "stateless",
    "strategy_entries",
    "strategy_entry",
    "strategy_for",
    "strategy_names",
    "uses_table",
]
