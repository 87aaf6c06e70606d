"""Active diagnosis, planned: the probe that isolates a fault class in the fewest commands.

:class:`ProbePlanner` searches adaptive plans of up to a few commands (worst case over the
fewest-fault classes first, then the expected cost, a bump costed as :data:`BUMP_COST` commands),
counting each reading as the belief counts it (:func:`_against`: under noisy odometry a reading one
perturbation from a rival only contradicts it) and each watching teammate's reading with its own
noise, its actuator reading too when it has the wheel view (:func:`_wheels_against`).
:func:`isolating_probe` is its entry point and falls back to the greedy two-command sequence of
:func:`.probes.best_probe` when only a sequence splits the hypotheses.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.diagnosis.belief import CONFIRMATIONS, FaultBelief, predictions
from selfrepair.diagnosis.cooperative import Observer
from selfrepair.diagnosis.hypotheses import FAILS, FaultModel
from selfrepair.diagnosis.observation import ObservationModel, actuators_of, perturbed
from selfrepair.diagnosis.probes import (
    Probe,
    _entropy,
    _posterior_over,
    _split,
    _to_split,
    best_probe,
)
from selfrepair.geometry import FreeGrid, Pose

__all__ = [
    "BUMP_COST",
    "RULED_OUT",
    "TICK_COST",
    "ProbePlanner",
    "Watcher",
    "isolating_probe",
]


BUMP_COST = 0.5
"""What a bump costs a probe plan, in commands: a wall contact is taken only when it saves a
whole command of isolation."""

TICK_COST = 0.01
"""What a tick costs a probe plan, in commands (a tie-break between plans of equal commands)."""

_WORST = 100.0
"""The weight of a plan's worst case over the parsimonious classes in its value (commands, each
far above any expected cost: the worst case decides first)."""


@dataclass(frozen=True, slots=True, eq=False)
class _Tables:
    """Per fault model: for each action and heading, the index of the motion group each class
    falls in (classes behave alike on every action, so the first hypothesis speaks for its
    class), and each group's ticks."""

    group: tuple[tuple[npt.NDArray[np.intp], ...], ...]
    ticks: tuple[tuple[tuple[float, ...], ...], ...]


def _tables(model: FaultModel) -> _Tables:
    firsts = [(bits & -bits).bit_length() - 1 for bits in model.classes]
    domain = model.domain
    group, ticks = [], []
    for per_heading in model.groups:
        group.append(
            tuple(
                np.array(
                    [next(g for g, gr in enumerate(groups) if gr.mask >> h & 1) for h in firsts],
                    dtype=np.intp,
                )
                for groups in per_heading
            )
        )
        ticks.append(
            tuple(
                tuple(
                    1.0
                    if gr.performed == FAILS
                    else float(Fraction(domain.duration(domain.actions[gr.performed])))
                    for gr in groups
                )
                for groups in per_heading
            )
        )
    return _Tables(tuple(group), tuple(ticks))


_TABLES: BoundedCache[FaultModel, _Tables] = BoundedCache(
    "diagnosis probe tables", 16, kind=CacheKind.PREFILLED
)


@dataclass(frozen=True, slots=True, eq=False)
class _At:
    """What every command does to every class from one pose: ``onehot[a, c, l]`` whether class
    ``c`` reads outcome ``l`` after action ``a``; the outcome's end pose ``ends[l]`` and its
    prediction ``outcomes[l]`` (end relative to the start cell, bump, failure), the actions
    performed by the classes of the outcome ``performed[l]`` (one, when a teammate with the
    wheel view sees the motion and the outcome is split by them); per action and class the bump
    indicator and the ticks."""

    label: npt.NDArray[np.intp]
    onehot: npt.NDArray[np.float64]
    ends: tuple[Pose, ...]
    outcomes: tuple[tuple[Pose, bool, bool], ...]
    performed: tuple[tuple[int, ...], ...]
    bumps: npt.NDArray[np.float64]
    ticks: npt.NDArray[np.float64]


Watcher = tuple[Observer, Pose]
"""A teammate watching the robot and where it stands for the probe (it stays there while the
plan runs)."""

RULED_OUT = 1 << 20
"""The evidence of a reading that rules a class out (far above :data:`~.belief.CONFIRMATIONS`)."""


