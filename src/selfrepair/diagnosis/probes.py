"""Active diagnosis, the greedy probe: the command (or short sequence) that best splits the
hypotheses still possible, per tick (:mod:`.probeplan` plans several commands ahead).

For each candidate command the hypotheses still possible fall into groups by what they predict
there (:func:`~.belief.predictions`: the pose after it, a bump, a failure); the expected
information of the command is the entropy of that split under the posterior (for exact,
deterministic outcomes the mutual information between hypothesis and outcome). A probe's value is
its information per expected tick (the performed motion's duration, one tick for a bump or a
failure). Commands are scored in the domain's order, ties to the first. When no single command
splits the hypotheses (walls around can hide the difference), sequences of two are scored: the
first command must not bump under any hypothesis still possible, the second is scored from where
each group of the first ends.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import numpy as np
import numpy.typing as npt

from selfrepair.diagnosis.belief import FaultBelief, predictions
from selfrepair.diagnosis.hypotheses import FAILS
from selfrepair.geometry import Pose

__all__ = ["Probe", "best_probe"]


@dataclass(frozen=True, slots=True)
class Probe:
    """The commands of a probe, their expected information (bits) and expected ticks."""

    actions: tuple[Any, ...]
    information: float
    ticks: float


def _entropy(masses: Iterable[float]) -> float:
    total = 0.0
    for m in masses:
        if m > 0:
            total -= m * math.log2(m)
    return total


def _split(
    belief: FaultBelief, action: int, pose: Pose, post: npt.NDArray[np.float64], alive: int
) -> tuple[dict[tuple[Any, ...], tuple[int, float]], float]:
    """The outcome groups of ``action`` from ``pose`` among ``alive``: per distinct prediction
    (bump switch read only when the robot has one: not assumed here, a bump and staying put
    differ in the pose only when the motion would have moved), the hypotheses and their mass; and
    the expected ticks."""
    model = belief.model
    out: dict[tuple[Any, ...], tuple[int, float]] = {}
    ticks = 0.0
    for group, (end, bumps, fails) in predictions(model, action, pose, belief.grid):
        mask = group.mask & alive
        if not mask:
            continue
        mass = float(sum(post[i] for i in model.members(mask)))
        key = (end, bumps, fails)
        bits, total = out.get(key, (0, 0.0))
        out[key] = (bits | mask, total + mass)
        if bumps or fails or group.performed == FAILS:
            ticks += mass
        else:
            duration = model.domain.duration(model.domain.actions[group.performed])
            ticks += mass * float(Fraction(duration))
    return out, ticks


def _better(info: float, ticks: float, length: int, best: Probe, per_tick: bool) -> bool:
    """Whether a probe of ``info`` bits, ``ticks`` expected ticks and ``length`` commands beats
    ``best``: more information per tick (or per command), then fewer ticks."""
    if per_tick:
        return info / ticks > best.information / best.ticks + 1e-12
    mine, theirs = info / length, best.information / len(best.actions)
    return mine > theirs + 1e-12 or (abs(mine - theirs) <= 1e-12 and ticks < best.ticks)


def _to_split(belief: FaultBelief, mask: int | None) -> int | None:
    """The hypotheses of ``mask`` (default: all) still possible, as a mask, when they fall into
    two classes or more; ``None`` when there is nothing to split."""
    alive = belief.alive if mask is None else mask & belief.alive
    return alive if len(belief.model.classes_in(alive)) >= 2 else None


def _posterior_over(belief: FaultBelief, alive: int) -> npt.NDArray[np.float64]:
    """The posterior, normalised over the hypotheses of ``alive``."""
    post = belief.posterior()
    return post / float(sum(post[i] for i in belief.model.members(alive)))


def best_probe(
    belief: FaultBelief,
    pose: Pose,
    mask: int | None = None,
    *,
    per_tick: bool = True,
) -> Probe | None:
    """The probe of most information per tick that splits the hypotheses of ``mask`` (default:
    those still possible) from ``pose``; ``None`` when they cannot be split in two commands (one
    class left, or walls hide every difference)."""
    alive = _to_split(belief, mask)
    if alive is None:
        return None
    post = _posterior_over(belief, alive)
    actions = belief.model.domain.actions
    best: Probe | None = None
    for a in range(len(actions)):
        split, ticks = _split(belief, a, pose, post, alive)
        info = _entropy(m for _, m in split.values())
        if info > 1e-12 and (best is None or _better(info, ticks, 1, best, per_tick)):
            best = Probe((actions[a],), info, ticks)
    if best is not None:
        return best
    for a in range(len(actions)):
        first, ticks1 = _split(belief, a, pose, post, alive)
        if any(key[1] or key[2] for key in first):
            continue  # the first command must move under every hypothesis
        for b in range(len(actions)):
            masses: list[float] = []
            ticks = ticks1
            for (end, _, _), (bits, _) in first.items():
                at = Pose(pose.x + end.x, pose.y + end.y, end.heading)
                second, ticks2 = _split(belief, b, at, post, bits)
                masses.extend(m for _, m in second.values())
                ticks += ticks2
            info = _entropy(masses)
            if info > 1e-12 and (best is None or _better(info, ticks, 2, best, per_tick)):
                best = Probe((actions[a], actions[b]), info, ticks)
    return best
