"""D* Lite benchmark: the compiled D* Lite against pathplanning's C++ D* Lite and A* from scratch.

Two parts, on MovingAI 512 x 512 maze maps (``tests/data/movingai``; default ``maze512-4-0``),
with ``--queries`` scenario lines spread evenly over the longer half of each map's file:

**Against the C++ peer** (``pathplanning`` 0.2.0, ``DStarLitePlanner`` on a 4-connected
``Grid2DSearchSpace``), on the same problem: a 4-connected grid robot (:data:`GRID4`: four moves,
each of 1 tick, and a slow variant of each of 2 ticks in the same motion class; the heading never
changes and the goal heading is the start's, so selfrepair's lattice is one copy of the grid).
Both searches are made and plan once (not timed); then the robot drives ``--advance`` of its
plan and the same update is given to both, timed side by side (which one goes first alternates
between repeats), in CPU time of the calling thread (``time.thread_time``: the peer's C++ runs in
this thread through ctypes):

* ``ahead-K`` and ``spread-K``: K cells of the remaining route become blocked, every second cell
  from 3 cells ahead of the robot (what its sensors see close by) or spread evenly over the rest
  of the route (:func:`blocked_cells`; the peer: every edge into and out of them set to
  infinity);
* ``reopen-K``: the cells of ``ahead-K`` were blocked (and both searches planned round them, not
  timed) and become free again (the peer: those edges restored to their initial cost);
* ``fault``: the fast north move is lost everywhere (the peer: every northward edge between free
  cells set to 2, the slow move's cost; the peer's A* is not run there, its grid has unit costs).

Each update is ``move_start`` + the update + ``plan``; ``move`` is reported apart (the peer
rebuilds its heuristic array of every cell on a move). The answer is checked against A* from
scratch on the changed problem (selfrepair's lattice A*, exact): the peer is no oracle (it was
seen to answer a false "no path" after edge updates), so it is timed only where its success and
cost agree with A*, and every disagreement is reported. A* from scratch is timed too: selfrepair's
compiled lattice A* (Manhattan heuristic, as D* Lite's; ``search`` = a second call on the same
map, ``cold`` = the first, with the per-map set-up) and the peer's A* (its native search time).

**The four-wheel robot** (no peer can plan for it): D* Lite kept from the mission's start
against a fresh lattice A* after the same blocked cells and after a fault (``FL:F``: the forward
move loses its fastest action everywhere), both compiled, the same way (one run each); A* with
the Manhattan heuristic (D* Lite's) and with the planner's default, ``grid-distance`` (a BFS
from the goal on the changed map, timed with it and without it).

Targets (issue 25 item 3): compiled D* Lite at most 1.5x the peer's time on the same updates
(median over queries and repeats of the per-update ratio, with a 95% bootstrap interval); and
where D* Lite beats A* from scratch (a few cells blocked) and where it does not (an action lost
everywhere). Results go to ``benchmarks/results/dstar_lite.json``.

Run: ``python benchmarks/dstar_lite.py`` (about five minutes; ``--queries``/``--repeats`` to
trade time for precision, ``--maps`` for more maps).
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Callable, Iterable
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
from pathplanning import plan_discrete
from pathplanning.core.contracts import DiscreteProblem
from pathplanning.planners.search.dstar_lite import DStarLitePlanner
from pathplanning.spaces.grid2d import Grid2DSearchSpace

from _common import write_report
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import Domain
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.astar import PlanStatus
from selfrepair.search.dstar import DStarLite
from selfrepair.search.lattice import plan
from selfrepair.search.problem import PlanningProblem
from selfrepair.search.scenarios import sample_indices
from selfrepair.search.warmup import ensure_warm
from selfrepair.stats import bootstrap_interval
from selfrepair.world.maze import Maze
from selfrepair.world.movingai import load_map, load_scenario

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "movingai"
MOVES = {"N": (0, -1), "E": (1, 0), "S": (0, 1), "W": (-1, 0)}
SLOW = {name.lower(): vector for name, vector in MOVES.items()}


def _grid4_apply(pose: Pose, action: str) -> Pose:
    dx, dy = MOVES.get(action) or SLOW[action]
    return Pose(pose.x + dx, pose.y + dy, pose.heading)


def _grid4_footprint(pose: Pose, action: str) -> tuple[Cell, ...]:
    end = _grid4_apply(pose, action)
    return (pose.cell, end.cell)


GRID4: Domain[str, str] = Domain(
    name="grid4",
    actions=("N", "E", "S", "W", "n", "e", "s", "w"),
    apply=_grid4_apply,
    footprint=_grid4_footprint,
    duration=lambda a: Fraction(1 if a.isupper() else 2),
    available=lambda a, faults: a not in faults,
    parse_action=str,
    format_action=str,
    faults=("N", "E", "S", "W"),
    parse_faults=lambda text: frozenset(p for p in text.split(",") if p),
    format_faults=lambda faults: ",".join(sorted(faults)),
    motion_class=str.upper,
)
"""A 4-connected grid robot: moves N/E/S/W of 1 tick, and slow variants (n/e/s/w, 2 ticks) in
the same motion classes, so a lost fast move changes edge costs rather than removing edges."""


def cpu(fn: Callable[[], Any]) -> tuple[float, Any]:
    """CPU seconds of this thread spent in ``fn()``, and its result."""
    t0 = time.thread_time()
    out = fn()
    return time.thread_time() - t0, out


def walk(domain: Domain[Any, Any], pose: Pose, actions: Iterable[Any]) -> list[Pose]:
    poses = [pose]
    for action in actions:
        poses.append(domain.apply(poses[-1], action))
    return poses


def blocked_cells(route: list[Pose], at: int, case: str) -> list[Cell]:
    """The cells a ``ahead-K`` or ``spread-K`` case blocks on the rest of ``route`` (the robot
    at ``route[at]``): ``ahead``, every second cell from 3 cells ahead (what a robot's sensors see
    close by); ``spread``, K cells spread evenly over the rest; never the robot's cell or the
    goal's last 3 cells."""
    kind, count = case.split("-")
    k = int(count)
    cells = list(dict.fromkeys(p.cell for p in route[at + 3 : -3]))
    cells = [c for c in cells if c != route[at].cell]
    if kind == "ahead":
        return cells[: 2 * k : 2]
    return [cells[int((i + 0.5) * len(cells) / k)] for i in range(k)] if cells else []