def _against(truth: Pose, rival: Pose, noise: float) -> int:
    """What one pose reading of ``truth`` (exact, as the plan assumes) says against a class
    predicting ``rival``: nothing when equal; one more contradiction when the sensor is noisy
    and ``rival`` is one of the reading's perturbations (the belief keeps it, counting a miss);
    else it rules the class out."""
    if truth == rival:
        return 0
    if noise > 0 and rival in perturbed(truth):
        return 1
    return RULED_OUT


def _wheels_against(table: Any, truth: int, rival: tuple[int, ...], noise: float) -> int:
    """What one actuator reading of ``truth`` (an action index, read exactly, as the plan
    assumes) says against a class performing one of ``rival`` (the least it says of them):
    nothing when the actuators agree; with a noisy sensor one contradiction per actuator that
    differs (the belief counts each as a miss); exact, any difference rules the class out."""
    wrong = min(table.mismatches(truth, other) for other in rival)
    if wrong == 0:
        return 0
    return RULED_OUT if noise == 0 else wrong


class ProbePlanner:
    """Plans probes that isolate a fault class in few commands (see :meth:`plan`). Mutable: it
    keeps, for one robot's mission, what each command does from each pose met (the known map
    ``grid``, ``None``: an open plane; ``switch``: whether the robot reads a bump switch; without
    one a bump reads as staying put)."""

    __slots__ = (
        "_at",
        "_evidence",
        "_memo",
        "_tables",
        "_views",
        "_watchers",
        "grid",
        "model",
        "noise",
        "switch",
    )

    def __init__(
        self, model: FaultModel, grid: FreeGrid | None, switch: bool = True, noise: float = 0.0
    ) -> None:
        ObservationModel(noise)  # validates the rate
        self.model = model
        self.grid = grid
        self.switch = switch
        self.noise = noise
        """The error rate of the robot's own odometry (0: exact readings)."""
        self._tables = _TABLES.get(model, lambda: _tables(model))
        self._at: dict[Pose, _At] = {}
        self._memo: dict[tuple[bytes, bytes, bytes, Pose, int], float] = {}
        self._evidence: dict[Pose, npt.NDArray[np.int64]] = {}
        self._views: dict[Pose, _At] = {}
        self._watchers: tuple[Watcher, ...] = ()

    def at(self, pose: Pose) -> _At:
        """The outcomes of every command from ``pose`` (kept): what the robot and teammates
        that read its pose can tell apart."""
        found = self._at.get(pose)
        if found is None:
            found = self._at[pose] = self._outcomes(pose, None)
        return found

    def view(self, pose: Pose) -> _At:
        """The outcomes of every command from ``pose`` as the readings of the current
        :meth:`plan`'s watchers tell them apart: :meth:`at`, with each outcome a teammate with
        the wheel view sees split by the action performed (kept until the next plan)."""
        wheels = [(o, stands) for o, stands in self._watchers if o.wheels]
        if not wheels:
            return self.at(pose)
        found = self._views.get(pose)
        if found is None:
            found = self._views[pose] = self._outcomes(
                pose, lambda end: any(o.watches(stands, pose, end) for o, stands in wheels)
            )
        return found

    def _outcomes(self, pose: Pose, split: Callable[[Pose], bool] | None) -> _At:
        """The :class:`_At` of ``pose``; ``split(end)``: whether the outcomes ending at ``end``
        are told apart by the action performed (``None``: never)."""
        model, tables = self.model, self._tables
        n_actions, n_classes = len(model.domain.actions), len(model.classes)
        keys: dict[tuple[Any, ...], int] = {}
        ends: list[Pose] = []
        outcomes: list[tuple[Pose, bool, bool]] = []
        performed: list[dict[int, None]] = []
        seen: dict[Pose, bool] = {}
        label = np.empty((n_actions, n_classes), dtype=np.intp)
        bumps = np.empty((n_actions, n_classes))
        ticks = np.empty((n_actions, n_classes))
        h = pose.heading
        for a in range(n_actions):
            labels, bumped, durations = [], [], []
            for g, (group, (end, bump, fails)) in enumerate(
                predictions(model, a, pose, self.grid)
            ):
                key: tuple[Any, ...] = (end, bump, fails) if self.switch else (end, fails)
                there = Pose(pose.x + end.x, pose.y + end.y, end.heading)
                if split is not None and not fails:
                    if there not in seen:
                        seen[there] = split(there)
                    if seen[there]:
                        key = (*key, group.performed)
                number = keys.setdefault(key, len(keys))
                if number == len(ends):
                    ends.append(there)
                    outcomes.append((end, bump, fails))
                    performed.append({})
                performed[number][group.performed] = None
                labels.append(number)
                bumped.append(float(bump))
                durations.append(1.0 if bump else tables.ticks[a][h][g])
            index = tables.group[a][h]
            label[a] = np.asarray(labels, dtype=np.intp)[index]
            bumps[a] = np.asarray(bumped)[index]
            ticks[a] = np.asarray(durations)[index]
        onehot = np.zeros((n_actions, n_classes, len(ends)))
        onehot[np.arange(n_actions)[:, None], np.arange(n_classes)[None, :], label] = 1.0
        return _At(
            label,
            onehot,
            tuple(ends),
            tuple(outcomes),
            tuple(tuple(p) for p in performed),
            bumps,
            ticks,
        )

    def evidence(self, pose: Pose) -> npt.NDArray[np.int64]:
        """``evidence[l, m]``: what the readings of a command from ``pose`` that ends in outcome
        ``l`` (read exactly, as the plan assumes) say against a class predicting outcome ``m``:
        the contradictions they add (the robot's own reading, with its bump switch when it has
        one, and one reading per watcher in range of the whole motion, each by its sensor's
        noise: see :func:`_against`; a watcher with the wheel view adds its actuator reading,
        :func:`_wheels_against`), or :data:`RULED_OUT` (ruled out). Outcomes are those of
        :meth:`view`. For the watchers of the current :meth:`plan` (kept until the next)."""
        found = self._evidence.get(pose)
        if found is not None:
            return found
        at = self.view(pose)
        outcomes, ends, performed = at.outcomes, at.ends, at.performed
        seeing = [
            [(o.noise, o.wheels) for o, stands in self._watchers if o.watches(stands, pose, end)]
            for end in ends
        ]
        wheels = any(o.wheels for o, _ in self._watchers)
        table = actuators_of(self.model.domain) if wheels else None
        n = len(outcomes)
        out = np.zeros((n, n), dtype=np.int64)
        for read, (end, bump, fails) in enumerate(outcomes):
            for m, (other, other_bump, other_fails) in enumerate(outcomes):
                if read == m:
                    continue
                if fails != other_fails or (self.switch and bump != other_bump):
                    out[read, m] = RULED_OUT  # the switch and the failed signal are exact
                    continue
                total = _against(end, other, self.noise)
                for noise, sees in seeing[read]:
                    total = min(RULED_OUT, total + _against(end, other, noise))
                    if sees and table is not None and not fails and len(performed[read]) == 1:
                        said = _wheels_against(table, performed[read][0], performed[m], noise)
                        total = min(RULED_OUT, total + said)
                out[read, m] = total
        self._evidence[pose] = out
        return out

    def plan(
        self,
        belief: FaultBelief,
        pose: Pose,
        mask: int | None = None,
        depth: int = 3,
        watchers: Sequence[Watcher] = (),
    ) -> Any | None:
        """The first command of the adaptive probe plan that isolates the classes of ``mask``
        (default: the hypotheses still possible) from ``pose``, or ``None`` when one class is
        left or no command splits them.

        The plan is a tree of up to ``depth`` commands, each chosen after reading the outcome of
        the one before; the robot re-plans after every reading, so only the first command is
        returned. Plans are compared first by the *worst case* over the parsimonious classes
        (those of the fewest faults still possible, the minimal diagnoses): the commands until
        each of them is isolated; then by the expected cost under the posterior: the commands
        until one class is left, plus :data:`BUMP_COST` per expected bump and
        :data:`TICK_COST` per expected tick. Beyond ``depth``, estimates: one more command for
        a parsimonious class not isolated yet, ``1 + log2(classes) / 3`` expected. Depth-first
        branch and bound: commands are tried in the order of a lower bound, ties to the first
        in the domain's order.

        What the readings of a command say is counted as the belief counts it (the plan takes
        every reading to be right): with exact odometry a differing reading rules a class out;
        with noisy odometry (:attr:`noise`) a reading one perturbation away from a class's
        prediction only contradicts it, and a class is isolated once every rival is
        contradicted :data:`~.belief.CONFIRMATIONS` times more than it
        (:meth:`FaultBelief.isolated`); the rivals' contradictions so far
        (:attr:`FaultBelief.misses`) are where the plan starts. Each of ``watchers`` (teammates,
        where they stand; they stay there while the plan runs) that sees the whole motion of a
        command adds its own reading, with its own noise, and no bump switch; one with the wheel
        view also its reading of the actuators (each actuator that differs from a class's
        performed action one contradiction, or ruled out when exact), and the outcomes it sees
        are told apart by the action performed (:meth:`view`). So a teammate in range can
        confirm in the same command what the robot alone confirms with a second."""
        model = self.model
        alive = belief.alive if mask is None else mask & belief.alive
        classes = np.asarray(model.classes_in(alive), dtype=np.intp)
        if len(classes) < 2:
            return None
        misses = np.zeros(len(classes), dtype=np.int64)
        if self.noise > 0 or any(o.noise > 0 for o, _ in watchers):
            seen = belief.misses
            for j, c in enumerate(classes):
                misses[j] = round(min(seen[h] for h in model.members(model.classes[c] & alive)))
            misses = np.minimum(misses - misses.min(), CONFIRMATIONS - 1)
        # the candidates: the classes every reading so far agrees with, as inside the plan (a
        # class a reading contradicted stays a rival to contradict again, not a truth to plan for)
        cand = misses == 0
        mass = np.where(cand, belief.class_posterior()[classes], 0.0)
        if float(mass.sum()) <= 0:
            mass = cand.astype(float)
        sizes = np.asarray(
            [min(len(model.sets[h]) for h in model.members(model.classes[c])) for c in classes]
        )
        primary = np.zeros(len(model.classes))
        primary[classes[cand & (sizes == sizes[cand].min())]] = 1.0
        watchers = tuple(watchers)
        if watchers != self._watchers:
            self._watchers = watchers
            self._evidence.clear()
            self._views.clear()
        self._memo.clear()  # the weights and the parsimonious classes change with the belief
        found = self._search(
            classes, misses, cand, mass / mass.sum(), primary, pose, depth, root=True
        )
        return None if found is None else model.domain.actions[int(found)]

    def _exact(self) -> bool:
        """Whether every reading is exact (a differing one rules a class out)."""
        return self.noise == 0 and all(o.noise == 0 for o, _ in self._watchers)

    def _search(
        self,
        idx: npt.NDArray[np.intp],
        misses: npt.NDArray[np.int64],
        cand: npt.NDArray[np.bool_],
        w: npt.NDArray[np.float64],
        primary: npt.NDArray[np.float64],
        pose: Pose,
        depth: int,
        root: bool = False,
    ) -> Any:
        """The value ``_WORST * worst + expected`` of the best plan isolating classes ``idx``
        from ``pose`` in ``depth`` commands (see :meth:`plan`); at the root, the best action's
        index instead (``None``: no command splits them). ``misses``: per class, the
        contradictions it has more than the least contradicted (below
        :data:`~.belief.CONFIRMATIONS`); ``cand``: the classes that may be the truth here (the
        others disagree with a reading of the plan, but not yet enough); ``w``: the weights of
        the candidates (zero for the others), summing to 1."""
        n = len(idx)
        first = (primary[idx] * cand).sum() > 0
        if n <= 1:
            return 0.0
        if depth == 0:
            return _WORST * first + 1.0 + math.log2(n) / 3.0
        key = (idx.tobytes(), misses.tobytes(), cand.tobytes(), pose, depth)
        if not root and key in self._memo:
            return self._memo[key]
        at = self.view(pose)
        onehot = at.onehot[:, idx, :]
        parts = np.einsum("acl,c->al", onehot, w)
        counts = onehot.sum(axis=1)
        splits = (counts > 0).sum(axis=1) >= 2
        if self._exact():  # a branch keeps the classes of its outcome
            sizes, keep, low, new = counts, None, None, None
        else:  # a branch keeps every class not yet contradicted enough
            labels = at.label[:, idx]
            against = self.evidence(pose)[labels[:, :, None], labels[:, None, :]]
            new = misses[None, None, :] + against
            low = new.min(axis=2)
            keep = new < low[:, :, None] + CONFIRMATIONS
            sizes = np.zeros_like(counts)
            rows, cols = np.nonzero(np.broadcast_to(cand, labels.shape))
            sizes[rows, labels[rows, cols]] = keep.sum(axis=2)[rows, cols]
        ambiguous_first = (np.einsum("acl,c->al", onehot, primary[idx] * cand) > 0) & (sizes > 1)
        own = 1.0 + BUMP_COST * (at.bumps[:, idx] @ w) + TICK_COST * (at.ticks[:, idx] @ w)
        own = own + _WORST * first
        if not splits.any():
            value: float = _WORST * (depth + 1) * first + 2.0 + math.log2(n)
            if not root:
                self._memo[key] = value
            return None if root else value
        if depth == 1:
            leaf = np.where(sizes > 1, 1.0 + np.log2(np.maximum(sizes, 1)) / 3.0, 0.0)
            worst = _WORST * ambiguous_first.any(axis=1)
            costs = np.where(splits, own + worst + (parts * leaf).sum(axis=1), np.inf)
            best = int(np.argmin(costs))
            if root:
                return best
            self._memo[key] = float(costs[best])
            return float(costs[best])
        bounds = own + _WORST * ambiguous_first.any(axis=1) + (parts * (sizes > 1)).sum(axis=1)
        bounds = np.where(splits, bounds, np.inf)
        order = np.argsort(bounds, kind="stable")
        best_value, best_action = math.inf, -1
        for a in order:
            if bounds[a] >= best_value - 1e-12:
                break
            expected, worst = float(own[a]), 0.0
            labels = at.label[a, idx]
            for part in np.flatnonzero(sizes[a] > 1):
                mine = labels == part
                if keep is None or new is None or low is None:
                    inside, sub_misses, sub_cand = mine, misses[mine], cand[mine]
                else:
                    j = int(np.flatnonzero(mine & cand)[0])
                    inside = keep[a, j]
                    sub_misses = new[a, j, inside] - low[a, j]
                    sub_cand = cand[inside] & mine[inside]
                sub = np.where(sub_cand, w[inside], 0.0)
                total = float(sub.sum())
                sub = sub / total if total > 0 else sub_cand / float(sub_cand.sum())
                got = self._search(
                    idx[inside], sub_misses, sub_cand, sub, primary, at.ends[part], depth - 1
                )
                high = _WORST * math.floor(got / _WORST)
                worst = max(worst, high)
                expected += float(parts[a, part]) * (got - high)
                if expected + worst >= best_value - 1e-12:
                    break
            value = expected + worst
            if value < best_value - 1e-12:
                best_value, best_action = value, int(a)
        if root:
            return best_action
        self._memo[key] = best_value
        return best_value


