"""What an episode of the Gymnasium environment is about: a maze, a route and a fault schedule.

Everything here is drawn from an explicit :class:`numpy.random.Generator` (the environment passes
its ``np_random``), so an episode is a pure function of the seed given to ``reset``. Nothing here
imports Gymnasium: the draws can be tested and reused without it.

Mazes (:func:`maze_sources`) come from

* the bundled set (``"bundled"``: all four, or one bundled name), each with its four routes;
* a maze file (a path to a ``.maze`` text file or a MovingAI ``.map``), with random routes;
* the seeded generator (:class:`MazeGenerator`), a fresh maze every episode, with random routes;
* a :class:`~selfrepair.world.maze.Maze` value, with random routes.

A random route (:func:`random_route`) starts on a random free cell with a random heading and ends
on a reachable cell at least half the largest 4-connected distance away, so routes are long.

Faults (:class:`FaultSpec`, :func:`draw_schedule`): one fault set is drawn per episode, then one
persistence, one detection mode and, per fault, when it starts; the result is a
:class:`~selfrepair.execution.faults.FaultSchedule`, which the simulator holds as the truth.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

import numpy as np

from selfrepair.errors import InputError, ProblemError, choice
from selfrepair.execution.faults import (
    Detection,
    FaultEvent,
    FaultSchedule,
    Persistence,
    canonical_order,
)
from selfrepair.geometry import Cell, Heading, Pose, parse_cell, parse_pose
from selfrepair.robots.domain import SomeDomain
from selfrepair.search.lattice import bfs_distances
from selfrepair.world.bundled import bundled_routes, maze_names, resolve_maze
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.routes import Route

__all__ = [
    "BUNDLED",
    "MAX_GENERATED_SIDE",
    "FaultSpec",
    "MazeGenerator",
    "MazeSource",
    "RouteChoice",
    "Scenario",
    "draw_scenario",
    "draw_schedule",
    "maze_sources",
    "random_route",
    "with_options",
]

BUNDLED = "bundled"
"""The maze specification that stands for every bundled maze."""

MAX_GENERATED_SIDE = 1024
"""The largest generated maze side (as for experiment configs); a larger one is refused."""

RESET_OPTIONS = ("faults", "goal", "maze", "start")
"""The keys of ``reset(options=...)`` that fix part of an episode (:func:`with_options`)."""

SEED_BOUND = 2**31
"""Per-episode seeds (maze generator, intermittent faults) are drawn from ``[0, SEED_BOUND)``."""


class RouteChoice(StrEnum):
    """Where an episode's route comes from: a bundled maze's own routes (random routes on mazes
    without any), or always random ones (:func:`random_route`)."""

    BUNDLED = "bundled"
    RANDOM = "random"


@dataclass(frozen=True, slots=True)
class MazeGenerator:
    """A fresh maze every episode from :func:`selfrepair.world.mazegen.generate_maze`, seeded from
    the episode's generator (the options as there)."""

    width: int = 25
    height: int = 25
    corridor: int = 1
    braid: float = 0.0

    def __post_init__(self) -> None:
        for what, side in (("width", self.width), ("height", self.height)):
            if not 5 <= side <= MAX_GENERATED_SIDE:
                raise ProblemError(
                    f"a generated maze's {what} must be from 5 to {MAX_GENERATED_SIDE}, got {side}"
                )
        generate_maze(self.width, self.height, corridor=self.corridor, braid=self.braid, seed=0)

    def draw(self, rng: np.random.Generator) -> Maze:
        """A maze seeded from ``rng`` (one integer is drawn)."""
        seed = int(rng.integers(SEED_BOUND))
        return generate_maze(
            self.width,
            self.height,
            corridor=self.corridor,
            braid=self.braid,
            seed=seed,
            name=f"gen{self.width}x{self.height}-c{self.corridor}-s{seed}",
        )


@dataclass(frozen=True, slots=True)
class MazeSource:
    """One entry of the environment's maze set: a fixed maze (with its bundled routes, if any) or
    a generator."""

    label: str
    maze: Maze | None = None
    routes: tuple[Route, ...] = ()
    generator: MazeGenerator | None = None

    @property
    def largest_side(self) -> int:
        """The longest side any maze of this source can have."""
        if self.maze is not None:
            return max(self.maze.width, self.maze.height)
        assert self.generator is not None
        return max(self.generator.width, self.generator.height)


MazeSpec = str | Maze | MazeGenerator
"""What names a maze source: ``"bundled"``, a bundled name, a maze file path, a maze value or a
generator."""


