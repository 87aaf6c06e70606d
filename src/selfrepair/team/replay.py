"""Re-simulating a team trace from its header alone, trusting none of its other lines.

:func:`replay_team` reports the first thing that does not hold:

- the header against the scenario file it names (``scenario_file``: its SHA-256, then the maze,
  robots, tasks and faults the file gives), when the file is found, and the maze rows against
  their digest;
- the faults: each fault line at the unit the header implies (a tick, or ``at`` ticks after the
  robot's first pick), its clearing line when a transient fault ends within the mission;
- the moves: a robot that *teleports* (a move that does not start where its previous move ended,
  or overlaps it in time), a move the robot model does not produce (wrong end pose or
  duration), a move through a wall or through a cell blocked at its start (a blocked team
  fault, or a world event of the header's ``world``: no executed motion sweeps a cell blocked
  at that time but the robot's own), a bump that sweeps no blocked cell, a move its true
  faults forbid;
- the acts: a pick, drop or handover that does not last its ticks or whose conditions do not hold
  (gripper, load, place, adjacency; a delivered item stays delivered, so picking it again is
  refused);
- a *conflict*: two robots holding the same cell at the same time (a moving robot holds its
  action's footprint, a resting one its cell);
- the summary: items delivered, makespan, moves, acts, incidents, repairs and own repairs as the
  lines give them.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

from selfrepair.errors import InputError
from selfrepair.execution.faults import FaultEvent, Persistence
from selfrepair.execution.result import StepSource
from selfrepair.geometry import Cell, Pose
from selfrepair.team.model import (
    DROP_TICKS,
    HANDOVER_TICKS,
    PICK_TICKS,
    ActionKind,
    TeamFault,
    TeamFaultKind,
    TeamScenario,
    Trigger,
)
from selfrepair.team.scenario import load_scenario, resolve_scenario, scenario_names
from selfrepair.team.spacetime import units
from selfrepair.team.traceformat import TeamTrace, maze_digest
from selfrepair.world.maze import format_maze

__all__ = ["TeamReplayReport", "replay_team"]

ACT_TICKS = {
    ActionKind.PICK: PICK_TICKS,
    ActionKind.DROP: DROP_TICKS,
    ActionKind.HANDOVER: HANDOVER_TICKS,
}
"""How many ticks each act lasts."""


@dataclass(frozen=True, slots=True)
class TeamReplayReport:
    """What :func:`replay_team` found: ``ok``, the first problem (with its trace line), how
    much was checked and what became of the scenario file (``scenario_file``: checked, not
    found, or none named)."""

    ok: bool
    problem: str
    line: int | None
    moves: int
    acts: int
    delivered: int
    scenario_file: str = ""

    def __str__(self) -> str:
        if self.ok:
            checked = f"; {self.scenario_file}" if self.scenario_file else ""
            return (
                f"ok: {self.moves} moves and {self.acts} acts re-simulated, no conflict, no "
                f"teleport, {self.delivered} items delivered{checked}"
            )
        where = f"line {self.line}: " if self.line is not None else ""
        return f"{where}{self.problem}"


class _Problem(Exception):
    def __init__(self, what: str, line: int | None) -> None:
        super().__init__(what)
        self.what, self.line = what, line


def replay_team(trace: TeamTrace, *, check_file: bool = True) -> TeamReplayReport:
    """Re-simulate ``trace`` (see the module docstring); ``check_file``: also compare the header
    with the scenario file it names, when that file is found."""
    delivered: dict[str, int] = {}
    checked = ""
    try:
        _check_maze(trace)
        checked = _check_scenario_file(trace) if check_file else ""
        active = _active_faults(trace)
        _check_moves(trace, active)
        delivered = _check_acts(trace, active)
        _check_conflicts(trace)
        _check_summary(trace, delivered)
    except _Problem as problem:
        return TeamReplayReport(
            False, problem.what, problem.line, len(trace.moves), len(trace.acts),
            len(delivered), checked,
        )  # fmt: skip
    return TeamReplayReport(
        True, "", None, len(trace.moves), len(trace.acts), len(delivered), checked
    )


def _check_maze(trace: TeamTrace) -> None:
    """The header's maze rows against their digest (version 2 traces)."""
    maze = trace.header.get("maze")
    digest = maze.get("sha256") if isinstance(maze, dict) else None
    if digest is None:
        return
    rows = format_maze(trace.scenario.maze).splitlines()
    if digest != maze_digest(rows):
        raise _Problem("the maze rows do not match the maze's sha256 in the header", 1)


