"""Baseline policies for :class:`~selfrepair.envs.env.FaultyMazeEnv`: the paper's two robots and a
random one.

``replacement``
    Planner + replacement table: plan from the start knowing no fault; when the next planned action
    is faulty under the known faults, take the table's first valid candidate, else replan. The
    paper's replacing robot (the environment's table and recursion mode).
``replan``
    Planner + replanning: the same, but every faulty action is met by a replan from scratch. The
    paper's replanning robot.
``random``
    A uniformly random action index at every step (seeded per episode).

A policy is started for each episode with :meth:`Policy.reset` (after the environment's reset)
and then called with each observation and info. The planner policies are *privileged*: they read
the environment's maze, pose and known faults (a :class:`~selfrepair.execution.stepper.Stepper`
made by the unwrapped environment, asked with :func:`~selfrepair.envs.env.ask`), as the executor
does; they are references to compare learned policies with,
not agents that see only the observation. A policy answers ``None`` when it gives up (no plan
exists under the known faults), as the executor stops a stuck mission.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import StrEnum
from typing import Any, Protocol

import numpy as np

from selfrepair.envs.env import FaultyMazeEnv, ask
from selfrepair.errors import ProblemError
from selfrepair.execution.stepper import Entry, Stepper
from selfrepair.repair.strategies import StrategyName

__all__ = [
    "POLICIES",
    "PlannerPolicy",
    "Policy",
    "PolicyName",
    "RandomPolicy",
    "make_policy",
    "policy_names",
]


class PolicyName(StrEnum):
    """The built-in baseline policies."""

    REPLACEMENT = StrategyName.REPLACEMENT
    REPLAN = StrategyName.REPLAN
    RANDOM = "random"


class Policy(Protocol):
    """A policy for :class:`FaultyMazeEnv` episodes."""

    name: str

    def reset(self, env: FaultyMazeEnv, seed: int) -> None:
        """Start an episode of ``env`` (already reset); ``seed`` seeds any randomness."""
        ...

    def __call__(self, observation: dict[str, Any], info: dict[str, Any]) -> int | None:
        """The action index to take, or ``None`` to give up."""
        ...


class PlannerPolicy:
    """A planner with a repair strategy of :mod:`selfrepair.repair.strategies` (privileged: see the
    module docstring)."""

    def __init__(self, strategy: str, name: str | None = None) -> None:
        self.strategy = strategy
        self.name = name or strategy
        self._env: FaultyMazeEnv | None = None
        self._stepper: Stepper | None = None
        self._pending: Entry | None = None

    def reset(self, env: FaultyMazeEnv, seed: int) -> None:
        """Plan from the robot's start, knowing no fault."""
        self._env = env
        self._stepper = env.stepper(self.strategy)
        self._pending = None

    def __call__(self, observation: dict[str, Any], info: dict[str, Any]) -> int | None:
        """The stepper's next action after recording what the previous command did."""
        env, stepper = self._env, self._stepper
        if env is None or stepper is None:
            raise ProblemError(f"policy {self.name!r}: call reset(env, seed) before acting")
        outcome = env.last_outcome
        if self._pending is not None and outcome is not None:
            stepper.observe(outcome, self._pending[1])
        entry, _ = ask(stepper, env.pose, env.known, env.steps)
        self._pending = entry
        return None if entry is None else env.action_index(entry[0])


class RandomPolicy:
    """Uniformly random action indices, from a generator seeded per episode."""

    name = PolicyName.RANDOM.value

    def __init__(self) -> None:
        self._rng = np.random.default_rng(0)
        self._count = 1

    def reset(self, env: FaultyMazeEnv, seed: int) -> None:
        """Seed the generator for this episode."""
        self._rng = np.random.default_rng(seed)
        self._count = len(env.actions)

    def __call__(self, observation: dict[str, Any], info: dict[str, Any]) -> int | None:
        """A random action index."""
        return int(self._rng.integers(self._count))


POLICIES: dict[str, Callable[[], Policy]] = {
    PolicyName.REPLACEMENT: lambda: PlannerPolicy(StrategyName.REPLACEMENT),
    PolicyName.REPLAN: lambda: PlannerPolicy(StrategyName.REPLAN),
    PolicyName.RANDOM: RandomPolicy,
}
"""Policy factories by name."""


def policy_names() -> tuple[str, ...]:
    """Every name :func:`make_policy` accepts."""
    return tuple(POLICIES)


def make_policy(name: str) -> Policy:
    """A new policy called ``name`` (one of :func:`policy_names`; anything else raises
    :class:`~selfrepair.errors.ProblemError` listing them)."""
    factory = POLICIES.get(name)
    if factory is None:
        raise ProblemError(f"unknown policy {name!r}; expected one of {', '.join(policy_names())}")
    return factory()
