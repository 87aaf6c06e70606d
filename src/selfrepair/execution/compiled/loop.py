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
mission has ended, outside every timed repair.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from fractions import Fraction

from selfrepair.errors import ProblemError
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.compiled.driver import REPAIR_STATUS, CompiledMission, Refused, warm
from selfrepair.execution.compiled.footing import runs_compiled
from selfrepair.execution.result import MissionSpec, RepairRecord, StepSource, TraceStep
from selfrepair.execution.simulator import Simulator
from selfrepair.execution.stepper import Stepper
from selfrepair.geometry import Pose
from selfrepair.repair.strategies import (
    Repair,
    RepairSource,
    RepairStatus,
    StrategyName,
    chained,
)
from selfrepair.status import REPAIR_OF_PLAN, MissionStatus, mission_status

__all__ = ["LoopEnd", "compiled_loop"]

LoopEnd = tuple[MissionStatus, str, int, int]
"""How the loop ended (status, reason), the executed time in units and the clearance penalty."""

_SOURCES = (
    StepSource.PLAN,
    StepSource.REPLACEMENT,
    StepSource.REPLAN,
    StepSource.FAILED_ATTEMPT,
    StepSource.WAIT,
    StepSource.LOOKAHEAD,
)
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
    _write_back(mission, moved)
    st = mission.st
    units, summed = int(st[k.S_EXEC_UNITS]), int(st[k.S_PENALTY])
    if end == k.REACHED:
        return MissionStatus.REACHED, "goal reached", units, summed
    if end == k.STEP_LIMIT:
        limit = spec.step_limit()
        return MissionStatus.STEP_LIMIT, f"{limit} steps without reaching the goal", units, summed
    if end == k.COLLISION:
        qa = mission.qa
        action = spec.domain.actions[int(qa[int(st[k.S_QLEN]) - 1])]
        name = spec.domain.format_action(action)
        reason = f"{name} at {sim.pose} would sweep a wall"
        return MissionStatus.COLLISION, reason, units, summed
    failure = stepper.repairs[int(st[k.S_FAIL_REP])].repair
    stepper.failure, stepper.stopped = failure, True
    return mission_status(failure.status), why(failure), units, summed


def _write_back(mission: CompiledMission, moved: list[int]) -> None:
    """Leave the stepper and the simulator as the Python loop would (see the module
    docstring of :mod:`selfrepair.execution.compiled.driver`), from the arrays."""
    st, sim, stepper, spec = mission.st, mission.sim, mission.stepper, mission.spec
    actions = spec.domain.actions
    n_actions = len(actions)
    unit = sim.unit
    durations: dict[int, Fraction] = {}
    poses: dict[int, Pose] = {}

    def pose(x: int, y: int, h: int) -> Pose:
        key = (y << 34) | (x << 2) | h
        found = poses.get(key)
        if found is None:
            found = poses[key] = mission.pose(x, y, h)
        return found

    n = int(st[k.S_NSTEPS])
    tr = mission.tr[:n]
    steps = stepper.steps
    for row in tr.tolist():
        step, a, x, y, h, ex, ey, eh, units, source, known = row
        duration = durations.get(units)
        if duration is None:
            duration = durations[units] = Fraction(units, unit)
        steps.append(
            TraceStep(step, actions[a], pose(x, y, h), pose(ex, ey, eh), duration,
                      _SOURCES[source], mission.known(known))
        )  # fmt: skip
    ran = tr[tr[:, k.T_SOURCE] != k.SRC_FAILED]
    keys = ((ran[:, k.T_Y] << 32) + 4 * ran[:, k.T_X] + ran[:, k.T_H]) * n_actions + ran[
        :, k.T_ACTION
    ]
    moved.extend(keys.tolist())
    for row in mission.rp[: int(st[k.S_NREP])].tolist():
        stepper.repairs.append(_record(mission, row))
    stepper.known = mission.known(int(st[k.S_KNOWN]))
    stepper.waits = int(st[k.S_WAITS])
    sim.pose = pose(int(st[k.S_X]), int(st[k.S_Y]), int(st[k.S_H]))
    sim.steps, sim.units = int(st[k.S_STEP]), int(st[k.S_UNITS])


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