def astar(
    walls: np.ndarray, domain: Domain[Any, Any], start: Pose, goal: Cell, heading: Heading | None,
    faults: frozenset[Any], heuristic: str = "manhattan",
) -> tuple[float, float, Any]:  # fmt: skip
    """selfrepair's compiled lattice A* from scratch on the map ``walls``: CPU seconds of the
    first call (per-map set-up included: for ``grid-distance`` a BFS from the goal) and of a
    second (search only), and the result."""
    problem = PlanningProblem(Maze(walls), start, goal, heading, faults, domain=domain)
    cold, _ = cpu(lambda: plan(problem, heuristic=heuristic, backend="numba"))
    warm, result = cpu(lambda: plan(problem, heuristic=heuristic, backend="numba"))
    return cold, warm, result


# --- the peer ------------------------------------------------------------------------------------


def peer_space(walls: np.ndarray) -> Grid2DSearchSpace:
    h, w = walls.shape
    return Grid2DSearchSpace(w, h, motions=list(MOVES.values()), occupancy=walls)


def blocking_edges(walls: np.ndarray, cells: list[Cell]) -> list[tuple[Cell, Cell, float]]:
    """Every directed edge into or out of ``cells`` (4-connected, inside the map), at infinity."""
    h, w = walls.shape
    seen: dict[tuple[Cell, Cell], None] = {}
    for x, y in cells:
        for dx, dy in MOVES.values():
            nx, ny = x + dx, y + dy
            if 0 <= nx < w and 0 <= ny < h:
                seen.setdefault(((x, y), (nx, ny)), None)
                seen.setdefault(((nx, ny), (x, y)), None)
    return [(a, b, math.inf) for a, b in seen]


