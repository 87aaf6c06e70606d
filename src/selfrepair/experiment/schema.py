"""The schema of an experiment file: frozen pydantic models of every section.

The file format is described in ``docs/experiments.md`` and in :mod:`selfrepair.experiment.config`,
which reads a file into an :class:`ExperimentConfig`. Validators that need the robot (fault
texts, profiles, LPG-adapt's availability) get it from the validation context (key ``domain``),
set by :func:`selfrepair.experiment.config.parse_config` after the plug-ins are loaded. The
``[planner]`` section and the strategy entries are in :mod:`.schema_strategies`, the
``[physics]`` section in :mod:`.schema_physics`; this module re-exports them.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Literal, TypeVar

from pydantic import Field, ValidationInfo, field_validator, model_validator

from selfrepair.diagnosis.cooperative import ObserverView
from selfrepair.errors import InputError
from selfrepair.execution.faults import Clock, Detection, Persistence
from selfrepair.experiment.schema_physics import PhysicsConfig
from selfrepair.experiment.schema_physics import context_domain as _domain
from selfrepair.experiment.schema_strategies import (
    STRATEGY_TAGS,
    DiagnosisStrategy,
    DStarLiteStrategy,
    LookaheadStrategy,
    LpgAdaptStrategy,
    PlannerConfig,
    ReplacementStrategy,
    ReplanStrategy,
    StrategyConfig,
)
from selfrepair.geometry import parse_cell, parse_pose
from selfrepair.limits import DEFAULT_OBSERVER_RANGE, DEFAULT_SENSING_RANGE, MAX_OBSERVERS
from selfrepair.robots.fromfile import DEFAULT_DOMAIN
from selfrepair.textio import source_dir
from selfrepair.tomlfile import Float, Frozen, Int, NonEmpty
from selfrepair.world.events import Sensing
from selfrepair.world.routes import MAX_ROUTES

__all__ = [
    "FAULT_PROFILES",
    "STRATEGY_TAGS",
    "DStarLiteStrategy",
    "DiagnosisStrategy",
    "ExperimentConfig",
    "FaultsConfig",
    "GeneratedMaze",
    "LookaheadStrategy",
    "LpgAdaptStrategy",
    "MazeConfig",
    "MazeSource",
    "PhysicsConfig",
    "PlannerConfig",
    "ReplacementStrategy",
    "ReplanStrategy",
    "RouteConfig",
    "StrategyConfig",
    "WorldConfig",
]

FAULT_PROFILES = ("paper", "singles", "doubles", "all")
"""Named fault-set profiles; see :func:`selfrepair.experiment.faultsets.fault_profile`."""

PAPER_ONLY = frozenset({"paper"})
"""Profiles defined for the four-wheel robot only."""


class GeneratedMaze(Frozen):
    """Options of :func:`selfrepair.world.mazegen.generate_maze`."""

    width: Annotated[Int, Field(ge=5, le=1024)]
    height: Annotated[Int, Field(ge=5, le=1024)]
    corridor: Annotated[Int, Field(ge=1, le=64)] = 1
    braid: Annotated[Float, Field(ge=0.0, le=1.0)] = 0.0
    seed: Int = 0


class RouteConfig(Frozen):
    """One explicit route: a start pose ``"X,Y,H"`` and a goal cell ``"X,Y"``."""

    start: str
    goal: str
    name: str | None = None

    @field_validator("start")
    @classmethod
    def _pose(cls, value: str) -> str:
        return str(_reraise(parse_pose, value))

    @field_validator("goal")
    @classmethod
    def _cell(cls, value: str) -> str:
        x, y = _reraise(parse_cell, value)
        return f"{x},{y}"


class MazeSource(Frozen):
    """Where a maze comes from: exactly one of ``bundled`` (a bundled maze's name), ``file`` (a
    maze or map file, relative to the experiment file) or ``generate`` (a seeded maze). Single-robot
    and team experiment files both describe their mazes so."""

    bundled: str | None = None
    file: str | None = None
    generate: GeneratedMaze | None = None

    @model_validator(mode="after")
    def _one_source(self) -> MazeSource:
        given = [k for k in ("bundled", "file", "generate") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "expected exactly one of 'bundled', 'file' or 'generate', got "
                + (", ".join(repr(k) for k in given) or "none")
            )
        return self


class MazeConfig(MazeSource):
    """A maze (see :class:`MazeSource`) and its routes.

    ``routes`` is ``"bundled"`` (the bundled maze's route file), a number of random routes (drawn
    from the experiment seed), or a list of explicit routes.
    """

    routes: (
        Literal["bundled"]
        | Annotated[Int, Field(ge=1, le=MAX_ROUTES)]
        | Annotated[tuple[RouteConfig, ...], Field(min_length=1)]
    ) = "bundled"

    @model_validator(mode="after")
    def _bundled_routes(self) -> MazeConfig:
        if self.routes == "bundled" and self.bundled is None:
            raise ValueError(
                'routes = "bundled" needs a bundled maze; give a number of random routes or a '
                "list of {start, goal} tables"
            )
        return self


class FaultsConfig(Frozen):
    """Which fault sets, when they appear (``at``, in steps or ticks per ``clock``), how long they
    last (``persistence`` with ``duration`` or ``probability``) and how they are detected."""

    sets: Literal["paper", "singles", "doubles", "all"] | tuple[str, ...] = "paper"
    at: Annotated[tuple[Annotated[Int, Field(ge=0)], ...], NonEmpty] = (0,)
    clock: Clock = Clock.STEP
    detection: Annotated[tuple[Detection, ...], NonEmpty] = (Detection.NOW,)
    persistence: Persistence = Persistence.PERMANENT
    duration: Annotated[Int, Field(ge=1)] | None = None
    probability: Annotated[Float, Field(ge=0.0, le=1.0)] | None = None
    at_random: bool = False
    """When true, each situation's faults appear at one step drawn (seeded by the situation)
    uniformly from the steps of the route's fault-free optimal plan, instead of at each ``at``."""
    behaviour: str | None = None
    """Detection ``hidden``: the robot's fault-behaviour model (its default when absent)."""
    noise: Annotated[tuple[Annotated[Float, Field(ge=0.0, lt=0.5)], ...], NonEmpty] = (0.0,)
    """Detection ``hidden``: the odometry error rates, one axis of the sweep."""
    bump_switch: bool = True
    """Detection ``hidden``: whether the robot senses a motion stopped at a wall."""
    observers: Annotated[tuple[Annotated[Int, Field(ge=0, le=MAX_OBSERVERS)], ...], NonEmpty] = (0,)
    """Detection ``hidden``: how many teammates watch the robot move (0: it is alone; 2: a team
    of 3), one axis of the sweep (:mod:`selfrepair.diagnosis.cooperative`)."""
    observer_range: Annotated[Int, Field(ge=0, le=64)] = DEFAULT_OBSERVER_RANGE
    """The observers' sensing range in cells (Chebyshev)."""
    observer_noise: Annotated[Float, Field(ge=0.0, lt=0.5)] | None = None
    """The observers' odometry error rate (absent: the mission's own ``noise`` rate)."""
    observer_view: ObserverView = ObserverView.POSE
    """What the observers see of each motion in range: ``pose`` (the robot's pose after the
    command) or ``wheels`` (the pose and the robot's actuators; a robot that declares
    actuators). See :class:`~selfrepair.diagnosis.cooperative.ObserverView`."""

    @field_validator("observer_view")
    @classmethod
    def _observer_view(cls, value: ObserverView, info: ValidationInfo) -> ObserverView:
        domain = _domain(info)
        if value is ObserverView.WHEELS and domain.actuators is None:
            raise ValueError(
                f"observer_view = \"wheels\" needs a robot that declares actuators; "
                f"{domain.name} does not (expected \"pose\")"
            )
        return value

    @field_validator("behaviour")
    @classmethod
    def _behaviour(cls, value: str | None, info: ValidationInfo) -> str | None:
        if value is None:
            return value
        domain = _domain(info)
        if value not in domain.behaviour_names():
            names = ", ".join(domain.behaviour_names()) or "none: the robot has no such model"
            raise ValueError(
                f"expected a fault behaviour of {domain.name} ({names}), got {value!r}"
            )
        return value

    @model_validator(mode="after")
    def _hidden_options(self) -> FaultsConfig:
        hidden = Detection.HIDDEN in self.detection
        watched = self.observers != (0,) or self.observer_noise is not None
        if not hidden and (self.behaviour is not None or self.noise != (0.0,) or watched):
            raise ValueError(
                'behaviour, noise and observers need detection = ["hidden"] (or a list with it)'
            )
        if self.observer_view is not ObserverView.POSE and not any(self.observers):
            raise ValueError(
                "observer_view needs observers: expected observers with a number above 0, "
                f"got {list(self.observers)}"
            )
        if len(set(self.observers)) != len(self.observers):
            raise ValueError(f"expected distinct numbers of observers, got {list(self.observers)}")
        return self

    @model_validator(mode="after")
    def _random_step(self) -> FaultsConfig:
        if self.at_random and (self.clock is not Clock.STEP or self.at != (0,)):
            raise ValueError("at_random = true draws a step: leave 'at' and 'clock' unset")
        return self

    @model_validator(mode="after")
    def _persistence_options(self) -> FaultsConfig:
        if self.persistence is Persistence.TRANSIENT and self.duration is None:
            raise ValueError("persistence = \"transient\" needs a 'duration' (>= 1)")
        if self.persistence is Persistence.INTERMITTENT and self.probability is None:
            raise ValueError("persistence = \"intermittent\" needs a 'probability' in [0, 1]")
        return self

    @field_validator("sets")
    @classmethod
    def _sets(cls, value: str | tuple[str, ...], info: ValidationInfo) -> str | tuple[str, ...]:
        domain = _domain(info)
        if isinstance(value, str):
            if value in PAPER_ONLY and domain.name != "four-wheel":
                raise ValueError(
                    f'the "{value}" profile is defined for the four-wheel robot; for '
                    f"{domain.name!r} use singles, doubles, all or a list of fault sets"
                )
            return value
        if not value:
            raise ValueError("expected at least one fault set")
        return tuple(domain.format_faults(_reraise(domain.parse_faults, text)) for text in value)


