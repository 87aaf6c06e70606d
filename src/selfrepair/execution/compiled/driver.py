"""The driver of the compiled mission loop: which missions it takes, the arrays of one mission,
the kernel's exits served, and the trace, repairs and tallies made from the arrays afterwards.

:func:`compiled_loop` is what :func:`selfrepair.execution.executor.run_mission` calls in place of
its Python loop when the mission's footing allows it (:func:`refusal` says why not). It leaves
the mission's state where the Python loop leaves it (the stepper's steps, repairs, known faults
and waits; the simulator's pose, step count and clock), so the executor makes the same
:class:`~selfrepair.execution.result.MissionResult` from either. Nothing of this runs per step
while the kernel runs: the trace and the repair records are made from the arrays once the
mission has ended, outside every timed repair.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.compiled.arrays import (
    MAX_SCHEDULE_FAULTS,
    compiled_lookups,
    empty_hash,
    fault_arrays,
    move_arrays,
)
from selfrepair.execution.compiled.draws import MAX_SEED, MAX_WORD, threshold
from selfrepair.execution.compiled.planner import (
    KernelPlanner,
    cached_planner,
    kernel_planner,
    new_records,
)
from selfrepair.execution.faults import Detection, Persistence, canonical_order
from selfrepair.execution.result import MissionSpec, RepairRecord, StepSource, TraceStep
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS, Simulator
from selfrepair.execution.stepper import MAX_REPAIRS_PER_STEP, Stepper
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.lookups import action_index
from selfrepair.repair.replacement import DEFERRING
from selfrepair.repair.strategies import (
    Repair,
    RepairSource,
    RepairStatus,
    StrategyName,
    chained,
)
from selfrepair.search.astar import PlanResult
from selfrepair.search.problem import make_pose
from selfrepair.status import REPAIR_OF_PLAN, MissionStatus, PlanStatus, mission_status

__all__ = ["FOOTINGS", "LoopEnd", "compiled_loop", "refusal", "runs_compiled"]

FOOTINGS = ("auto", "compiled", "python")
"""What a mission's ``footing`` may ask for: the compiled loop where it can run (``auto``), the
compiled loop or an error (``compiled``), or the Python loop."""

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
_COMPILED = (StrategyName.REPLAN, StrategyName.REPLACEMENT, StrategyName.LOOKAHEAD)
_REPAIR_STATUS = {
    RepairStatus.REPAIRED: k.R_REPAIRED,
    RepairStatus.STUCK: k.R_STUCK,
    RepairStatus.BUDGET_EXHAUSTED: k.R_BUDGET,
}
_STATUS_OF = {code: status for status, code in _REPAIR_STATUS.items()}
_EVENT_KIND = {
    Persistence.PERMANENT: k.EV_PERMANENT,
    Persistence.TRANSIENT: k.EV_TRANSIENT,
    Persistence.INTERMITTENT: k.EV_INTERMITTENT,
}


def refusal(spec: MissionSpec, stepper: Stepper | None = None) -> str | None:
    """Why the compiled loop cannot run ``spec`` (one line), or ``None`` when it can."""
    if not k.NUMBA:
        return "numba is not installed (the 'fast' extra)"
    if spec.strategy not in _COMPILED:
        compiled = "replan, replacement, lookahead"
        return f"strategy {spec.strategy!s} runs in Python (compiled: {compiled})"
    if spec.strategy == StrategyName.LOOKAHEAD and spec.options.recursion in DEFERRING:
        mode = spec.options.recursion
        return f"lookahead's fallback in {mode!s} recursion defers actions (Python only)"
    if spec.objective is not None:
        return "a tolerant planning objective runs in Python"
    if stepper is not None and stepper.horizon and spec.strategy != StrategyName.LOOKAHEAD:
        return "a repair horizon runs in Python (compiled: lookahead's)"
    if spec.world:
        return "world events (a changing maze) run in Python"
    if spec.schedule.detection is Detection.HIDDEN:
        return "faults hidden from the robot (detection hidden) run in Python"
    events = spec.schedule.events
    if any(e.persistence is Persistence.INTERMITTENT for e in events) and (
        spec.seed > MAX_SEED or len(events) > MAX_WORD or spec.step_limit() > MAX_WORD
    ):
        return (
            f"intermittent faults run in Python with a seed above {MAX_SEED} or more than "
            f"{MAX_WORD} steps or events (the compiled draw takes 64-bit seeds, 32-bit steps)"
        )
    if len({e.fault for e in events}) > MAX_SCHEDULE_FAULTS:
        return f"more than {MAX_SCHEDULE_FAULTS} distinct faults in the schedule"
    if not spec.maze.in_bounds(spec.start.x, spec.start.y):
        return "the start lies off the maze"
    return None


def runs_compiled(spec: MissionSpec, sim: Simulator, stepper: Stepper) -> bool:
    """Whether the compiled loop runs ``spec`` with ``sim`` and ``stepper`` (for footing
    ``compiled`` a refusal raises :class:`ProblemError` with the reason)."""
    if spec.footing == "python":
        return False
    reason = refusal(spec, stepper)
    if reason is None and type(sim) is not Simulator:  # another world holds the truth (physics)
        reason = f"its simulator is a {type(sim).__name__}, not the lattice Simulator"
    if reason is not None and spec.footing == "compiled":
        raise ProblemError(f"footing 'compiled' cannot run this mission: {reason}")
    return reason is None


class _Mission:
    """The arrays of one mission in the kernel's layout, and what serves its exits."""

    def __init__(
        self, spec: MissionSpec, sim: Simulator, stepper: Stepper, penalty: Sequence[int]
    ) -> None:
        context = stepper.context
        domain = spec.domain
        self.spec, self.sim, self.stepper, self.context = spec, sim, stepper, context
        self.index = action_index(domain)
        self.faults = tuple(canonical_order(spec.schedule.all_faults()))
        self.bits = {f: i for i, f in enumerate(self.faults)}
        table = sim.table
        if not table.ends_covered:
            raise _Refused("a move may end off its footprint")
        self.mv = move_arrays(table)
        self.avail, self.block = fault_arrays(domain, self.faults)
        grid = sim.grid
        self.grid = np.frombuffer(grid.data, dtype=np.uint8)
        unit = sim.unit
        ev = np.zeros((len(spec.schedule.events), 6), dtype=np.int64)
        for e, event in enumerate(spec.schedule.events):
            scale = 1 if event.clock == "step" else unit
            end = 0 if event.duration is None else (event.at + event.duration) * scale
            p = event.probability
            cut = threshold(p) if event.persistence is Persistence.INTERMITTENT and p else 0
            ev[e] = (self.bits[event.fault], int(event.clock != "step"),
                     _EVENT_KIND[event.persistence], event.at * scale, end, cut)  # fmt: skip
        self.ev = ev
        self.waits = np.array([self.index.of(w) for w in domain.waits], dtype=np.int64)
        replacement = spec.strategy == StrategyName.REPLACEMENT
        lookahead = spec.strategy == StrategyName.LOOKAHEAD
        deferring = replacement and spec.options.recursion in DEFERRING
        n_actions = len(domain.actions)
        self.lookups = compiled_lookups(context, n_actions) if replacement or lookahead else None
        self.set_of = (
            self.lookups.set_of(self.faults)
            if self.lookups is not None
            else np.full(1 << len(self.faults), -1, dtype=np.int64)
        )
        weight = bool(Fraction(spec.clearance_weight))
        self.pen = (
            np.frombuffer(penalty, dtype=np.uint8).astype(np.int64)
            if isinstance(penalty, bytes)
            else np.array(penalty, dtype=np.int64)
        ) if weight else np.zeros(1, dtype=np.int64)  # fmt: skip
        goal_h = -1 if spec.goal_heading is None else int(spec.goal_heading)
        par = np.zeros(k.P_SIZE, dtype=np.int64)
        par[k.P_STRATEGY] = 2 if lookahead else int(replacement)
        par[k.P_BEFORE] = stepper.horizon if lookahead else 0
        par[k.P_WINDOW] = spec.options.window
        par[k.P_REWRITE] = int(replacement and spec.options.rewrite and not deferring)
        par[k.P_DEFER] = int(deferring)
        par[k.P_WIDTH], par[k.P_HEIGHT] = grid.width, grid.height
        par[k.P_STRIDE], par[k.P_MARGIN] = grid.stride, grid.margin
        par[k.P_GX], par[k.P_GY], par[k.P_GH] = spec.goal[0], spec.goal[1], goal_h
        par[k.P_LIMIT] = spec.step_limit()
        par[k.P_SENSE_NOW] = int(spec.schedule.detection is Detection.NOW)
        par[k.P_MAX_WAIT] = stepper.max_wait
        par[k.P_FAILED_UNITS] = int(FAILED_ATTEMPT_TICKS * sim.unit)
        par[k.P_NSLOTS] = 4 * n_actions
        par[k.P_WEIGHT] = int(weight)
        par[k.P_MAX_TRIES] = MAX_REPAIRS_PER_STEP
        par[k.P_SEED] = spec.seed if spec.seed <= MAX_SEED else 0  # only intermittent draws read it
        self.par = par
        plan = [self.index.of(a) for a, _ in stepper.queue]
        n = len(plan)
        cap = max(64, 2 * n)
        self.qa = np.zeros(cap, dtype=np.int64)
        self.qs = np.zeros(cap, dtype=np.int64)
        self.qa[:n] = plan[::-1]
        self.qs[:n] = k.SRC_PLAN
        self.pend = np.zeros((cap, 2), dtype=np.int64)  # deferring: pending by marker
        self.tr = np.zeros((max(64, 2 * n), k.T_COLS), dtype=np.int64)
        self.rp = np.zeros((64, k.RP_COLS), dtype=np.int64)
        self.rp_act = np.zeros(max(256, 4 * n), dtype=np.int64)
        self.pb = np.zeros(max(64, n), dtype=np.int64)
        st = np.zeros(k.S_SIZE, dtype=np.int64)
        pose = sim.pose
        st[k.S_STEP], st[k.S_UNITS] = sim.steps, sim.units
        st[k.S_X], st[k.S_Y], st[k.S_H] = pose.x, pose.y, int(pose.heading)
        st[k.S_KNOWN] = self.mask(stepper.known)
        st[k.S_QLEN] = n
        self.st = st
        self.plans: list[PlanResult] = []
        self._known: dict[int, frozenset[object]] = {}
        st[k.S_PL_MASK] = -1
        st[k.S_EARLY_AT] = -1
        self.planner: tuple[Any, ...] = _NO_PLANNER  # the compiled planner's arrays
        self.search: tuple[Any, ...] = _NO_SEARCH
        self._holder: list[tuple[Any, ...]] = [_NO_SEARCH]
        budget = context.replan_budget
        par[k.P_BUDGET] = (1 << 62) if budget is None else min(budget, 1 << 62)
        full = (1 << len(self.faults)) - 1
        ready = cached_planner(spec, self.known(full))  # made by an earlier run: load it now
        if ready is not None:
            self._load_planner(full, ready)

    def mask(self, faults: frozenset[object]) -> int:
        """The bit mask of ``faults`` (each one of the schedule's)."""
        return sum(1 << self.bits[f] for f in faults)

    def known(self, mask: int) -> frozenset[object]:
        """The fault set of ``mask`` (one value per mask)."""
        found = self._known.get(mask)
        if found is None:
            found = frozenset(f for i, f in enumerate(self.faults) if mask >> i & 1)
            if found == self.stepper.known:
                found = self.stepper.known
            self._known[mask] = found
        return found

    def _load_planner(self, mask: int, planner: KernelPlanner | None) -> None:
        """Hand the kernel the planner of the known mask ``mask`` (``None``: the driver plans)."""
        st = self.st
        st[k.S_PL_MASK] = mask
        st[k.S_PL_KERNEL] = int(planner is not None)
        if planner is not None:
            self.planner = (planner.mt, planner.hdist, planner.pen, planner.nbr, planner.par,
                            planner.moves)  # fmt: skip
            states = planner.states
            self._holder = _RECORDS.get(states, lambda: [new_records(states)])
            self.search = self._holder[0]

    def run(self) -> int:
        """Call the kernel until the mission ends, serving its exits."""
        while True:
            lk = self.lookups
            if lk is None:
                lk_arrays: tuple[Any, ...] = _NO_LOOKUPS  # int64 arrays, ans_act int32
            else:
                lk_arrays = (lk.lk, lk.codes, lk.ht, lk.ans, lk.ans_act)
            slots, codes, ht, ans, ans_act = lk_arrays
            deferring: tuple[Any, ...] = (
                _NO_DEFERRING if lk is None else (self.pend, lk.gh, lk.ans_dpos)
            )
            code = k.run_kernel(
                self.par, self.st, self.mv, self.grid, self.avail, self.block, self.waits,
                self.ev, self.set_of, slots, codes, ht, ans, ans_act, self.pen, self.pb, self.qa,
                self.qs, self.tr, self.rp, self.rp_act, self.planner, self.search, deferring,
            )  # fmt: skip
            if code == k.DONE:
                return int(self.st[k.S_END])
            self._serve(code)

    def _serve(self, code: int) -> None:
        st, lk = self.st, self.lookups
        args = [int(v) for v in st[k.S_ARG0 : k.S_ARG4 + 1]]
        if code == k.NEED_SET:
            assert lk is not None
            self.set_of[args[0]] = lk.set_id(self.known(args[0]))
        elif code == k.NEED_SLOT:
            assert lk is not None
            lk.load_slot(args[0], args[1])
        elif code == k.NEED_FILL:
            assert lk is not None
            lk.fill(*args)
        elif code == k.NEED_PLAN:
            self._plan(args[0], self.pose(args[1], args[2], args[3]))
        elif code == k.NEED_WINDOW:
            self._plan_window(args[0], self.pose(args[1], args[2], args[3]))
        elif code == k.OFF_GRID:
            raise ProblemError(
                f"lookahead at {self.pose(int(st[k.S_X]), int(st[k.S_Y]), int(st[k.S_H]))}: the "
                "faulty action would be met off the maze"
            )
        elif code == k.NEED_GUARD:
            assert lk is not None
            lk.serve_guard(args[0], args[1])
        elif code == k.NEED_PLANNER:
            self._load_planner(args[0], kernel_planner(self.spec, self.known(args[0])))
        elif code == k.GROW:
            need = int(st[k.S_PLAN_LEN]) + int(st[k.S_QLEN]) + 2
            self.qa, self.qs = _grow(self.qa, need), _grow(self.qs, need)
            self.pend = _grow(self.pend, self.qa.shape[0])
            self.tr, self.rp = _grow(self.tr), _grow(self.rp)
            self.rp_act = _grow(self.rp_act, int(st[k.S_NACT]) + need + 64)
            self.pb = _grow(self.pb, need)
        elif code == k.GROW_HEAP:
            rec, gen, heap, *scratch = self.search
            bigger = np.empty((2 * heap.shape[0], 2), dtype=np.int64)
            bigger[: heap.shape[0]] = heap
            self.search = self._holder[0] = (rec, gen, bigger, *scratch)  # kept grown
        elif code == k.TOO_MANY:
            pose = self.pose(int(st[k.S_X]), int(st[k.S_Y]), int(st[k.S_H]))
            raise ProblemError(
                f"strategy repaired the queue {MAX_REPAIRS_PER_STEP} times at {pose} and its "
                "first action is still unavailable: a repair must start with an available action"
            )
        else:  # pragma: no cover - the kernel has no other exit
            raise AssertionError(f"unknown kernel exit {code}")

    def _plan(self, mask: int, pose: Pose) -> None:
        """Plan from ``pose`` to the goal under the known faults (the mission's planner)."""
        st, context = self.st, self.context
        result = context.plan(
            pose, context.goal, context.goal_heading, self.known(mask), context.replan_budget
        )
        status = self._planned(result)
        st[k.S_PLAN_STATUS] = _REPAIR_STATUS[status]
        st[k.S_PLAN_LEN] = len(result.actions)
        st[k.S_PLAN_EXP] = result.expansions
        st[k.S_PLAN_ID] = len(self.plans) - 1
        st[k.S_PLAN_READY] = 1

    def _plan_window(self, mask: int, end: Pose) -> None:
        """The lookahead window's search: from the current pose to the window's end ``end``
        under the known faults, within the window budget (as ``lookahead`` asks it)."""
        st, context = self.st, self.context
        pose = self.pose(int(st[k.S_X]), int(st[k.S_Y]), int(st[k.S_H]))
        budget = context.options.lookahead_expansions
        result = context.plan(pose, end.cell, end.heading, self.known(mask), budget)
        solved = result.status is PlanStatus.SOLVED
        self._planned(result)
        st[k.S_LA_STATUS] = k.R_REPAIRED if solved else k.R_STUCK
        st[k.S_LA_LEN] = len(result.actions)
        st[k.S_LA_EXP] = result.expansions
        st[k.S_LA_ID] = len(self.plans) - 1
        st[k.S_LA_READY] = 1

    def _planned(self, result: PlanResult) -> RepairStatus:
        """Keep ``result`` and put its actions in the plan buffer; its repair status."""
        of = self.index.of
        acts = [of(a) for a in result.actions]
        while self.pb.shape[0] < len(acts):
            self.pb = _grow(self.pb)
        self.pb[: len(acts)] = acts
        self.plans.append(result)
        return REPAIR_OF_PLAN[result.status]

    def pose(self, x: int, y: int, h: int) -> Pose:
        """The pose of ``(x, y, h)`` (shared from the maze's pose table when it has one)."""
        return make_pose(x, y, _HEADINGS[h])