def maze_sources(spec: MazeSpec | Sequence[MazeSpec]) -> tuple[MazeSource, ...]:
    """The maze sources ``spec`` names (one spec or a sequence of them); files are read now."""
    specs: Sequence[MazeSpec] = (
        (spec,) if isinstance(spec, str | Maze | MazeGenerator) else tuple(spec)
    )
    if not specs:
        raise InputError("expected at least one maze", source="<mazes>")
    sources: list[MazeSource] = []
    for one in specs:
        if isinstance(one, MazeGenerator):
            sources.append(MazeSource(f"generated {one.width}x{one.height}", generator=one))
        elif isinstance(one, Maze):
            sources.append(MazeSource(one.name or "maze", maze=one))
        elif one == BUNDLED:
            sources.extend(_bundled(name) for name in maze_names())
        elif one in maze_names():
            sources.append(_bundled(one))
        else:
            maze = resolve_maze(one)
            sources.append(MazeSource(maze.name or one, maze=maze))
    return tuple(sources)


def _bundled(name: str) -> MazeSource:
    return MazeSource(name, resolve_maze(name), bundled_routes(name))


def random_route(maze: Maze, rng: np.random.Generator, name: str = "random") -> Route:
    """A random start pose and a goal at least half the largest 4-connected distance away from it
    (see the module docstring); needs a maze with two connected free cells."""
    free = maze.free_cells()
    if len(free) < 2:
        raise InputError("expected a maze with at least two free cells", source=maze.name)
    start = free[int(rng.integers(len(free)))]
    heading = Heading(int(rng.integers(4)))
    distances = bfs_distances(maze, start)
    far = int(distances.max())
    if far < 1:
        raise InputError(
            f"expected free cells connected to {start[0]},{start[1]}", source=maze.name
        )
    ys, xs = np.nonzero(distances * 2 >= far)
    cells = ((int(x), int(y)) for x, y in zip(xs, ys, strict=True))
    goals = sorted(cell for cell in cells if cell != start)
    goal = goals[int(rng.integers(len(goals)))]
    return Route(name, Pose(start[0], start[1], heading), goal)


@dataclass(frozen=True, slots=True)
class FaultSpec:
    """How an episode's faults are drawn (see the module docstring).

    ``sets`` are fault sets in the domain's text (``"FL:F,RL:F"``; ``""`` is no fault); ``None``
    means every set of ``domain.fault_sets`` (singles, then doubles). One of ``persistence`` and
    one of ``detection`` is drawn per episode. A fault starts at a step drawn from ``at``
    (inclusive range); a transient one lasts a number of steps drawn from ``duration``; an
    intermittent one is active at each step with a probability drawn from ``probability``.
    """

    sets: tuple[str, ...] | None = None
    persistence: tuple[Persistence, ...] = (Persistence.PERMANENT,)
    detection: tuple[Detection, ...] = (Detection.NOW,)
    at: tuple[int, int] = (0, 0)
    duration: tuple[int, int] = (5, 50)
    probability: tuple[float, float] = (0.2, 0.8)

    def __post_init__(self) -> None:
        persistence = tuple(choice(Persistence, p, "persistence") for p in self.persistence)
        object.__setattr__(self, "persistence", persistence)
        object.__setattr__(
            self, "detection", tuple(choice(Detection, d, "detection") for d in self.detection)
        )
        if self.sets is not None:
            object.__setattr__(self, "sets", tuple(self.sets))
        if self.sets == () or not self.persistence or not self.detection:
            raise ProblemError("expected at least one fault set, persistence and detection")
        if Detection.HIDDEN in self.detection and len(self.detection) > 1:
            raise ProblemError(
                "detection 'hidden' cannot be drawn with other modes: the agent's observation "
                "(no fault flags) must be the same in every episode"
            )
        _check_range(self.at, "at", 0)
        _check_range(self.duration, "duration", 1)
        low, high = self.probability
        if not 0.0 <= low <= high <= 1.0:
            raise ProblemError(f"expected 0 <= probability range <= 1, got {self.probability}")

    @property
    def hidden(self) -> bool:
        """Whether the faults are hidden from the robot (detection ``hidden``): the Gymnasium
        environments' partially observable variant."""
        return self.detection == (Detection.HIDDEN,)

    def fault_sets(self, domain: SomeDomain) -> tuple[frozenset[object], ...]:
        """The fault sets to draw from, parsed for ``domain``."""
        if self.sets is None:
            return domain.fault_sets
        return tuple(domain.parse_faults(text) for text in self.sets)


def _check_range(bounds: tuple[int, int], what: str, least: int) -> None:
    low, high = bounds
    if not least <= low <= high:
        raise ProblemError(f"expected a range {least} <= low <= high for {what}, got {bounds}")