def north_edges(walls: np.ndarray) -> list[tuple[Cell, Cell, float]]:
    """Every northward edge between two free cells, at the slow move's cost."""
    ys, xs = np.nonzero(~walls[1:] & ~walls[:-1])
    return [((int(x), int(y) + 1), (int(x), int(y)), 2.0) for y, x in zip(ys, xs, strict=True)]


def peer_astar(walls: np.ndarray, start: Cell, goal: Cell) -> dict[str, Any]:
    """The peer's A* from scratch on the map ``walls`` (unit costs): its native search time and
    the whole call (graph materialisation included)."""
    t0 = time.thread_time()
    result = plan_discrete(DiscreteProblem(peer_space(walls), start, goal), planner="astar")
    whole = time.thread_time() - t0
    return {
        "success": bool(result.success),
        "cost": float(result.stats.get("path_cost", math.nan)),
        "native_s": float(result.stats.get("native_search_s", math.nan)),
        "whole_s": whole,
    }


# --- one update, both D* Lites ---------------------------------------------------------------


def run_update(
    maze: Maze, start: Pose, goal: Cell, case: str, advance: float, repeat: int,
) -> dict[str, Any]:  # fmt: skip
    """One repeat of one update on fresh searches (ours and the peer's), side by side."""
    heading = start.heading
    ours = DStarLite.create(GRID4, maze, start, goal, goal_heading=heading, backend="numba")
    first = ours.plan()
    assert first.status is PlanStatus.SOLVED
    poses = walk(GRID4, start, first.actions)
    at = poses[int(advance * (len(poses) - 1))]
    walls = maze.walls.copy()
    faults: frozenset[str] = frozenset()
    peer = DStarLitePlanner(peer_space(maze.walls), start.cell, goal)
    peer_first = peer.plan()
    edges: list[tuple[Cell, Cell, float | None]]
    if case.startswith("reopen-"):  # first blocked (not timed), then free again (timed)
        picks = blocked_cells(poses, poses.index(at), case.replace("reopen", "ahead"))
        blocking = blocking_edges(maze.walls, picks)
        ours.move_start(at)
        ours.update_cells(blocked=picks)
        ours.plan()
        peer.move_start(at.cell)
        peer.update_edges(blocking)
        peer.plan()
        update = lambda: ours.update_cells(freed=picks)  # noqa: E731
        edges = [(a, b, None) for a, b, _ in blocking]  # the peer's "restore the initial cost"
    elif case != "fault":
        picks = blocked_cells(poses, poses.index(at), case)
        walls[[y for _, y in picks], [x for x, _ in picks]] = True
        update = lambda: ours.update_cells(blocked=picks)  # noqa: E731
        edges = list(blocking_edges(maze.walls, picks))
    else:
        faults = frozenset({"N"})
        update = lambda: ours.update_faults(faults)  # noqa: E731
        edges = list(north_edges(maze.walls))
    row: dict[str, Any] = {"case": case, "repeat": repeat, "cells_ahead": len(poses) - 1}
    row["peer_first_success"] = bool(peer_first.success)

    def time_ours() -> None:
        row["ours_move_s"], _ = cpu(lambda: ours.move_start(at))
        row["ours_update_s"], _ = cpu(update)
        row["ours_plan_s"], found = cpu(ours.plan)
        row["ours_status"] = found.status.value
        row["ours_cost"] = float(found.cost) if found.cost is not None else math.nan
        row["ours_expansions"] = found.expansions

    def time_peer() -> None:
        row["peer_move_s"], _ = cpu(lambda: peer.move_start(at.cell))
        row["peer_update_s"], _ = cpu(lambda: peer.update_edges(edges))
        row["peer_plan_s"], answer = cpu(peer.plan)
        row["peer_success"] = bool(answer.success)
        row["peer_cost"] = float(answer.stats.get("path_cost", math.nan))
        row["peer_expansions"] = int(answer.iters)

    for fn in (time_ours, time_peer) if repeat % 2 == 0 else (time_peer, time_ours):
        fn()
    cold, warm, fresh = astar(walls, GRID4, at, goal, heading, faults)
    row["astar_cold_s"], row["astar_s"] = cold, warm
    row["astar_status"] = fresh.status.value
    row["astar_cost"] = float(fresh.cost) if fresh.cost is not None else math.nan
    row["astar_expansions"] = fresh.expansions
    assert row["ours_status"] == row["astar_status"], row
    assert fresh.cost is None or row["ours_cost"] == float(fresh.cost), row
    solved = fresh.status is PlanStatus.SOLVED
    row["peer_agrees"] = row["peer_success"] == solved and (
        not solved or abs(row["peer_cost"] - row["astar_cost"]) < 1e-6
    )
    if not faults:  # the peer's A* plans on unit costs only (its grid has no slow moves)
        peer_a = peer_astar(walls, at.cell, goal)
        row.update({f"peer_astar_{k}": v for k, v in peer_a.items()})
    for who in ("ours", "peer"):
        row[f"{who}_s"] = row[f"{who}_update_s"] + row[f"{who}_plan_s"]
        row[f"{who}_with_move_s"] = row[f"{who}_s"] + row[f"{who}_move_s"]
    return row