def _check_scenario_file(trace: TeamTrace) -> str:
    """Compare the header with the scenario file it names (bundled, or a file that exists);
    returns what was done, for the report."""
    named = trace.header.get("scenario_file")
    if not isinstance(named, dict) or not isinstance(named.get("path"), str):
        return ""
    path, digest = named["path"], named.get("sha256")
    if not digest:
        return f"not checked against {path} (the header gives no sha256: not the file's content)"
    bundled = path.removeprefix("<bundled:").removesuffix(">")
    try:
        if path.startswith("<bundled:") and bundled in scenario_names():
            scenario = resolve_scenario(bundled)
        elif not path.startswith("<") and Path(path).is_file():
            scenario = load_scenario(path)
        else:
            return "" if path.startswith("<") else f"scenario file {path} not found, not checked"
    except InputError as exc:
        raise _Problem(f"the scenario file {path} does not load: {exc}", 1) from None
    if scenario.digest != digest:
        raise _Problem(f"the scenario file {path} changed since the trace was written", 1)
    mismatch = _scenario_mismatch(scenario, trace.scenario)
    if mismatch:
        raise _Problem(f"the header's {mismatch} differ from the scenario file {path}", 1)
    return f"header matches scenario file {path}"


def _scenario_mismatch(file: TeamScenario, header: TeamScenario) -> str:
    """The first part of ``header`` that differs from ``file`` ("" when none)."""
    for what, mine, theirs in (
        ("robot domain", file.domain.name, header.domain.name),
        ("maze rows", format_maze(file.maze), format_maze(header.maze)),
        ("robots", file.robots, header.robots),
        ("tasks", file.tasks, header.tasks),
        ("faults", file.faults, header.faults),
        ("world events", file.world, header.world),
    ):
        if mine != theirs:
            return what
    return ""


def _active_faults(trace: TeamTrace) -> list[tuple[int, int | None, TeamFault]]:
    """Each fault's active stretch ``[on, off)`` (``off`` None: for good), computed from the
    header - a tick, or the end of the robot's first pick in the acts, plus ``at`` - and
    checked against the trace's fault lines."""
    scale = trace.scale
    first_pick: dict[str, int] = {}
    for act in sorted(trace.acts, key=lambda a: a.start):
        if act.action.kind is ActionKind.PICK:
            first_pick.setdefault(act.action.robot, act.end)
    horizon = _horizon(trace)
    spans: list[tuple[int, int | None, TeamFault]] = []
    for index, fault in enumerate(trace.scenario.faults):
        if fault.trigger is Trigger.TICK:
            on: int | None = fault.at * scale
        else:
            picked = first_pick.get(fault.robot)
            on = None if picked is None else picked + fault.at * scale
        if on is None:
            continue
        off = None if fault.duration is None else on + fault.duration * scale
        lines = [f for f in trace.faults if f.index == index]
        expected = [(on, True)] + ([] if off is None else [(off, False)])
        got = [(f.at, f.active) for f in lines]
        due = [e for e in expected if e[0] < horizon]  # what the mission lived to see
        if got != expected[: len(got)] or len(got) < len(due):
            line = lines[0].line if lines else None
            raise _Problem(
                f"fault {index} ({fault.describe()}) is logged as {got}, not {expected}", line
            )
        spans.append((on, off, fault))
    return spans


def _horizon(trace: TeamTrace) -> int:
    """The last unit the trace covers: its last move or act, or the summary's simulated ticks."""
    last = max([m.end for m in trace.moves] + [a.end for a in trace.acts] + [0])
    ticks = None if trace.summary is None else trace.summary.get("ticks_simulated")
    if isinstance(ticks, int | float) and not isinstance(ticks, bool):
        last = max(last, int(Fraction(ticks).limit_denominator(trace.scale) * trace.scale))
    return last


def _faults_at(spans: list[tuple[int, int | None, TeamFault]], t: int) -> list[TeamFault]:
    return [f for on, off, f in spans if on <= t and (off is None or t < off)]


