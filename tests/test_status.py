"""The one family of end statuses: explicit conversions, one success per enum, and no status or
step source made from another by value anywhere in the package."""

from __future__ import annotations

import ast
from enum import Enum
from pathlib import Path

import pytest

from selfrepair.errors import ProblemError
from selfrepair.execution.result import STEP_OF_REPAIR, StepSource
from selfrepair.repair.strategies import RepairSource
from selfrepair.status import (
    MISSION_OF_REPAIR,
    POSITIVE_OUTCOMES,
    REPAIR_OF_PLAN,
    EpisodeEnd,
    LpgStatus,
    MissionStatus,
    PlanStatus,
    RepairOutcome,
    RepairStatus,
    TeamStatus,
    is_positive,
    mission_status,
    repair_status,
)

FAMILY: tuple[type[Enum], ...] = (
    PlanStatus,
    RepairStatus,
    MissionStatus,
    TeamStatus,
    RepairOutcome,
    LpgStatus,
    EpisodeEnd,
)
SRC = Path(__file__).resolve().parents[1] / "src" / "selfrepair"


def test_one_success_per_enum() -> None:
    for kind in FAMILY:
        assert [m for m in kind if is_positive(m)] == [next(iter(kind))], kind
    assert len(POSITIVE_OUTCOMES) == len(FAMILY)
    assert not is_positive(RepairOutcome.DEFERRED) and not is_positive(EpisodeEnd.TRUNCATED)


def test_conversions_are_explicit_and_total() -> None:
    assert {repair_status(s) for s in PlanStatus} == set(RepairStatus)
    assert repair_status(PlanStatus.SOLVED) is RepairStatus.REPAIRED
    assert mission_status(RepairStatus.STUCK) is MissionStatus.STUCK
    assert mission_status(RepairStatus.BUDGET_EXHAUSTED) is MissionStatus.BUDGET_EXHAUSTED
    assert set(REPAIR_OF_PLAN) == set(PlanStatus)
    assert set(MISSION_OF_REPAIR) == set(RepairStatus) - {RepairStatus.REPAIRED}
    with pytest.raises(ProblemError, match="does not end a mission"):
        mission_status(RepairStatus.REPAIRED)
    assert set(STEP_OF_REPAIR) == set(RepairSource)
    assert all(STEP_OF_REPAIR[s] is StepSource(str(s)) for s in RepairSource)


def _by_value(tree: ast.AST, enums: set[str]) -> list[int]:
    """Lines where one of ``enums`` is called with an attribute or ``.value`` of something else
    (``MissionStatus(repair.status)``, ``IncidentKind(start.value)``)."""
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id in enums
        and len(node.args) == 1
        and isinstance(node.args[0], ast.Attribute)
    ]


def test_no_status_or_source_converted_by_value() -> None:
    enums = {k.__name__ for k in FAMILY} | {
        "StepSource", "RepairSource", "TeamSource", "IncidentKind", "DriveStart",
    }  # fmt: skip
    found = {
        str(path.relative_to(SRC)): lines
        for path in sorted(SRC.rglob("*.py"))
        if (lines := _by_value(ast.parse(path.read_text(encoding="utf-8")), enums))
    }
    assert not found


def test_the_check_sees_a_conversion_by_value() -> None:
    tree = ast.parse("a = MissionStatus(repair.status)\nb = MissionStatus.STUCK\n")
    assert _by_value(tree, {"MissionStatus"}) == [1]
