"""Checks that a team scenario can run, before anything runs.

:func:`check_scenario` refuses, with one :class:`~selfrepair.errors.InputError` naming the file
and (given the file's text) the line, everything that cannot run: a robot or task on a wall or off
the maze, two robots on one cell or of one name, more robots than free cells, a task no robot with
a gripper can reach (or whose drop-off cannot be reached from its pickup), an unknown robot in a
fault, a blocked cell or a world event's cell off the maze, more robots or tasks than the
:class:`Limits`.
"""

from __future__ import annotations

from collections.abc import Callable

from selfrepair.errors import InputError
from selfrepair.geometry import Cell
from selfrepair.limits import check_limit
from selfrepair.team.grid import components
from selfrepair.team.model import TeamScenario
from selfrepair.team.randomteam import Limits
from selfrepair.tomlfile import find_line
from selfrepair.world.maze import Maze

__all__ = ["check_scenario"]

Fail = Callable[..., InputError]
"""``fail(what, *loc)``: the error to raise, at the line of the key path ``loc``."""


def check_scenario(scenario: TeamScenario, *, text: str = "", limits: Limits | None = None) -> None:
    """Raise :class:`InputError` naming the file (and line, given the ``text``) for the first
    thing in ``scenario`` that cannot run (see the module docstring)."""
    maze, source = scenario.maze, scenario.source

    def fail(what: str, *loc: str | int) -> InputError:
        return InputError(what, source=source, line=find_line(text, loc) if text else None)

    free = len(maze.free_cells())
    if len(scenario.robots) > free:
        raise fail(
            f"{len(scenario.robots)} robots do not fit: maze {maze.name or 'of the scenario'} "
            f"has {free} free cells",
            "robots",
        )
    if not scenario.robots:
        raise fail("expected at least one robot", "robots")
    if limits is not None:
        line = find_line(text, ("robots",)) if text else None
        check_limit(
            len(scenario.robots), limits.max_robots, name="max_robots", what="robots",
            source=source, line=line,
        )  # fmt: skip
        line = find_line(text, ("tasks",)) if text else None
        check_limit(
            len(scenario.tasks), limits.max_tasks, name="max_tasks", what="tasks",
            source=source, line=line,
        )  # fmt: skip
    _check_robots(scenario, maze, fail)
    _check_tasks(scenario, maze, fail)
    _check_faults(scenario, maze, fail)
    for event in scenario.world.events:
        x, y = event.cell
        if not maze.in_bounds(x, y):
            raise fail(
                f"the world event at tick {event.at} on cell {x},{y}: the cell is off the maze",
                "world",
                "events",
            )


def _check_robots(scenario: TeamScenario, maze: Maze, fail: Fail) -> None:
    seen: dict[Cell, str] = {}
    names: set[str] = set()
    for n, robot in enumerate(scenario.robots):
        if robot.name in names:
            raise fail(f"two robots are called {robot.name}", "robots", n, "name")
        names.add(robot.name)
        x, y = robot.start.cell
        if not maze.is_free(x, y):
            what = "a wall" if maze.in_bounds(x, y) else "off the maze"
            raise fail(
                f"robot {robot.name} starts at {x},{y}, which is {what}", "robots", n, "start"
            )
        if robot.start.cell in seen:
            raise fail(
                f"robots {seen[robot.start.cell]} and {robot.name} both start at {x},{y}",
                "robots",
                n,
                "start",
            )
        seen[robot.start.cell] = robot.name


def _check_tasks(scenario: TeamScenario, maze: Maze, fail: Fail) -> None:
    items: set[str] = set()
    pickups: dict[Cell, str] = {}
    comp = components(maze)
    reach = {comp[r.start.cell] for r in scenario.robots if r.gripper}
    for n, task in enumerate(scenario.tasks):
        if task.item in items:
            raise fail(f"two tasks deliver item {task.item}", "tasks", n, "item")
        items.add(task.item)
        for what, (x, y) in (("pickup", task.pickup), ("dropoff", task.dropoff)):
            if not maze.is_free(x, y):
                where = "a wall" if maze.in_bounds(x, y) else "off the maze"
                raise fail(f"task {task.item}: {what} {x},{y} is {where}", "tasks", n, what)
        if task.pickup == task.dropoff:
            raise fail(
                f"task {task.item}: pickup and dropoff are the same cell", "tasks", n, "dropoff"
            )
        if task.pickup in pickups:
            raise fail(
                f"items {pickups[task.pickup]} and {task.item} lie on the same cell",
                "tasks",
                n,
                "pickup",
            )
        pickups[task.pickup] = task.item
        x, y = task.pickup
        if comp[task.pickup] not in reach:
            raise fail(
                f"item {task.item} at {x},{y}: no robot with a gripper can reach it",
                "tasks",
                n,
                "pickup",
            )
        if comp[task.dropoff] != comp[task.pickup]:
            bx, by = task.dropoff
            raise fail(
                f"item {task.item} cannot be brought from {x},{y} to {bx},{by}: no path",
                "tasks",
                n,
                "dropoff",
            )


def _check_faults(scenario: TeamScenario, maze: Maze, fail: Fail) -> None:
    names = {r.name for r in scenario.robots}
    for n, fault in enumerate(scenario.faults):
        if fault.robot and fault.robot not in names:
            raise fail(
                f"a {fault.kind} fault names unknown robot {fault.robot!r}", "faults", n, "robot"
            )
        for x, y in fault.cells:
            if not maze.in_bounds(x, y):
                raise fail(f"blocked cell {x},{y} is off the maze", "faults", n, "cells")