_HEADINGS = tuple(Heading)
_NO_PLANNER = (
    np.zeros((4, 1, 6), dtype=np.int64),
    np.zeros(1, dtype=np.int32),
    np.zeros(1, dtype=np.int64),
    np.zeros(1, dtype=np.uint16),
    np.zeros(7, dtype=np.int64),
    np.zeros(1, dtype=np.int64),
)
for _array in _NO_PLANNER:
    _array.setflags(write=False)
_NO_SEARCH = (np.zeros((1, 3), dtype=np.int64), np.zeros(1, dtype=np.int64),
              np.zeros((8, 2), dtype=np.int64), np.zeros(4, dtype=np.int64),
              np.zeros(9, dtype=np.int64), np.zeros(1, dtype=np.int64))  # fmt: skip
_RECORDS: BoundedCache[int, list[tuple[object, ...]]] = BoundedCache(
    "compiled-loop search records", 4, kind=CacheKind.PLAN
)
_NO_DEFERRING = (
    np.zeros((1, 2), dtype=np.int64),
    empty_hash(2),
    np.zeros(1, dtype=np.int64),
)
_NO_LOOKUPS = (
    np.zeros((1, 1, 2), dtype=np.int64),
    np.zeros((1, 1, 1), dtype=np.int64),
    empty_hash(2),
    np.zeros((1, k.A_COLS), dtype=np.int64),
    np.zeros(1, dtype=np.int32),
)


