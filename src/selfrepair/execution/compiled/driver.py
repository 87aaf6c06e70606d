"""The driver of the compiled mission loop: the arrays of one mission in the kernel's layout,
and the kernel's exits served (a fault set's look-up slot, a pattern met for the first time, a
plan, a planner, more room) until the mission ends.

:class:`CompiledMission` is made and run by
:func:`~selfrepair.execution.compiled.loop.compiled_loop`, which then makes the trace, the repair
records and the tallies from its arrays; which missions it takes is
:mod:`selfrepair.execution.compiled.footing`'s answer.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.compiled.arrays import (
    compiled_lookups,
    empty_hash,
    fault_arrays,
    move_arrays,
)
from selfrepair.execution.compiled.draws import MAX_SEED, threshold
from selfrepair.execution.compiled.planner import (
    KernelPlanner,
    cached_planner,
    kernel_planner,
    new_records,
)
from selfrepair.execution.faults import Detection, Persistence, canonical_order
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.simulator import FAILED_ATTEMPT_TICKS, Simulator
from selfrepair.execution.stepper import MAX_REPAIRS_PER_STEP, Stepper
from selfrepair.geometry import Heading, Pose
from selfrepair.repair.lookups import action_index
from selfrepair.repair.replacement import DEFERRING
from selfrepair.repair.strategies import RepairStatus, StrategyName
from selfrepair.search.astar import PlanResult
from selfrepair.search.problem import make_pose
from selfrepair.status import REPAIR_OF_PLAN, PlanStatus

__all__ = ["REPAIR_STATUS", "CompiledMission", "Refused", "warm"]

REPAIR_STATUS = {
    RepairStatus.REPAIRED: k.R_REPAIRED,
    RepairStatus.STUCK: k.R_STUCK,
    RepairStatus.BUDGET_EXHAUSTED: k.R_BUDGET,
}
"""The kernel's code of each repair status a plan can end a repair with."""
_EVENT_KIND = {
    Persistence.PERMANENT: k.EV_PERMANENT,
    Persistence.TRANSIENT: k.EV_TRANSIENT,
    Persistence.INTERMITTENT: k.EV_INTERMITTENT,
}


class CompiledMission:
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
            raise Refused("a move may end off its footprint")
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
        longest = 0 if self.lookups is None else self.lookups.longest
        par[k.P_LONGEST] = longest
        if par[k.P_REWRITE]:  # room for a rewrite of the whole plan: no growing inside its clock
            cap = max(cap, n * max(longest, 1) + 2)
        self.qa = np.zeros(cap, dtype=np.int64)
        self.qs = np.zeros(cap, dtype=np.int64)
        self.qa[:n] = plan[::-1]
        self.qs[:n] = k.SRC_PLAN
        self.pend = np.zeros((cap, 2), dtype=np.int64)  # deferring: pending by marker
        self.tr = np.zeros((max(64, 2 * n), k.T_COLS), dtype=np.int64)
        self.rp = np.zeros((64, k.RP_COLS), dtype=np.int64)
        self.rp_act = np.zeros(max(256, 4 * n, n * (longest + 1) + longest + 64), dtype=np.int64)
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
                self.par[k.P_LONGEST] = lk.longest
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
            qlen = int(st[k.S_QLEN])
            need = int(st[k.S_PLAN_LEN]) + qlen + 2
            acts = need + 64
            if self.par[k.P_REWRITE]:  # the longest rewrite (kernel._rewrite_short)
                longest = max(int(self.par[k.P_LONGEST]), 1)
                need = max(need, qlen * longest + 2)
                acts = max(acts, qlen * (longest + 1) + longest + 64)
            self.qa, self.qs = _grow(self.qa, need), _grow(self.qs, need)
            self.pend = _grow(self.pend, self.qa.shape[0])
            self.tr, self.rp = _grow(self.tr), _grow(self.rp)
            self.rp_act = _grow(self.rp_act, int(st[k.S_NACT]) + acts)
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
        st[k.S_PLAN_STATUS] = REPAIR_STATUS[status]
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


class Refused(Exception):
    """The mission's arrays cannot be made (the Python loop runs it)."""


_WARM: list[bool] = []


def warm() -> None:
    """Load the kernels the driver calls from Python (from numba's cache, or compiled) once per
    process, before any repair's clock runs: a cold run's first fill must not pay for it."""
    if not _WARM:
        table = empty_hash(2)
        k.hash_put(table, 0, 0, 0)
        k.hash_get(table, 0, 0)
        _WARM.append(True)