def run_four_wheel(
    maze: Maze, start: Pose, goal: Cell, case: str, advance: float
) -> dict[str, Any]:  # fmt: skip
    """The four-wheel robot: D* Lite kept from the start against a fresh A*, both compiled."""
    ours = DStarLite.create(FOUR_WHEEL, maze, start, goal, backend="numba")
    first = ours.plan()
    poses = walk(FOUR_WHEEL, start, first.actions)
    at = poses[int(advance * (len(poses) - 1))]
    walls = maze.walls.copy()
    faults: frozenset[Any] = frozenset()
    if case.startswith("reopen-"):  # first blocked (not timed), then free again (timed)
        picks = blocked_cells(poses, poses.index(at), case.replace("reopen", "ahead"))
        ours.move_start(at)
        ours.update_cells(blocked=picks)
        ours.plan()
        update = lambda: ours.update_cells(freed=picks)  # noqa: E731
    elif case != "fault":
        picks = blocked_cells(poses, poses.index(at), case)
        walls[[y for _, y in picks], [x for x, _ in picks]] = True
        update = lambda: ours.update_cells(blocked=picks)  # noqa: E731
    else:
        faults = FOUR_WHEEL.parse_faults("FL:F")
        update = lambda: ours.update_faults(faults)  # noqa: E731
    row: dict[str, Any] = {"case": case, "first_expansions": first.expansions}
    move_s, _ = cpu(lambda: ours.move_start(at))
    update_s, _ = cpu(update)
    plan_s, found = cpu(ours.plan)
    row["ours_s"] = move_s + update_s + plan_s
    row["ours_expansions"] = found.expansions
    cold, warm, fresh = astar(walls, FOUR_WHEEL, at, goal, None, faults)
    assert found.cost == fresh.cost, (found.cost, fresh.cost)
    row["astar_cold_s"], row["astar_s"], row["astar_expansions"] = cold, warm, fresh.expansions
    cold, warm, fresh = astar(walls, FOUR_WHEEL, at, goal, None, faults, "grid-distance")
    assert found.cost == fresh.cost, (found.cost, fresh.cost)
    row["astar_bfs_cold_s"], row["astar_bfs_s"] = cold, warm
    row["astar_bfs_expansions"] = fresh.expansions
    return row


# --- summaries -------------------------------------------------------------------------------