def draw_schedule(
    domain: SomeDomain,
    spec: FaultSpec,
    rng: np.random.Generator,
    sets: Sequence[frozenset[object]] | None = None,
) -> FaultSchedule:
    """One episode's fault schedule (``sets``: ``spec.fault_sets(domain)`` parsed beforehand)."""
    choices = spec.fault_sets(domain) if sets is None else sets
    faults = choices[int(rng.integers(len(choices)))]
    persistence = spec.persistence[int(rng.integers(len(spec.persistence)))]
    detection = spec.detection[int(rng.integers(len(spec.detection)))]
    events = []
    for fault in canonical_order(faults):
        at = int(rng.integers(spec.at[0], spec.at[1] + 1))
        duration = probability = None
        if persistence is Persistence.TRANSIENT:
            duration = int(rng.integers(spec.duration[0], spec.duration[1] + 1))
        elif persistence is Persistence.INTERMITTENT:
            probability = float(rng.uniform(*spec.probability))
        events.append(FaultEvent(fault, at, persistence=persistence, duration=duration,
                                 probability=probability))  # fmt: skip
    return FaultSchedule(tuple(events), detection)


@dataclass(frozen=True, slots=True)
class Scenario:
    """One episode's situation: the maze, the route, the true fault schedule and the seed of its
    intermittent faults (the simulator's seed)."""

    maze: Maze
    maze_label: str
    route: Route
    schedule: FaultSchedule
    fault_seed: int

    @property
    def start(self) -> Pose:
        """Where the robot starts."""
        return self.route.start

    @property
    def goal(self) -> Cell:
        """The cell to reach."""
        return self.route.goal


def draw_scenario(
    sources: Sequence[MazeSource],
    routes: RouteChoice,
    domain: SomeDomain,
    faults: FaultSpec,
    rng: np.random.Generator,
    fault_sets: Sequence[frozenset[object]] | None = None,
) -> Scenario:
    """Draw a maze source, a route (``routes``: see :class:`RouteChoice`), a fault schedule
    and a fault seed from ``rng``, in that order."""
    source = sources[int(rng.integers(len(sources)))]
    if source.maze is not None:
        maze, label = source.maze, source.label
    else:
        assert source.generator is not None
        maze = source.generator.draw(rng)
        label = maze.name
    if routes is RouteChoice.BUNDLED and source.routes:
        route = source.routes[int(rng.integers(len(source.routes)))]
    else:
        route = random_route(maze, rng)
    schedule = draw_schedule(domain, faults, rng, fault_sets)
    return Scenario(maze, label, route, schedule, int(rng.integers(SEED_BOUND)))


def with_options(
    scenario: Scenario,
    options: dict[str, Any],
    domain: SomeDomain,
    rng: np.random.Generator,
    hidden: bool = False,
) -> Scenario:
    """``scenario`` with the parts ``options`` fixes (``reset(options=...)`` of the Gymnasium
    environments): ``maze`` (a bundled name, file or ``Maze``; a route is then drawn on it from
    ``rng`` unless given), ``start`` (a pose ``"x,y,H"`` or a ``Pose``), ``goal`` (a cell
    ``"x,y"``) and ``faults`` (a fault-set text, permanent from the first step and detected at
    once, or hidden when ``hidden``; or a ``FaultSchedule``, hidden exactly when ``hidden``)."""
    unknown = sorted(set(options) - set(RESET_OPTIONS))
    if unknown:
        raise ProblemError(
            f"unknown reset option(s) {', '.join(unknown)}; expected {', '.join(RESET_OPTIONS)}"
        )
    maze, label, route = scenario.maze, scenario.maze_label, scenario.route
    if "maze" in options:
        given = options["maze"]
        maze = given if isinstance(given, Maze) else resolve_maze(str(given))
        label = maze.name or str(given)
        route = random_route(maze, rng)
    start = _pose(options.get("start", route.start))
    goal = _cell(options.get("goal", route.goal))
    for what, cell in (("start", start.cell), ("goal", goal)):
        if not maze.is_free(*cell):
            raise ProblemError(f"reset option {what}: {cell} is not a free cell of the maze")
    schedule = scenario.schedule
    if "faults" in options:
        given = options["faults"]
        detection = Detection.HIDDEN if hidden else Detection.NOW
        schedule = given if isinstance(given, FaultSchedule) else FaultSchedule.permanent(
            domain.parse_faults(str(given)), detection=detection
        )  # fmt: skip
        if (schedule.detection is Detection.HIDDEN) != hidden:
            raise ProblemError(
                "reset option faults: this environment "
                + ("hides faults; expected detection 'hidden'" if hidden else "tells the robot "
                   "its faults; expected detection 'now' or 'on-use'")
            )  # fmt: skip
    route = type(route)(route.name, start, goal)
    return Scenario(maze, label, route, schedule, scenario.fault_seed)


def _pose(value: Pose | str) -> Pose:
    return value if isinstance(value, Pose) else parse_pose(str(value), source="reset option start")


def _cell(value: Cell | str) -> Cell:
    if isinstance(value, tuple):
        return (int(value[0]), int(value[1]))
    return parse_cell(str(value), source="reset option goal")
