"""Evaluating a policy on :class:`~selfrepair.envs.env.FaultyMazeEnv`: episodes, success rate and
return, with 95% intervals.

:func:`evaluate` runs ``episodes`` episodes, episode ``i`` reset with the ``i``-th seed that
``numpy.random.SeedSequence(seed)`` generates, so two policies evaluated with the same seed meet
the same mazes, routes and faults (paired comparisons). :func:`run_episode` runs one episode and
accepts ``reset`` options (to replay a given mission).

Intervals (:mod:`selfrepair.stats`, the one statistics module): the success rate gets the Wilson
score interval (good at rates near 0 and 1, where the normal approximation fails) and the mean
return a percentile bootstrap interval seeded by the evaluation's seed; both are undefined
(``nan`` ends) for too few episodes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from selfrepair.envs.env import FaultyMazeEnv
from selfrepair.envs.policies import Policy
from selfrepair.errors import ProblemError
from selfrepair.stats import LEVEL, Interval, bootstrap_interval, wilson_interval
from selfrepair.status import EpisodeEnd

__all__ = [
    "MAX_EPISODES",
    "Episode",
    "EpisodeEnd",
    "Evaluation",
    "episode_seeds",
    "evaluate",
    "run_episode",
]

BOOTSTRAP_RESAMPLES_EVAL = 9999
"""Bootstrap resamples of an evaluation's return interval (episodes are few and cheap)."""

MAX_EPISODES = 10_000
"""The most episodes :func:`evaluate` runs unless its ``max_episodes`` is raised."""

CONFIDENCE = LEVEL
"""The default confidence of the intervals (:data:`selfrepair.stats.LEVEL`)."""


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


def _undefined(n: int, level: float) -> Interval:
    """An interval that does not exist (too few episodes), with ``nan`` ends."""
    nan = float("nan")
    return Interval(nan, nan, nan, n, level)


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
        """The Wilson interval of the success rate (``nan`` ends without episodes)."""
        n = len(self.episodes)
        found = wilson_interval(self.successes, n, confidence)
        return _undefined(n, confidence) if found is None else found

    def return_interval(self, confidence: float = CONFIDENCE) -> Interval:
        """The percentile-bootstrap interval of the mean return, seeded by the evaluation's
        seed (``nan`` ends for fewer than two episodes)."""
        returns = [e.episode_return for e in self.episodes]
        found = bootstrap_interval(
            returns, "mean", level=confidence, seed=self.seed, resamples=BOOTSTRAP_RESAMPLES_EVAL
        )
        return _undefined(len(returns), confidence) if found is None or len(returns) < 2 else found


def episode_seeds(seed: int, episodes: int) -> tuple[int, ...]:
    """The reset seeds of an evaluation's episodes (see the module docstring)."""
    return tuple(int(s) for s in np.random.SeedSequence(seed).generate_state(episodes))


def run_episode(
    env: FaultyMazeEnv,
    policy: Policy,
    seed: int,
    options: Mapping[str, object] | None = None,
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
