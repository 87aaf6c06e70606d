"""Evaluating a policy on :class:`~selfrepair.envs.env.FaultyMazeEnv`: episodes, success rate and
return, with 95% intervals.

:func:`evaluate` runs ``episodes`` episodes, episode ``i`` reset with the ``i``-th seed that
``numpy.random.SeedSequence(seed)`` generates, so two policies evaluated with the same seed meet
the same mazes, routes and faults (paired comparisons). :func:`run_episode` runs one episode and
accepts ``reset`` options (to replay a given mission).

Intervals: the success rate gets the Wilson score interval (good at rates near 0 and 1, where
the normal approximation fails) and the mean return a percentile bootstrap interval, both from
SciPy (``scipy.stats.binomtest(...).proportion_ci`` and ``scipy.stats.bootstrap``, seeded).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from selfrepair.envs.env import FaultyMazeEnv
from selfrepair.envs.policies import Policy
from selfrepair.errors import ProblemError
from selfrepair.status import EpisodeEnd

__all__ = [
    "MAX_EPISODES",
    "Episode",
    "EpisodeEnd",
    "Evaluation",
    "Interval",
    "bootstrap_interval",
    "episode_seeds",
    "evaluate",
    "run_episode",
    "wilson_interval",
]

MAX_EPISODES = 10_000
"""The most episodes :func:`evaluate` runs unless its ``max_episodes`` is raised."""

CONFIDENCE = 0.95


@dataclass(frozen=True, slots=True)
class Episode:
    """One episode's situation (as the reset info names it) and outcome."""

    seed: int
    maze: str
    start: str
    goal: str
    faults: str
    end: EpisodeEnd
    steps: int
    episode_return: float

    @property
    def reached(self) -> bool:
        """Whether the goal was reached."""
        return self.end is EpisodeEnd.REACHED


@dataclass(frozen=True, slots=True)
class Interval:
    """A two-sided confidence interval (``nan`` ends when it is undefined)."""

    low: float
    high: float
    confidence: float = CONFIDENCE


def wilson_interval(successes: int, trials: int, confidence: float = CONFIDENCE) -> Interval:
    """The Wilson score interval of a success rate (SciPy's ``binomtest``)."""
    if trials < 1:
        return Interval(float("nan"), float("nan"), confidence)
    from scipy.stats import binomtest

    ci = binomtest(successes, trials).proportion_ci(confidence_level=confidence, method="wilson")
    return Interval(float(ci.low), float(ci.high), confidence)


def bootstrap_interval(
    values: np.ndarray | list[float], confidence: float = CONFIDENCE, seed: int = 0
) -> Interval:
    """A percentile bootstrap interval of the mean of ``values`` (SciPy's ``bootstrap``, 9999
    resamples, seeded). Undefined (``nan``) for fewer than two values; a single point when all
    values are equal."""
    data = np.asarray(values, dtype=float)
    if data.size < 2:
        return Interval(float("nan"), float("nan"), confidence)
    if np.all(data == data[0]):
        return Interval(float(data[0]), float(data[0]), confidence)
    from scipy.stats import bootstrap

    result = bootstrap(
        (data,),
        np.mean,
        confidence_level=confidence,
        method="percentile",
        n_resamples=9999,
        rng=np.random.default_rng(seed),
    )
    ci = result.confidence_interval
    return Interval(float(ci.low), float(ci.high), confidence)


@dataclass(frozen=True, slots=True)
class Evaluation:
    """Every episode of one policy's evaluation, and its summary figures."""

    policy: str
    seed: int
    episodes: tuple[Episode, ...]

    @property
    def successes(self) -> int:
        """Episodes that reached the goal."""
        return sum(e.reached for e in self.episodes)

    @property
    def success_rate(self) -> float:
        """The share of episodes that reached the goal."""
        return self.successes / len(self.episodes) if self.episodes else float("nan")

    @property
    def mean_return(self) -> float:
        """The mean undiscounted return."""
        if not self.episodes:
            return float("nan")
        return float(np.mean([e.episode_return for e in self.episodes]))

    def success_interval(self, confidence: float = CONFIDENCE) -> Interval:
        """The Wilson interval of the success rate."""
        return wilson_interval(self.successes, len(self.episodes), confidence)

    def return_interval(self, confidence: float = CONFIDENCE) -> Interval:
        """The bootstrap interval of the mean return (seeded by the evaluation's seed)."""
        returns = [e.episode_return for e in self.episodes]
        return bootstrap_interval(returns, confidence, self.seed)


def episode_seeds(seed: int, episodes: int) -> tuple[int, ...]:
    """The reset seeds of an evaluation's episodes (see the module docstring)."""
    return tuple(int(s) for s in np.random.SeedSequence(seed).generate_state(episodes))


def run_episode(
    env: FaultyMazeEnv,
    policy: Policy,
    seed: int,
    options: Mapping[str, Any] | None = None,
) -> Episode:
    """Reset ``env`` with ``seed`` (and ``options``), start ``policy`` and run to the end."""
    observation, info = env.reset(seed=seed, options=dict(options) if options else None)
    policy.reset(env, seed)
    start = info
    total = 0.0
    steps = 0
    end = EpisodeEnd.GAVE_UP
    while True:
        action = policy(observation, info)
        if action is None:
            break
        observation, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        steps += 1
        if terminated or truncated:
            end = EpisodeEnd.REACHED if terminated else EpisodeEnd.TRUNCATED
            break
    return Episode(
        seed, start["maze"], start["start"], start["goal"], start["faults"], end, steps, total
    )


def evaluate(
    env: FaultyMazeEnv,
    policy: Policy,
    episodes: int,
    *,
    seed: int = 0,
    max_episodes: int = MAX_EPISODES,
) -> Evaluation:
    """Run ``episodes`` episodes of ``policy`` on ``env`` (see the module docstring)."""
    if not 1 <= episodes <= max_episodes:
        raise ProblemError(
            f"episodes must be from 1 to {max_episodes}, got {episodes} "
            "(raise the limit with --max-episodes)"
        )
    runs = tuple(run_episode(env, policy, s) for s in episode_seeds(seed, episodes))
    return Evaluation(policy.name, seed, runs)
