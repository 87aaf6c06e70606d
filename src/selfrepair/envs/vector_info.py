"""What the vector environment reports besides its observations: the ``info`` arrays of a step
or reset (each key with its ``_key`` mask, as Gymnasium's vector environments give them), the
``final_obs``/``final_info`` of robots that ended in a same-step autoreset, the episode keys of a
reset, and the per-robot seeds of ``reset(seed=...)``. Pure functions of the environment's arrays
(:mod:`selfrepair.envs.vector` holds them)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from selfrepair.envs import _vector_kernels as _S
from selfrepair.errors import ProblemError

__all__ = [
    "EPISODE_KEYS",
    "Array",
    "Episodes",
    "batch_seeds",
    "copy_obs",
    "final_info",
    "step_info",
]

EPISODE_KEYS = (
    "maze", "start", "goal", "faults", "schedule", "detection",
    "fault_seed", "np_random_seed", "max_steps",
)  # fmt: skip
"""The single environment's episode keys, reported for the robots a call resets."""

Array = npt.NDArray[np.generic]
"""One of the environment's arrays over the robots (states, flags, rewards, observations)."""

Episodes = dict[str, list[str | int | None]]
"""Per episode key, the values of the robots reset, in robot order."""


def step_info(
    outcome: Array,
    state: Array,
    elapsed: Array,
    which: Array,
    episodes: Episodes,
    reset: Array | None = None,
) -> dict[str, object]:
    """The info of robots ``which`` (per-step keys: ``outcome``, ``pose``, ``ticks``) and of the
    robots that were reset (``reset``, default ``which``: the episode keys)."""
    n = len(outcome)
    mask = np.zeros(n, dtype=np.bool_)
    mask[which] = True
    info: dict[str, object] = {
        "outcome": outcome.copy(), "_outcome": mask,
        "pose": state[:, _S._X : _S._HEAD + 1].copy(), "_pose": mask.copy(),
        "ticks": elapsed.copy(), "_ticks": mask.copy(),
    }  # fmt: skip
    reset = which if reset is None else reset
    if reset.size and episodes.get("maze"):
        reset_mask = np.zeros(n, dtype=np.bool_)
        reset_mask[reset] = True
        for key, values in episodes.items():
            kind = np.int64 if isinstance(values[0], int) else object
            array = np.zeros(n, dtype=kind) if kind is np.int64 else np.full(n, None, object)
            array[reset] = values
            info[key], info[f"_{key}"] = array, reset_mask.copy()
    return info


def final_info(
    obs: dict[str, Array], outcome: Array, state: Array, elapsed: Array, ended: Array
) -> dict[str, object]:
    """``final_obs`` and ``final_info`` of the robots ``ended`` (same-step autoreset)."""
    n = len(outcome)
    mask = np.zeros(n, dtype=np.bool_)
    mask[ended] = True
    final_obs = np.full(n, None, dtype=object)
    for robot in ended.tolist():  # one robot's observation, as the single env gives it
        final_obs[robot] = {key: value[robot].copy() for key, value in obs.items()}
        final_obs[robot]["heading"] = int(obs["heading"][robot])
    last = {
        "outcome": outcome.copy(), "_outcome": mask.copy(),
        "pose": state[:, _S._X : _S._HEAD + 1].copy(), "_pose": mask.copy(),
        "ticks": elapsed.copy(), "_ticks": mask.copy(),
    }  # fmt: skip
    return {
        "final_obs": final_obs, "_final_obs": mask.copy(),
        "final_info": last, "_final_info": mask.copy(),
    }  # fmt: skip


def batch_seeds(seed: int | Sequence[int | None] | None, n: int) -> list[int | None]:
    """Robot ``i``'s seed for ``reset(seed=seed)``: ``seed + i``, or one of a list of ``n``."""
    if seed is None:
        return [None] * n
    if isinstance(seed, int | np.integer):
        return [int(seed) + i for i in range(n)]
    seeds = list(seed)
    if len(seeds) != n:
        raise ProblemError(f"expected {n} seeds (one per robot), got {len(seeds)}")
    return seeds


def copy_obs(obs: dict[str, Array]) -> dict[str, Array]:
    """A copy of the batch's observation arrays (the environment reuses its own)."""
    return {key: value.copy() for key, value in obs.items()}