def interval(values: list[float]) -> list[float] | None:
    found = bootstrap_interval(values)
    return None if found is None else [found.estimate, found.low, found.high]


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """Per case: medians with intervals of the times and of the per-update ratios, over the
    updates where the peer agrees with A*; the disagreements."""
    out: dict[str, Any] = {}
    for case in dict.fromkeys(r["case"] for r in rows):
        mine = [r for r in rows if r["case"] == case]
        good = [r for r in mine if r["peer_agrees"]]
        entry: dict[str, Any] = {
            "updates": len(mine),
            "peer_disagrees": len(mine) - len(good),
            "peer_false_no_path": sum(
                1 for r in mine if not r["peer_success"] and r["astar_status"] == "solved"
            ),
            "ours_ms": interval([1e3 * r["ours_s"] for r in mine]),
            "ours_update_ms": interval([1e3 * r["ours_update_s"] for r in mine]),
            "ours_plan_ms": interval([1e3 * r["ours_plan_s"] for r in mine]),
            "astar_ms": interval([1e3 * r["astar_s"] for r in mine]),
            "astar_cold_ms": interval([1e3 * r["astar_cold_s"] for r in mine]),
            "ours_vs_astar": interval([r["ours_s"] / r["astar_s"] for r in mine]),
            "ours_expansions": statistics.median(r["ours_expansions"] for r in mine),
            "astar_expansions": statistics.median(r["astar_expansions"] for r in mine),
        }
        if good:
            entry |= {
                "peer_ms": interval([1e3 * r["peer_s"] for r in good]),
                "peer_move_ms": interval([1e3 * r["peer_move_s"] for r in good]),
                "peer_update_ms": interval([1e3 * r["peer_update_s"] for r in good]),
                "peer_plan_ms": interval([1e3 * r["peer_plan_s"] for r in good]),
                "ours_vs_peer_plan": interval([r["ours_plan_s"] / r["peer_plan_s"] for r in good]),
                "ours_vs_peer": interval([r["ours_s"] / r["peer_s"] for r in good]),
                "ours_vs_peer_with_move": interval(
                    [r["ours_with_move_s"] / r["peer_with_move_s"] for r in good]
                ),
                "peer_astar_ms": interval(
                    [1e3 * r["peer_astar_native_s"] for r in good if "peer_astar_native_s" in r]
                ),
                "peer_vs_peer_astar": interval(
                    [
                        r["peer_s"] / r["peer_astar_native_s"]
                        for r in good
                        if "peer_astar_native_s" in r
                    ]
                ),
                "peer_expansions": statistics.median(r["peer_expansions"] for r in good),
            }
        out[case] = entry
    return out