class WorldConfig(Frozen):
    """A changing world (:mod:`selfrepair.world.events`): per situation, obstacles drawn by
    :func:`~selfrepair.world.events.random_world` near the route's fault-free optimal plan, at
    each of ``rates`` (obstacles per 100 ticks), each staying ``duration`` ticks (absent: for
    good), on cells within ``distance`` (Chebyshev) of the plan, over ``horizon`` times the
    plan's duration; sensed per each of ``sensing`` with range ``range``; a robot waits at most
    ``max_wait`` steps in all for a way to open. A rate of 0 is the maze that never changes."""

    rates: Annotated[tuple[Annotated[Float, Field(ge=0.0, le=1000.0)], ...], NonEmpty]
    duration: Annotated[Int, Field(ge=1)] | None = 30
    distance: Annotated[Int, Field(ge=0, le=64)] = 1
    horizon: Annotated[Int, Field(ge=1, le=100)] = 4
    sensing: Annotated[tuple[Sensing, ...], NonEmpty] = (Sensing.RANGE,)
    range: Annotated[Int, Field(ge=0, le=64)] = DEFAULT_SENSING_RANGE
    max_wait: Annotated[Int, Field(ge=0, le=100_000)] = 200
    """Steps a robot may wait in place, in all, while no plan exists round what it believes
    blocked (``StrategyOptions.max_wait``; obstacles that stay ``duration`` ticks need more than
    the default of a maze that never changes)."""


