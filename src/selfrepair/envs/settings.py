"""What the single and the vector Gymnasium environment check and build alike: the settings a
user gives (step limit, view radius, render mode, fault-behaviour model) and one robot's
observation space (see :mod:`selfrepair.envs.env` for what each key means)."""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from selfrepair.envs.scenarios import MazeSource
from selfrepair.errors import ProblemError
from selfrepair.robots.domain import SomeDomain

__all__ = ["MAX_VIEW_RADIUS", "check_behaviour", "check_settings", "observation_space"]

MAX_VIEW_RADIUS = 32
"""The largest ``view_radius`` accepted (the window has ``(2r+1)**2`` cells)."""


def check_settings(
    max_steps: int | None, view_radius: int, render_mode: str | None, modes: list[str]
) -> None:
    """A :class:`ProblemError` naming the keyword when ``max_steps``, ``view_radius`` or
    ``render_mode`` (one of ``modes`` or ``None``) is out of range (the single and the vector
    environment check alike)."""
    if max_steps is not None and max_steps < 1:
        raise ProblemError(f"max_steps must be at least 1, got {max_steps}")
    if not 0 <= view_radius <= MAX_VIEW_RADIUS:
        raise ProblemError(f"view_radius must be from 0 to {MAX_VIEW_RADIUS}, got {view_radius}")
    if render_mode is not None and render_mode not in modes:
        raise ProblemError(
            f"render_mode must be one of {', '.join(modes)} or None, got {render_mode!r}"
        )


def check_behaviour(domain: SomeDomain, hidden: bool, behaviour: str | None) -> str | None:
    """``behaviour``, checked: a fault-behaviour model of ``domain``, given only with hidden
    faults (the default model is ``None``)."""
    if behaviour is not None:
        if not hidden:
            raise ProblemError(
                "behaviour applies to hidden faults only: give faults=FaultSpec(detection="
                "('hidden',))"
            )
        domain.behaviour(behaviour)
    return behaviour


def observation_space(
    domain: SomeDomain,
    sources: tuple[MazeSource, ...],
    view_radius: int,
    hidden: bool = False,
) -> spaces.Dict:
    """One robot's observation space (see the module docstring): the window of ``view_radius``,
    the heading, the goal offset bounded by the longest maze side of ``sources``, and the known
    faults when ``domain`` has any and they are not ``hidden``."""
    side = 2 * view_radius + 1
    reach = max(source.largest_side for source in sources) - 1
    observation: dict[str, spaces.Space[Any]] = {
        "window": spaces.MultiBinary((side, side)),
        "heading": spaces.Discrete(4),
        "goal": spaces.Box(-reach, reach, shape=(2,), dtype=np.int32),
    }
    if domain.faults and not hidden:
        observation["faults"] = spaces.MultiBinary(len(domain.faults))
    return spaces.Dict(observation)