def _grow(array: npt.NDArray[Any], need: int = 0) -> npt.NDArray[Any]:
    """``array`` at least twice as long (first axis) and at least ``need`` long."""
    size = max(2 * array.shape[0], need)
    out = np.zeros((size, *array.shape[1:]), dtype=array.dtype)
    out[: array.shape[0]] = array
    return out


class _Refused(Exception):
    """The mission's arrays cannot be made (the Python loop runs it)."""


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
    _warm()
    try:
        mission = _Mission(spec, sim, stepper, penalty)
    except _Refused as exc:
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


_WARM: list[bool] = []


def _warm() -> None:
    """Load the kernels the driver calls from Python (from numba's cache, or compiled) once per
    process, before any repair's clock runs: a cold run's first fill must not pay for it."""
    if not _WARM:
        table = empty_hash(2)
        k.hash_put(table, 0, 0, 0)
        k.hash_get(table, 0, 0)
        _WARM.append(True)


def _write_back(mission: _Mission, moved: list[int]) -> None:
    """Leave the stepper and the simulator as the Python loop would (see the module
    docstring), from the arrays."""
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
            found = poses[key] = make_pose(x, y, _HEADINGS[h])
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


def _record(mission: _Mission, row: list[int]) -> RepairRecord:
    """The :class:`RepairRecord` of one repair row (the same values the Python loop records)."""
    actions = mission.spec.domain.actions
    step, x, y, h, a, kind, aid, _, latency, consumed, off, length, subst, plan, known, qlen = row[
        : k.RP_EXPANSIONS
    ]
    pose = make_pose(x, y, _HEADINGS[h])
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
