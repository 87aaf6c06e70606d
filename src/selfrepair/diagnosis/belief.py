"""One robot's belief about its faults, updated by one observation at a time.

A :class:`FaultBelief` holds, over the hypotheses of a :class:`~.hypotheses.FaultModel`:

- ``alive``, the bit set of the hypotheses no observation has ruled out (exact elimination: a
  hypothesis goes when the observation is impossible under it);
- the posterior, by Bayes' rule from the model's prior: each observation multiplies the weight of
  every hypothesis by the likelihood of the reading under it, with the observation's own noise
  rate (:mod:`~.observation`: ``1 - p`` for the predicted pose, ``p / 7`` for each of its seven
  wrong readings, 0 otherwise; the bump switch and the failed signal must match exactly).

An exact observation (``noise == 0``) costs one dictionary look-up and one ``&`` of two integers:
for each (action, heading, relative reading) the bit set of the hypotheses it is consistent with
is computed once and kept (the posterior is then the prior restricted to ``alive``, made when
asked). A noisy one also multiplies the weight vector by the kept likelihood vector. Near walls
the prediction depends on which motions the walls stop (a bump), so the key also holds which of
the command's motion groups are blocked there (tested in the grid once per action and pose met,
the union of their footprints first).

A teammate's actuator reading (``Observation.wheels``, the wheel view) enters the same entry as
its pose reading: each motion group performs one action, so a group's likelihood is the pose
term times the chance of reading that action's actuators as read
(:meth:`~.observation.Actuators.likelihood`: ``1 - p`` per actuator read as the group sets it,
``p / (m - 1)`` per actuator read as another of its ``m`` states), and each actuator read
otherwise counts as one more reading the group explains only as a sensor error
(:attr:`FaultBelief.misses`). Exact (``p == 0``), a group whose actuators differ is ruled out.

An observation that no hypothesis still possible explains (a fault outside the hypotheses, a
wrong behaviour model) changes nothing and is counted in :attr:`FaultBelief.inexplicable`.
Observations of the robot made by teammates enter the same way (their ``source`` and ``noise``
say who made them and how good their sensor is).
"""

from __future__ import annotations

from itertools import repeat
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.diagnosis.hypotheses import FAILS, FaultModel, Group
from selfrepair.diagnosis.observation import PERTURBATIONS, Observation, actuators_of, perturbed
from selfrepair.geometry import FreeGrid, Heading, Pose
from selfrepair.limits import DEFAULT_CONFIDENCE
from selfrepair.textio import JSONObject

__all__ = ["CONFIRMATIONS", "DEFAULT_CONFIDENCE", "FaultBelief", "Prediction", "predictions"]

CONFIRMATIONS = 2
"""How many more noisy readings must contradict every rival of a class than its own best
hypothesis before the class counts as isolated under noise (:meth:`FaultBelief.isolated`)."""


_Entry = tuple[int, "npt.NDArray[np.float64] | None", "npt.NDArray[np.float64] | None"]
"""A kept reading: its support bit set, its likelihood vector and its contradiction indicator
(the last two only for a noisy reading)."""

_RENORMALISE = 32
"""Noisy updates between two renormalisations of the weights (against underflow)."""

Prediction = tuple[Pose, bool, bool]
"""What a group of hypotheses predicts for one command: the pose after it relative to the start
cell (the start heading kept), whether it bumps and whether it fails."""


def _predicted(group: Group, blocked: bool, heading: Heading) -> Prediction:
    if blocked:
        return Pose(0, 0, heading), True, False
    if group.performed == FAILS:
        return Pose(0, 0, heading), False, True
    return Pose(group.dx, group.dy, group.heading), False, False


def predictions(
    model: FaultModel, action: int, pose: Pose, grid: FreeGrid | None
) -> tuple[tuple[Group, Prediction], ...]:
    """Each motion group of ``action`` (an index) from ``pose`` with what it predicts there (see
    :data:`Prediction`); ``grid`` (``None``: an open plane) says which motions a wall stops."""
    groups = model.groups[action][pose.heading]
    out = []
    for group in groups:
        blocked = grid is not None and not grid.all_free(
            [(pose.x + dx, pose.y + dy) for dx, dy in group.cells[1:]]
        )
        out.append((group, _predicted(group, blocked, pose.heading)))
    return tuple(out)