def isolating_probe(
    belief: FaultBelief,
    pose: Pose,
    mask: int | None = None,
    *,
    depth: int = 3,
    switch: bool = True,
    planner: ProbePlanner | None = None,
    noise: float = 0.0,
    watchers: Sequence[Watcher] = (),
) -> Probe | None:
    """The probe :meth:`ProbePlanner.plan` chooses (one command; ``planner``: one kept for the
    mission, else a new one with ``switch`` and the robot's odometry ``noise``; ``watchers``:
    the teammates that will watch it, where they stand), or, when no single command splits the
    hypotheses, the two-command sequence of :func:`best_probe`; ``None`` when nothing splits
    them. ``information`` is the entropy of the first command's split (bits), ``ticks`` its
    expected ticks."""
    model = belief.model
    alive = _to_split(belief, mask)
    if alive is None:
        return None
    if planner is None:
        planner = ProbePlanner(model, belief.grid, switch, noise)
    action = planner.plan(belief, pose, alive, depth, watchers)
    if action is None:
        return best_probe(belief, pose, alive)  # only a sequence splits them (walls)
    post = _posterior_over(belief, alive)
    split, ticks = _split(belief, model.index[action], pose, post, alive)
    return Probe((action,), _entropy(m for _, m in split.values()), ticks)