def _check_moves(trace: TeamTrace, spans: list[tuple[int, int | None, TeamFault]]) -> None:
    scenario, domain, scale = trace.scenario, trace.scenario.domain, trace.scale
    maze = scenario.maze
    names = {r.name for r in scenario.robots}
    last: dict[str, tuple[Pose, int]] = {r.name: (r.start, 0) for r in scenario.robots}
    steps = dict.fromkeys(names, 0)  # each robot's commands so far (its intermittent draws)
    for m in sorted(trace.moves, key=lambda m: (m.start, m.line)):
        if m.robot not in names:
            raise _Problem(f"move of unknown robot {m.robot!r}", m.line)
        pose, free_at = last[m.robot]
        if m.before != pose:
            raise _Problem(
                f"teleport: {m.robot} moves from {m.before} but stands at {pose}", m.line
            )
        if m.start < free_at:
            raise _Problem(
                f"{m.robot} starts a move at {m.start} before its last one ends ({free_at})", m.line
            )
        faults, blocked = _truth(trace, spans, m.robot, m.start, steps[m.robot])
        steps[m.robot] += 1
        name = domain.format_action(m.action)
        if m.source is StepSource.FAILED_ATTEMPT or m.source is StepSource.BUMPED:
            what = "failed attempt" if m.source is StepSource.FAILED_ATTEMPT else "bump"
            if m.after != m.before or m.end - m.start != scale:
                raise _Problem(f"{m.robot}'s {what} moves or lasts not one tick", m.line)
            if m.source is StepSource.BUMPED:
                swept = domain.footprint(m.before, m.action)[1:]
                if not any(c in blocked for c in swept):
                    raise _Problem(
                        f"{m.robot}'s {name} is logged as a bump, but it sweeps no cell blocked "
                        f"at unit {m.start}",
                        m.line,
                    )
            elif domain.available(m.action, faults):
                raise _Problem(
                    f"{m.robot}'s {name} is logged as failed, but its true faults allow it", m.line
                )
            continue
        if domain.apply(m.before, m.action) != m.after:
            raise _Problem(f"{name} from {m.before} does not end at {m.after}", m.line)
        if m.end - m.start != units(domain, m.action, scale):
            raise _Problem(
                f"{name} takes {units(domain, m.action, scale)} units, not {m.end - m.start}",
                m.line,
            )
        cells = domain.footprint(m.before, m.action)
        if not maze.all_free(cells):
            raise _Problem(f"{m.robot}'s move sweeps a wall", m.line)
        if hit := [c for c in cells[1:] if c in blocked]:
            x, y = hit[0]
            raise _Problem(
                f"{m.robot}'s move sweeps cell {x},{y}, blocked at unit {m.start}", m.line
            )
        if not domain.available(m.action, faults):
            raise _Problem(f"{m.robot} moves with {name}, which its faults forbid", m.line)
        last[m.robot] = (m.after, m.end)


def _truth(
    trace: TeamTrace,
    spans: list[tuple[int, int | None, TeamFault]],
    robot: str,
    t: int,
    step: int,
) -> tuple[frozenset[object], set[Cell]]:
    """The true domain faults of ``robot`` at ``t`` (its command number ``step``: an
    intermittent fault is drawn as :class:`~selfrepair.team.state.RobotFaultClock` draws it,
    from the options' seed) and the blocked cells (by blocked team faults and by the world
    events due by then, :meth:`WorldSchedule.blocked_at
    <selfrepair.world.events.WorldSchedule.blocked_at>`, computed from the header alone)."""
    domain = trace.scenario.domain
    faults: set[object] = set()
    world = trace.scenario.world
    blocked: set[Cell] = set(world.blocked_at(Fraction(t, trace.scale))) if world else set()
    for f in _faults_at(spans, t):
        if f.kind is TeamFaultKind.BLOCKED:
            blocked.update(f.cells)
            continue
        if f.robot != robot or f.kind not in (TeamFaultKind.IMMOBILISED, TeamFaultKind.WHEELS):
            continue
        if f.persistence is Persistence.INTERMITTENT:
            index = next(i for i, g in enumerate(trace.scenario.faults) if g is f)
            draw = FaultEvent(None, persistence=Persistence.INTERMITTENT, probability=f.probability)
            if not draw.active(index, step, Fraction(0), trace.options.seed):
                continue
        if f.kind is TeamFaultKind.IMMOBILISED:
            faults.update(domain.faults)
        else:
            faults |= domain.parse_faults(f.wheel_faults)
    return frozenset(faults), blocked