class FaultBelief:
    """The belief of one robot about its faults (see the module docstring). Mutable: one per
    robot and mission. ``grid`` is the map the robot knows (``None``: an open plane)."""

    __slots__ = (
        "_blocks",
        "_cache",
        "_count",
        "_unions",
        "alive",
        "grid",
        "inexplicable",
        "misses",
        "model",
        "observations",
        "weights",
    )

    def __init__(self, model: FaultModel, grid: FreeGrid | None = None) -> None:
        self.model = model
        self.grid = grid
        self.alive = model.all
        """The bit set of the hypotheses still possible."""
        self.weights: npt.NDArray[np.float64] = model.prior.copy()
        self.observations = 0
        """Observations taken in so far."""
        self.inexplicable = 0
        """Observations no hypothesis still possible explained (ignored)."""
        self.misses: npt.NDArray[np.float64] = np.zeros(model.size)
        """Per hypothesis, the noisy readings it explains only as a sensor error (a reading
        other than the one it predicts)."""
        self._count = 0
        self._cache: dict[tuple[Any, ...], _Entry] = {}
        self._unions: dict[tuple[int, int], tuple[int, ...]] = {}
        self._blocks: dict[tuple[int, int, int, int], tuple[bool, ...] | None] = {}

    def update(self, observation: Observation) -> int:
        """Take ``observation`` in; returns the new :attr:`alive`."""
        action, start, end, bumped, failed, noise, wheels = (
            observation.action, observation.start, observation.end, observation.bumped,
            observation.failed, observation.noise, observation.wheels,
        )  # fmt: skip
        a = self.model.index[action]
        heading = start.heading
        where = (a, heading, start.x, start.y)
        blocks = self._blocks
        if where in blocks:
            blocked = blocks[where]
        else:  # not looked at here yet
            blocked = blocks[where] = self._blocked(a, start)
        key = (
            a, heading, blocked, end.x - start.x, end.y - start.y, end.heading, bumped, failed,
            noise, wheels,
        )  # fmt: skip
        entry = self._cache.get(key)
        if entry is None:
            entry = self._cache[key] = self._likelihood(a, heading, blocked, key, noise)
        support, likelihood, missed = entry
        self.observations += 1
        alive = self.alive & support
        if not alive:
            self.inexplicable += 1
            return self.alive
        self.alive = alive
        if likelihood is not None and missed is not None:
            self.weights *= likelihood
            self.misses += missed
            self._count += 1
            if self._count % _RENORMALISE == 0:
                self.weights /= self.weights.sum()
        return alive

    def _blocked(self, action: int, start: Pose) -> tuple[bool, ...] | None:
        """``None`` when no motion group of ``action`` from ``start`` meets a wall (the common
        case, one test of the union of their footprints); else, per group, whether it does."""
        grid = self.grid
        if grid is None:
            return None
        heading = int(start.heading)
        union = self._unions.get((action, heading))
        if union is None:
            cells = {c for g in self.model.groups[action][heading] for c in g.cells[1:]}
            union = tuple(sorted(dy * grid.stride + dx for dx, dy in cells))
            self._unions[(action, heading)] = union
        x, y = start.x, start.y
        if 0 <= x < grid.width and 0 <= y < grid.height:
            data, base = grid.data, grid.index(x, y)
            if all(data[base + o] for o in union):
                return None
        return tuple(
            not grid.all_free([(x + dx, y + dy) for dx, dy in g.cells[1:]])
            for g in self.model.groups[action][heading]
        )

    def _likelihood(
        self,
        action: int,
        heading: Heading,
        blocked: tuple[bool, ...] | None,
        key: tuple[Any, ...],
        noise: float,
    ) -> _Entry:
        """The support bit set and (noisy readings only) the likelihood vector of ``key`` and
        the indicator of the hypotheses it contradicts (their predicted reading is another)."""
        reading = Pose(key[3], key[4], key[5])
        bumped, failed, wheels = key[6], key[7], key[9]
        likelihood = np.zeros(self.model.size) if noise > 0 else None
        missed = np.zeros(self.model.size) if noise > 0 else None
        support = 0
        groups = self.model.groups[action][heading]
        read = None
        if wheels is not None:
            actuators, read = actuators_of(self.model.domain), self.model.index[wheels]
        for group, stopped in zip(groups, blocked or repeat(False), strict=False):
            end, bumps, fails = _predicted(group, stopped, heading)
            if fails != failed or (bumped is not None and bumps != bumped):
                continue
            misses = 0
            if reading == end:
                value = 1.0 - noise
            elif noise > 0 and reading in perturbed(end):
                value, misses = noise / PERTURBATIONS, 1
            else:
                continue
            if read is not None and group.performed != FAILS:
                wrong = actuators.mismatches(read, group.performed)
                if wrong and noise == 0:
                    continue
                value *= actuators.likelihood(read, group.performed, noise)
                misses += wrong
            if misses and missed is not None:
                missed[list(group.members)] = float(misses)
            support |= group.mask
            if likelihood is not None:
                likelihood[list(group.members)] = value
        return support, likelihood, missed

    # --- what the belief says --------------------------------------------------------------

    def posterior(self) -> npt.NDArray[np.float64]:
        """The posterior over the hypotheses (zero outside :attr:`alive`), normalised."""
        alive = self.alive
        mask = np.fromiter(((alive >> i) & 1 for i in range(self.model.size)), float)
        weights: npt.NDArray[np.float64] = self.weights * mask
        return weights / float(weights.sum())

    def class_posterior(self) -> npt.NDArray[np.float64]:
        """The posterior mass of each class (:attr:`FaultModel.classes` order)."""
        post = self.posterior()
        out = np.zeros(len(self.model.classes))
        np.add.at(out, np.asarray(self.model.class_of), post)
        return out

    def most_probable(self) -> tuple[int, frozenset[Any]]:
        """The most probable class (ties: the first) and the fault set of its most probable
        hypothesis (ties: the first)."""
        post = self.posterior()
        mass = np.zeros(len(self.model.classes))
        np.add.at(mass, np.asarray(self.model.class_of), post)
        best = int(np.argmax(mass))
        members = self.model.members(self.model.classes[best])
        top = max(members, key=lambda i: (post[i], -i))
        return best, self.model.sets[top]

    def credible(self, error: float) -> int:
        """The bit set of the hypotheses (alive) of the fewest most probable classes whose mass
        is at least ``1 - error`` (ties by class order)."""
        mass = self.class_posterior()
        order = sorted(range(len(mass)), key=lambda c: (-mass[c], c))
        mask, total = 0, 0.0
        for c in order:
            if mass[c] <= 0 or total >= 1.0 - error:
                break
            mask |= self.model.classes[c]
            total += float(mass[c])
        return mask & self.alive

    def classes_alive(self) -> tuple[int, ...]:
        """The classes that still hold a possible hypothesis."""
        return self.model.classes_in(self.alive)

    def contenders(self, error: float) -> int:
        """The bit set of the hypotheses still in the running: those of the credible classes
        (:meth:`credible`) and every hypothesis still possible that fewer than
        :data:`CONFIRMATIONS` noisy readings more than the credible classes' best one
        contradict. With exact readings only: every hypothesis still possible."""
        credible = self.credible(error)
        if not credible:
            return self.alive
        misses = self.misses
        floor = min(misses[i] for i in self.model.members(credible))
        alive, out = self.alive, credible
        for i in self.model.members(alive & ~credible):
            if misses[i] < floor + CONFIRMATIONS:
                out |= 1 << i
        return out & alive

    def isolated(self, error: float = 0.0) -> int | None:
        """The class the belief has isolated, or ``None``: the one class left of the
        hypotheses still possible, or (``error > 0``) the one class of the :meth:`contenders`:
        it holds posterior mass at least ``1 - error`` and every rival is contradicted by
        :data:`CONFIRMATIONS` noisy readings more than it (one wrong reading never isolates a
        class: a second must confirm it)."""
        alive = self.classes_alive()
        if len(alive) == 1:
            return alive[0]
        if error > 0:
            left = self.model.classes_in(self.contenders(error))
            if len(left) == 1:
                return left[0]
        return None

    def snapshot(self) -> JSONObject:
        """A JSON-able summary for traces: hypotheses and classes still possible, the most
        probable class's fault set and mass."""
        best, faults = self.most_probable()
        return {
            "alive": bin(self.alive).count("1"),
            "classes": len(self.classes_alive()),
            "most_probable": self.model.domain.format_faults(faults) or "none",
            "mass": round(float(self.class_posterior()[best]), 6),
        }
