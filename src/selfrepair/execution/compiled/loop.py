"""The compiled mission loop's entry: :func:`compiled_loop` runs a mission in the kernel (through
the driver, :mod:`selfrepair.execution.compiled.driver`) and makes, from the arrays once the
mission has ended, the trace, the repair records and the tallies the Python loop would have left.

:func:`compiled_loop` is what :func:`selfrepair.execution.executor.run_mission` calls in place of
its Python loop when the mission's footing allows it
(:func:`~selfrepair.execution.compiled.footing.refusal` says why not). It leaves the mission's
state where the Python loop leaves it (the stepper's steps, repairs, known faults and waits; the
simulator's pose, step count and clock), so the executor makes the same
:class:`~selfrepair.execution.result.MissionResult` from either. Nothing of this runs per step
while the kernel runs: the trace and the repair records are made from the arrays once the
mission has ended, outside every timed repair; the trace is not even made then: the result keeps
the kernel's trace rows (:class:`~selfrepair.execution.compiled.trace.ArrayTrace`), whose steps
are made when read.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from selfrepair.errors import ProblemError
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.compiled.driver import REPAIR_STATUS, CompiledMission, Refused, warm
from selfrepair.execution.compiled.footing import runs_compiled
from selfrepair.execution.compiled.trace import ArrayTrace
from selfrepair.execution.result import MissionSpec, RepairRecord, StepSource
from selfrepair.execution.simulator import Simulator
from selfrepair.execution.stepper import Stepper
from selfrepair.repair.strategies import (
    Repair,
    RepairSource,
    RepairStatus,
    StrategyName,
    chained,
)
from selfrepair.status import REPAIR_OF_PLAN, MissionStatus, mission_status

__all__ = ["LoopEnd", "compiled_loop"]


class LoopEnd(NamedTuple):
    """How the compiled loop ended (status, reason), the executed time in units, the clearance
    penalty, the trace (made from the kernel's rows when read) and its number of waits."""

    status: MissionStatus
    reason: str
    units: int
    penalty: int
    trace: ArrayTrace
    waits: int


_STATUS_OF = {code: status for status, code in REPAIR_STATUS.items()}


def compiled_loop(
    spec: MissionSpec,
    sim: Simulator,
    stepper: Stepper,
    moved: list[int],
    why: Callable[[Repair], str],
    penalty: Sequence[int],
) -> LoopEnd | None:
    """Run the mission's loop compiled, or ``None`` (nothing done) when its footing says
    Python or the compiled loop cannot take it. ``moved`` receives the plan-distance keys of the
    executed steps; ``why(failure)`` is the reason of a mission that ends on a failed repair;
    ``penalty`` the clearance penalties in the simulator grid's layout (read when the clearance
    weight is not zero)."""
    if not runs_compiled(spec, sim, stepper):
        return None
    warm()
    try:
        mission = CompiledMission(spec, sim, stepper, penalty)
    except Refused as exc:
        if spec.footing == "compiled":
            raise ProblemError(f"footing 'compiled' cannot run this mission: {exc}") from None
        return None
    end = mission.run()
    trace = _write_back(mission, moved)
    st = mission.st
    units, summed = int(st[k.S_EXEC_UNITS]), int(st[k.S_PENALTY])
    waits = trace.count_source(StepSource.WAIT)
    if end == k.REACHED:
        return LoopEnd(MissionStatus.REACHED, "goal reached", units, summed, trace, waits)
    if end == k.STEP_LIMIT:
        reason = f"{spec.step_limit()} steps without reaching the goal"
        return LoopEnd(MissionStatus.STEP_LIMIT, reason, units, summed, trace, waits)
    if end == k.COLLISION:
        qa = mission.qa
        action = spec.domain.actions[int(qa[int(st[k.S_QLEN]) - 1])]
        name = spec.domain.format_action(action)
        reason = f"{name} at {sim.pose} would sweep a wall"
        return LoopEnd(MissionStatus.COLLISION, reason, units, summed, trace, waits)
    failure = stepper.repairs[int(st[k.S_FAIL_REP])].repair
    stepper.failure, stepper.stopped = failure, True
    return LoopEnd(mission_status(failure.status), why(failure), units, summed, trace, waits)


def _write_back(mission: CompiledMission, moved: list[int]) -> ArrayTrace:
    """Leave the stepper and the simulator as the Python loop would (see the module
    docstring of :mod:`selfrepair.execution.compiled.driver`), from the arrays, but for the
    stepper's steps: the mission's trace, returned (its steps are made when read)."""
    st, sim, stepper, spec = mission.st, mission.sim, mission.stepper, mission.spec
    actions = spec.domain.actions
    n_actions = len(actions)
    n = int(st[k.S_NSTEPS])
    tr = mission.tr[:n]
    known = {mask: mission.known(mask) for mask in np.unique(tr[:, k.T_KNOWN]).tolist()}
    trace = ArrayTrace.of(tr, tuple(actions), known, sim.unit)
    ran = tr[tr[:, k.T_SOURCE] != k.SRC_FAILED]
    keys = ((ran[:, k.T_Y] << 32) + 4 * ran[:, k.T_X] + ran[:, k.T_H]) * n_actions + ran[
        :, k.T_ACTION
    ]
    moved.extend(keys.tolist())
    for row in mission.rp[: int(st[k.S_NREP])].tolist():
        stepper.repairs.append(_record(mission, row))
    stepper.known = mission.known(int(st[k.S_KNOWN]))
    stepper.waits = int(st[k.S_WAITS])
    sim.pose = mission.pose(int(st[k.S_X]), int(st[k.S_Y]), int(st[k.S_H]))
    sim.steps, sim.units = int(st[k.S_STEP]), int(st[k.S_UNITS])
    return trace


def _record(mission: CompiledMission, row: list[int]) -> RepairRecord:
    """The :class:`RepairRecord` of one repair row (the same values the Python loop records)."""
    actions = mission.spec.domain.actions
    step, x, y, h, a, kind, aid, _, latency, consumed, off, length, subst, plan, known, qlen = row[
        : k.RP_EXPANSIONS
    ]
    pose = mission.pose(x, y, h)
    action = None if a < 0 else actions[a]
    window = row[k.RP_WINDOW]
    repair: Repair
    if kind == k.K_WINDOW:
        result = mission.plans[window]
        repair = Repair(
            RepairStatus.REPAIRED,
            RepairSource.LOOKAHEAD,
            result.actions,
            consumed,
            expansions=result.expansions,
            attempts=(StrategyName.LOOKAHEAD,),
        )
        return RepairRecord(step, pose, action, repair, latency)
    if kind in (k.K_HIT, k.K_REWRITE):
        lookups = mission.lookups
        assert lookups is not None
        head = lookups.answers[aid]
        if kind == k.K_HIT:
            repair = head
        else:
            spliced = tuple(actions[i] for i in mission.rp_act[off : off + length].tolist())
            repair = Repair(
                head.status, head.source, spliced, consumed, head.replans, head.candidate_length,
                head.depth, head.examined, head.expansions, head.attempts, head.candidate_index,
                subst,
            )  # fmt: skip
    else:
        if plan >= 0:
            result = mission.plans[plan]
            status, planned, expansions = (
                REPAIR_OF_PLAN[result.status], result.actions, result.expansions,
            )  # fmt: skip
        else:  # planned in the kernel
            status = _STATUS_OF[row[k.RP_STATUS]]
            planned = tuple(actions[i] for i in mission.rp_act[off : off + length].tolist())
            expansions = row[k.RP_EXPANSIONS]
        repair = Repair(
            status,
            RepairSource.REPLAN,
            planned,
            qlen,
            replans=1,
            expansions=expansions,
            attempts=(StrategyName.REPLAN,),
        )
        if kind == k.K_MISS:
            table = mission.context.table
            assert table is not None
            examined = len(table.candidates(action, mission.known(known)))
            repair = chained(repair, (StrategyName.REPLACEMENT,), examined=examined)
    if window >= 0:  # lookahead's fallback: the healthy prefix kept in front, the window's work
        prefix = row[k.RP_PREFIX]
        if prefix:
            spliced = tuple(actions[i] for i in mission.rp_act[off : off + length].tolist())
            consumed_all = repair.consumed + prefix if kind == k.K_HIT else repair.consumed
            repair = repair._replace(actions=spliced, consumed=consumed_all)
        repair = chained(
            repair, (StrategyName.LOOKAHEAD,), expansions=mission.plans[window].expansions
        )
    return RepairRecord(step, pose, action, repair, latency)