def _check_acts(trace: TeamTrace, spans: list[tuple[int, int | None, TeamFault]]) -> dict[str, int]:
    """Duration and item logic of every act, in time order; returns the items delivered, with
    the unit their drop ended."""
    scenario = trace.scenario
    tasks = {t.item: t for t in scenario.tasks}
    floor: dict[str, Cell | None] = {t.item: t.pickup for t in scenario.tasks}
    holder: dict[str, str] = {}
    carrying: dict[str, str] = {}
    gripper = {r.name: r.gripper for r in scenario.robots}
    delivered: dict[str, int] = {}
    for a in sorted(trace.acts, key=lambda a: (a.start, a.line)):
        action = a.action
        if action.item not in tasks:
            raise _Problem(f"act on unknown item {action.item!r}", a.line)
        ticks = ACT_TICKS[action.kind]
        if a.end - a.start != ticks * trace.scale:
            raise _Problem(
                f"{action} lasts {a.end - a.start} units, not {ticks} ticks "
                f"({ticks * trace.scale} units)",
                a.line,
            )
        if action.item in delivered:
            raise _Problem(
                f"{action}: item {action.item} was delivered at unit {delivered[action.item]}",
                a.line,
            )
        for robot, cell in zip(action.robots, a.cells, strict=False):
            if _pose_at(trace, robot, a.start).cell != cell or _moving(
                trace, robot, a.start, a.end
            ):
                raise _Problem(f"{robot} is not resting on {cell} during {action}", a.line)
        broken = {f.robot for f in _faults_at(spans, a.start) if f.kind is TeamFaultKind.GRIPPER}
        grips = {r for r, g in gripper.items() if g and r not in broken}
        item = action.item
        if action.kind is ActionKind.PICK:
            if action.robot not in grips or action.robot in carrying or floor[item] != a.cells[0]:
                raise _Problem(f"{action} cannot happen (gripper, load or item place)", a.line)
            floor[item], holder[item], carrying[action.robot] = None, action.robot, item
        elif action.kind is ActionKind.DROP:
            if action.robot not in grips or holder.get(item) != action.robot:
                raise _Problem(f"{action} cannot happen (gripper or load)", a.line)
            del holder[item], carrying[action.robot]
            floor[item] = a.cells[0]
            if a.cells[0] == tasks[item].dropoff:
                delivered[item] = a.end
        else:
            (gx, gy), (tx, ty) = a.cells
            if abs(gx - tx) + abs(gy - ty) != 1 or holder.get(item) != action.robot:
                raise _Problem(
                    f"{action} cannot happen (not adjacent, or the giver lacks the item)", a.line
                )
            if action.taker not in grips or action.taker in carrying:
                raise _Problem(f"{action} cannot happen (the taker cannot take it)", a.line)
            del carrying[action.robot]
            holder[item], carrying[action.taker] = action.taker, item
    return delivered


def _pose_at(trace: TeamTrace, robot: str, t: int) -> Pose:
    pose = trace.scenario.robot(robot).start
    for m in trace.moves:  # in time order
        if m.robot == robot and m.end <= t:
            pose = m.after
    return pose


def _moving(trace: TeamTrace, robot: str, start: int, end: int) -> bool:
    return any(m.robot == robot and m.start < end and start < m.end for m in trace.moves)


def _check_conflicts(trace: TeamTrace) -> None:
    """No two robots hold one cell at the same time (moving: footprint; resting: cell)."""
    domain = trace.scenario.domain
    horizon = max([m.end for m in trace.moves] + [a.end for a in trace.acts] + [0]) + 1
    by_cell: dict[Cell, list[tuple[int, int, str, int]]] = {}
    for robot in trace.scenario.robots:
        moves = sorted((m for m in trace.moves if m.robot == robot.name), key=lambda m: m.start)
        pose, since, line = robot.start, 0, 1
        for m in moves:
            by_cell.setdefault(pose.cell, []).append((since, m.start, robot.name, line))
            held = (
                (m.before.cell,)
                if m.source in (StepSource.FAILED_ATTEMPT, StepSource.BUMPED)
                else domain.footprint(m.before, m.action)
            )  # a failed attempt or a bump holds the robot's cell
            for cell in held:
                by_cell.setdefault(cell, []).append((m.start, m.end, robot.name, m.line))
            pose, since, line = m.after, m.end, m.line
        by_cell.setdefault(pose.cell, []).append((since, horizon, robot.name, line))
    first: tuple[int, str, int] | None = None
    for cell, spans in by_cell.items():
        spans.sort()
        for i, (s1, e1, r1, l1) in enumerate(spans):
            for s2, e2, r2, l2 in spans[i + 1 :]:
                if s2 >= e1:
                    break
                if r1 != r2 and s2 < e1 and s1 < e2:
                    at = max(s1, s2)
                    text = (
                        f"conflict: {r1} and {r2} both hold cell {cell[0]},{cell[1]} at unit {at}"
                    )
                    if first is None or at < first[0]:
                        first = (at, text, max(l1, l2))
    if first is not None:
        raise _Problem(first[1], first[2])


def _check_summary(trace: TeamTrace, delivered: dict[str, int]) -> None:
    """The summary's counts and makespan against what the lines give."""
    summary = trace.summary
    if summary is None:
        return
    kinds = [str(o.get("type")) for o in trace.other]
    makespan = float(Fraction(max(delivered.values(), default=0), trace.scale))
    scenario = trace.scenario
    for key, value in (
        ("delivered", len(delivered)),
        ("all_delivered", int(len(delivered) == len(scenario.tasks))),
        ("makespan", makespan),
        ("moves", len(trace.moves)),
        ("acts", len(trace.acts)),
        ("incidents", kinds.count("incident")),
        ("repairs", kinds.count("repair")),
        ("own_repairs", kinds.count("own-repair")),
        ("team_size", len(scenario.robots)),
        ("tasks", len(scenario.tasks)),
    ):
        if summary.get(key) != value:
            raise _Problem(
                f"the summary says {key} {summary.get(key)!r}, the trace's lines give {value!r}",
                None,
            )