class ExperimentConfig(Frozen):
    """A whole experiment: the cross product of mazes x routes x fault settings x strategies x
    clearance weights x repeats, for the robot ``domain`` (a name in the domain registry).
    ``source`` is the file it was read from (for error messages and for resolving relative
    paths). ``crossover``: the experiment command also estimates the maze size where
    replacement's repair compute per mission falls below 1/10 of the replanner's
    (:mod:`selfrepair.experiment.scale`); it does not change any mission. ``timing_repeats``:
    warm timing runs per mission (the command line's ``--repeats`` overrides it)."""

    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")]
    description: str = ""
    domain: str = DEFAULT_DOMAIN
    plugins: tuple[str, ...] = ()
    seed: Int = 0
    repeats: Annotated[Int, Field(ge=1, le=1000)] = 1
    crossover: bool = False
    timing_repeats: Annotated[Int, Field(ge=1, le=1000)] = 1
    mazes: Annotated[tuple[MazeConfig, ...], Field(min_length=1)]
    faults: FaultsConfig = FaultsConfig()
    world: WorldConfig | None = None
    physics: PhysicsConfig | None = None
    planner: PlannerConfig = PlannerConfig()
    strategies: Annotated[tuple[StrategyConfig, ...], Field(min_length=1)]
    source: str = "<string>"

    @property
    def base_dir(self) -> Path:
        """The directory relative paths in the file are resolved against."""
        return source_dir(self.source)


T = TypeVar("T")


def _reraise(parser: Callable[[str], T], text: str) -> T:
    """Run a robot-model parser, turning its InputError into a plain ValueError for pydantic."""
    try:
        return parser(text)
    except InputError as exc:
        raise ValueError(exc.reason) from None
