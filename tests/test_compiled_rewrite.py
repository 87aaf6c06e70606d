"""The compiled loop's whole-plan rewrite (:mod:`selfrepair.execution.compiled.kernel`): what it
costs is the walk and its look-ups, nothing else. A warm rewrite never leaves the kernel inside
its clock (the room for the longest splice is made before the clock starts), and it gives the
Python loop's trace and repairs on the paper's rewriting missions."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import pytest

from extras import NUMBA
from selfrepair.caching import clear_caches
from selfrepair.execution.compiled import driver as compiled_driver
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionResult, MissionSpec
from selfrepair.experiment.timing import COLD_CLEARS
from selfrepair.repair.strategies import StrategyOptions
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.world.bundled import bundled_routes, load_bundled

LONG_ANSWERS = ("FL:S,FL:F", "FR:S,FR:F")
"""Paper fault sets whose replacements are long: a rewrite of the whole plan splices more
actions than the plan had room for."""


def _specs(maze: str) -> list[MissionSpec]:
    """The rewriting missions of the paper on ``maze`` with the :data:`LONG_ANSWERS` faults:
    every bundled route, table and rewriting recursion mode."""
    return [
        MissionSpec(
            load_bundled(maze),
            route.start,
            route.goal,
            schedule=FaultSchedule.permanent(FOUR_WHEEL.parse_faults(faults)),
            strategy="replacement",
            options=StrategyOptions(table=table, recursion=recursion, rewrite=True),  # type: ignore[arg-type]
            domain=FOUR_WHEEL,
            footing="compiled",
        )
        for faults in LONG_ANSWERS
        for table in ("handwritten", "generated-agnostic", "generated-indexed")
        for recursion in ("flat", "guarded")
        for route in bundled_routes(maze)
    ]


@pytest.fixture
def exits(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[tuple[int, int]]]:
    """Every exit the compiled driver serves, as ``(code, phase)`` (phase 1: inside a repair's
    clock)."""
    seen: list[tuple[int, int]] = []
    serve = compiled_driver.CompiledMission._serve

    def spy(self: Any, code: int) -> None:
        seen.append((code, int(self.st[k.S_PHASE])))
        serve(self, code)

    monkeypatch.setattr(compiled_driver.CompiledMission, "_serve", spy)
    yield seen


MAZES = ("narrow-short", "narrow-long")


@NUMBA
@pytest.mark.parametrize("maze", MAZES)
def test_a_warm_rewrite_never_leaves_the_kernel_inside_its_clock(
    exits: list[tuple[int, int]], maze: str
) -> None:
    rewrites = 0
    for spec in _specs(maze):
        clear_caches(COLD_CLEARS)
        run_mission(spec)  # cold: fills every pattern the mission meets
        exits.clear()
        warm = run_mission(spec)
        assert warm.footing == "compiled"
        rewrites += sum(r.repair.rewritten > 0 for r in warm.repairs)
        assert [e for e in exits if e[1] == 1] == []  # no exit while a repair's clock runs
    assert rewrites >= 10


def _same_repairs(python: MissionResult, compiled: MissionResult) -> None:
    assert python.steps == compiled.steps
    assert [r._replace(latency_ns=0) for r in python.repairs] == [
        r._replace(latency_ns=0) for r in compiled.repairs
    ]


@NUMBA
@pytest.mark.parametrize("maze", MAZES)
def test_the_rewrite_with_long_answers_is_the_python_loops(maze: str) -> None:
    for spec in _specs(maze):
        python = run_mission(dataclasses.replace(spec, footing="python"))
        clear_caches(COLD_CLEARS)
        _same_repairs(python, run_mission(spec))  # cold: grows as it goes
        _same_repairs(python, run_mission(spec))  # warm: every room made up front