def fmt(iv: list[float] | None, digits: int = 2) -> str:
    if iv is None:
        return "-"
    return f"{iv[0]:.{digits}f} [{iv[1]:.{digits}f}, {iv[2]:.{digits}f}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--maps", nargs="+", default=["maze512-4-0"])
    parser.add_argument("--queries", type=int, default=6)
    parser.add_argument("--repeats", type=int, default=4)
    parser.add_argument("--advance", type=float, default=0.1)
    parser.add_argument(
        "--cases",
        nargs="+",
        default=["ahead-1", "ahead-4", "ahead-16", "spread-4", "reopen-4", "fault"],
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if not _numba():
        sys.exit("numba is not installed: the benchmark measures the compiled D* Lite")
    ensure_warm("lattice")
    warm = Maze(np.zeros((4, 4), dtype=bool))
    DStarLite.create(GRID4, warm, Pose(0, 0, Heading.E), (3, 3), backend="numba").plan()
    cases = args.cases
    report: dict[str, Any] = {"settings": vars(args) | {"out": str(args.out)}, "maps": {}}
    for name in args.maps:
        maze = load_map(DATA / f"{name}.map")
        queries = list(load_scenario(DATA / f"{name}.map.scen"))
        half = len(queries) // 2
        picked = [queries[half + i] for i in sample_indices(len(queries) - half, args.queries, 0)]
        rows, robot = [], []
        for q in picked:
            start = Pose(*q.start, Heading.E)
            for case in cases:
                for repeat in range(args.repeats):
                    row = run_update(maze, start, q.goal, case, args.advance, repeat)
                    row["line"] = q.line
                    rows.append(row)
                    print(
                        f"{name} line {q.line:5d} {case:9s} r{repeat}"
                        f" ours {1e3 * row['ours_s']:8.2f} ms  peer {1e3 * row['peer_s']:8.2f} ms"
                        f"{'' if row['peer_agrees'] else ' (peer DISAGREES)'}"
                        f"  A* {1e3 * row['astar_s']:7.2f} ms",
                        flush=True,
                    )
                robot.append(run_four_wheel(maze, start, q.goal, case, args.advance))
        summary = summarise(rows)
        robot_summary = {
            case: {
                "dstar_ms": interval([1e3 * r["ours_s"] for r in robot if r["case"] == case]),
                "astar_ms": interval([1e3 * r["astar_s"] for r in robot if r["case"] == case]),
                "dstar_vs_astar": interval(
                    [r["ours_s"] / r["astar_s"] for r in robot if r["case"] == case]
                ),
                "dstar_expansions": statistics.median(
                    r["ours_expansions"] for r in robot if r["case"] == case
                ),
                "astar_expansions": statistics.median(
                    r["astar_expansions"] for r in robot if r["case"] == case
                ),
                "astar_bfs_ms": interval(
                    [1e3 * r["astar_bfs_s"] for r in robot if r["case"] == case]
                ),
                "astar_bfs_cold_ms": interval(
                    [1e3 * r["astar_bfs_cold_s"] for r in robot if r["case"] == case]
                ),
                "dstar_vs_astar_bfs": interval(
                    [r["ours_s"] / r["astar_bfs_s"] for r in robot if r["case"] == case]
                ),
                "dstar_vs_astar_bfs_cold": interval(
                    [r["ours_s"] / r["astar_bfs_cold_s"] for r in robot if r["case"] == case]
                ),
                "astar_bfs_expansions": statistics.median(
                    r["astar_bfs_expansions"] for r in robot if r["case"] == case
                ),
            }
            for case in cases
        }
        report["maps"][name] = {
            "rows": rows,
            "summary": summary,
            "four_wheel": robot,
            "four_wheel_summary": robot_summary,
        }
        print_summary(name, summary, robot_summary)
    path = write_report("dstar_lite", report, args.out)
    print(f"wrote {path}")


def print_summary(name: str, summary: dict[str, Any], robot: dict[str, Any]) -> None:
    print(f"\n{name}: 4-connected grid robot, medians [95% interval] over queries x repeats")
    print(
        f"{'case':9} {'ours ms':>22} {'peer ms':>22} {'ours/peer':>20} {'A* ms':>20}"
        f" {'ours/A*':>20} {'peer A* ms':>20} {'peer/peer A*':>20} disagree"
    )
    for case, s in summary.items():
        print(
            f"{case:9} {fmt(s['ours_ms']):>22} {fmt(s.get('peer_ms')):>22}"
            f" {fmt(s.get('ours_vs_peer')):>20} {fmt(s['astar_ms']):>20}"
            f" {fmt(s['ours_vs_astar']):>20} {fmt(s.get('peer_astar_ms')):>20}"
            f" {fmt(s.get('peer_vs_peer_astar')):>20} {s['peer_disagrees']}/{s['updates']}"
        )
    print("update and plan apart (ms): ours update / plan, peer update / plan, ours/peer plan")
    for case, s in summary.items():
        print(
            f"  {case:9} {fmt(s['ours_update_ms'])} / {fmt(s['ours_plan_ms'])},"
            f" {fmt(s.get('peer_update_ms'))} / {fmt(s.get('peer_plan_ms'))},"
            f" {fmt(s.get('ours_vs_peer_plan'))}"
        )
    for case, s in summary.items():
        ratio = s.get("ours_vs_peer")
        verdict = "-" if ratio is None else ("met" if ratio[0] <= 1.5 else "NOT met")
        print(f"  target ours/peer <= 1.5 on {case}: {fmt(ratio)} ({verdict})")
    print(f"{name}: four-wheel robot, D* Lite kept against a fresh A* (both compiled)")
    for case, s in robot.items():
        print(
            f"  {case:9} D* Lite {fmt(s['dstar_ms'])} ms, A* (Manhattan) {fmt(s['astar_ms'])} ms,"
            f" ratio {fmt(s['dstar_vs_astar'])}; expansions {s['dstar_expansions']:.0f}"
            f" against {s['astar_expansions']:.0f}"
        )
        print(
            f"  {'':9} A* (grid-distance, the default) {fmt(s['astar_bfs_ms'])} ms search,"
            f" {fmt(s['astar_bfs_cold_ms'])} ms with its BFS; ratio"
            f" {fmt(s['dstar_vs_astar_bfs'])} and {fmt(s['dstar_vs_astar_bfs_cold'])};"
            f" expansions {s['astar_bfs_expansions']:.0f}"
        )


def _numba() -> bool:
    from selfrepair.search import _dstar_kernels

    return _dstar_kernels.NUMBA


if __name__ == "__main__":
    main()
