"""D* Lite (Koenig and Likhachev 2002) on a robot's pose lattice, kept between changes.

One incremental search for one goal, which follows the robot and the world: build it with
:meth:`DStarLite.create` (robot, maze, start, goal, known faults), then, as things change,

* :meth:`DStarLite.update_faults` when the known faults change (an action lost is an edge-cost
  change of every edge of its motion class, everywhere on the map: the worst case for
  incremental search),
* :meth:`DStarLite.update_cells` when cells become blocked or free (a door closes, a box is
  dropped: the edges whose footprint sweeps those cells change, and with a clearance term the
  edges near them),
* :meth:`DStarLite.move_start` when the robot has moved,

and call :meth:`DStarLite.plan` for the optimal plan from the current start
(:class:`DStarPlan`: status, actions, exact cost, expansions since the last plan). The search
repairs only what the changes touch. This is the API for "D* Lite kept between changes" (the
changing-world experiment) as well as the ``dstar-lite`` repair strategy
(:mod:`selfrepair.repair.dstar_lite`)::

    search = DStarLite.create(FOUR_WHEEL, maze, start, goal, frozenset())
    first = search.plan()                      # from scratch
    search.move_start(pose)                    # the robot drove on
    search.update_cells(blocked=[(4, 7)])      # a cell became blocked
    again = search.plan()                      # incremental: only the affected part
    search.update_faults(FOUR_WHEEL.parse_faults("FL:F"))

**Graph.** Nodes are integers ``4 * cell + heading`` with ``cell`` an index into the maze padded
by ``margin`` wall cells (the robot's reach, so that no footprint leaves the buffer) and
flattened; the goal given as a cell (any heading, or one heading) is a virtual node reached at
cost 0 from each goal pose. Each motion class (the domain's ``motion_class``, in the order of first
appearance in ``domain.actions``; classes that never move are left out) is one integer node
offset per heading; its edge from a node costs the scaled duration of the class's fastest
available action under the known faults (:func:`~selfrepair.robots.domain.primitive_by_motion`)
plus the clearance term (weight x the clearance penalties of the footprint cells, exactly as
:func:`selfrepair.search.lattice.action_cost`), times the integer cost scale
(:func:`~selfrepair.search.lattice.cost_scale`); it is impassable when the class has no
available action or a footprint cell is blocked. The search runs backwards from the goal with the
consistent heuristic ``rate * manhattan`` to the start (``rate`` from
:func:`~selfrepair.robots.domain.progress_rate` over all actions, so it stays admissible under
any faults; rounded down, which keeps it consistent on integer costs).

**Tie-breaking** (the same in both backends, so they return the same plans). The open list is
ordered by the key ``(k1, k2)`` and then by the node number: a total order, so the order of
expansions is defined whatever the heap's arrangement (the pure-Python reference uses a
lazy-deletion ``heapq``, the compiled one an indexed heap: they pop the same nodes in the same
order). The plan follows ``argmin(c + g)`` from the start, ties to the lowest motion class. Two
plans of different backends are therefore the same action for action, with the same cost and
the same number of expansions; against A* from scratch only the cost is the same (A* breaks
ties differently).

**Backends.** ``"python"`` is the reference
(:class:`~selfrepair.search._dstar_reference.PythonCore`); ``"numba"`` runs the kernels of
:mod:`selfrepair.search._dstar_kernels` (optional, the ``fast`` extra); ``"auto"`` uses numba when
it is importable, as for the planner (:func:`selfrepair.search.backend.use_numba`). A blocked
goal cell or start cell means no plan (``UNSOLVABLE``, at once: the search is not run then).
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Protocol

import numpy as np
import numpy.typing as npt

from selfrepair.errors import ProblemError
from selfrepair.geometry import Cell, Heading, Pose
from selfrepair.robots.domain import SomeDomain, primitive_by_motion, progress_rate
from selfrepair.search._dstar_reference import INF, Core, PythonCore, geometry, reach
from selfrepair.search.astar import BACKENDS, PlanStatus
from selfrepair.search.backend import use_numba

__all__ = ["INF", "DStarLite", "DStarPlan", "WallMap"]


def _use_numba(backend: str) -> bool:
    """Whether ``backend`` means the kernels: the planner's switch without a domain
    (:func:`selfrepair.search.backend.use_numba`; the kernels take any robot, their margin is
    its reach), after checking that ``backend`` is one."""
    if backend not in BACKENDS:
        raise ProblemError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    return use_numba(backend)


def _compiled(graph: DStarLite) -> Core:
    from selfrepair.search._dstar_kernels import CompiledCore

    return CompiledCore(graph)


class WallMap(Protocol):
    """What :meth:`DStarLite.create` reads of a maze (:class:`selfrepair.world.maze.Maze` is
    one): its walls, ``[y, x]``, true for a blocked cell. (A protocol, so that this module, which
    the repair layer uses, depends on no maze.)"""

    @property
    def walls(self) -> npt.NDArray[np.bool_]: ...


@dataclass(frozen=True, slots=True)
class DStarPlan:
    """What :meth:`DStarLite.plan` found: ``status``, the actions from the current start (empty
    unless solved), their exact ``cost`` (duration plus clearance term; ``None`` unless solved) and
    ``scaled_cost`` (``cost`` times the cost scale, an integer; 0 unless solved), the vertex
    ``expansions`` since the previous plan, and the wall time of the call."""

    status: PlanStatus
    actions: tuple[object, ...]
    cost: Fraction | None
    scaled_cost: int
    expansions: int
    wall_time_ns: int


def _penalties(free: npt.NDArray[np.uint8], radius: int) -> npt.NDArray[np.int64]:
    """``max(0, radius - clearance)`` per cell of the 2-D array ``free`` (clearance: Chebyshev
    distance to the nearest blocked cell; beyond the array counts as blocked), as
    :func:`selfrepair.world.maze.clearance_penalties` computes it on a maze."""
    near = free == 0
    pen = np.where(near, radius, 0).astype(np.int64)
    for d in range(1, radius):
        grown = np.pad(near, 1, constant_values=True)
        rows = grown[:-2] | grown[1:-1] | grown[2:]
        near = rows[:, :-2] | rows[:, 1:-1] | rows[:, 2:]
        pen[(pen == 0) & near] = radius - d
    return pen


class DStarLite:
    """One D* Lite search kept between changes (mutable: see the module docstring).

    Build it with :meth:`create` (a maze or a wall array). ``backend`` says
    which implementation runs (``"numba"`` or ``"python"``); ``faults`` are the known faults,
    ``start`` the pose the next plan starts from, ``walls`` the current map (``[y, x]``, true for
    a blocked cell).
    """

    def __init__(
        self,
        domain: SomeDomain,
        walls: npt.NDArray[np.bool_],
        start: Pose,
        goal: Cell,
        faults: frozenset[object],
        goal_heading: Heading | None,
        clearance_weight: Fraction,
        clearance_radius: int,
        backend: str,
    ) -> None:
        numba = _use_numba(backend)
        weight = Fraction(clearance_weight)
        if weight < 0 or clearance_radius < 0:
            raise ProblemError("clearance weight and radius must be at least 0")
        height, width = walls.shape
        for what, (x, y) in (("start", start.cell), ("goal", goal)):
            if not (0 <= x < width and 0 <= y < height):
                raise ProblemError(f"the {what} {(x, y)} is outside the {width}x{height} maze")
        self.domain = domain
        self.scale = domain.time_unit * weight.denominator  # as search.lattice.cost_scale
        self.wmul = weight.numerator * (self.scale // weight.denominator)
        self.radius = clearance_radius
        margin = max(1, reach(domain), clearance_radius - 1 if self.wmul else 0)
        pw = width + 2 * margin
        self.geometry = geometry(domain, pw, margin, height + 2 * margin)
        padded = np.zeros((height + 2 * margin, pw), dtype=np.uint8)
        padded[margin:-margin, margin:-margin] = ~np.asarray(walls, dtype=bool)
        self._free2d = padded
        self.free = padded.ravel()
        self._pen2d = _penalties(padded, clearance_radius) if self.wmul else None
        self.pen = self._pen2d.ravel() if self._pen2d is not None else np.zeros(1, dtype=np.int64)
        rate = progress_rate(domain, domain.actions) * self.scale
        self.rnum, self.rden = rate.numerator, rate.denominator
        self.goal = goal
        self.goal_heading = goal_heading
        self.goal_cell = self._cell(*goal)
        self.goal_head = -1 if goal_heading is None else int(goal_heading)
        self.faults: frozenset[object] = frozenset()
        self.chosen: tuple[object, ...] = ()
        self.dur = np.full(len(self.geometry.classes), -1, dtype=np.int64)
        self._choose(frozenset(faults))
        self.backend = "numba" if numba else "python"
        self.core: Core = _compiled(self) if self.backend == "numba" else PythonCore(self)
        self.start = start
        self.core.start = self._node(start)
        self.core.update_nodes([self.geometry.nodes])  # queue the goal

    @classmethod
    def create(
        cls,
        domain: SomeDomain,
        maze: WallMap | npt.NDArray[np.bool_],
        start: Pose,
        goal: Cell,
        faults: frozenset[object] = frozenset(),
        *,
        goal_heading: Heading | None = None,
        clearance_weight: Fraction | int = 0,
        clearance_radius: int = 2,
        backend: str = "auto",
    ) -> DStarLite:
        """A search for ``domain`` on ``maze`` (or on a wall array ``[y, x]``, true for a blocked
        cell, for layers that know no maze) from ``start`` to ``goal`` (any heading unless
        ``goal_heading``) under the known ``faults``; nothing is searched until :meth:`plan`."""
        walls = maze if isinstance(maze, np.ndarray) else maze.walls
        return cls(
            domain, walls, start, goal, faults, goal_heading, Fraction(clearance_weight),
            clearance_radius, backend,
        )  # fmt: skip

    # --- coordinates ---------------------------------------------------------------------------

    def _cell(self, x: int, y: int) -> int:
        m = self.geometry.margin
        return (y + m) * self.geometry.pw + x + m

    def _node(self, pose: Pose) -> int:
        return 4 * self._cell(pose.x, pose.y) + int(pose.heading)

    @property
    def walls(self) -> npt.NDArray[np.bool_]:
        """The current map, ``[y, x]``, true for a blocked cell (a copy)."""
        m = self.geometry.margin
        walls: npt.NDArray[np.bool_] = self._free2d[m:-m, m:-m] == 0
        return walls

    # --- changes -------------------------------------------------------------------------------

    def _choose(self, faults: frozenset[object]) -> bool:
        fastest = primitive_by_motion(self.domain, faults)
        chosen = tuple(fastest.get(m) for m in self.geometry.classes)
        changed = chosen != self.chosen
        self.faults, self.chosen = faults, chosen
        for k, action in enumerate(chosen):
            self.dur[k] = (
                -1 if action is None else int(Fraction(self.domain.duration(action)) * self.scale)
            )
        return changed

    def update_faults(self, faults: frozenset[object]) -> int:
        """The known faults are now ``faults``; returns the number of vertex updates made (0 when
        no motion class changed its action)."""
        faults = frozenset(faults)
        if faults == self.faults or not self._choose(faults):
            self.faults = faults
            return 0
        self.core.set_dur(self.dur)
        return self.core.faults_sweep()

    def update_cells(self, blocked: Iterable[Cell] = (), freed: Iterable[Cell] = ()) -> int:
        """Cells ``blocked`` became blocked and cells ``freed`` free (each ``(x, y)``; a cell
        already in that state is ignored); returns the number of vertex updates made. Raises
        :class:`ProblemError` for a cell outside the maze or named in both."""
        to_block, to_free = sorted(set(blocked)), sorted(set(freed))
        both = set(to_block) & set(to_free)
        if both:
            raise ProblemError(f"cell {min(both)} is both blocked and freed")
        height, width = self._free2d.shape
        m = self.geometry.margin
        flips: list[int] = []
        for value, named in ((0, to_block), (1, to_free)):
            for x, y in named:
                if not (0 <= x < width - 2 * m and 0 <= y < height - 2 * m):
                    raise ProblemError(f"cell {(x, y)} is outside the maze")
                c = self._cell(x, y)
                if self.free[c] != value:
                    self.free[c] = value
                    flips.append(c)
        changed = set(flips)
        if self.wmul and flips:
            changed.update(self._repenalise(flips))
        cells = sorted(changed)
        if not cells:
            return 0
        self.core.set_cells(cells)
        geo = self.geometry
        nodes: set[int] = set()
        for q in cells:
            for per in geo.sweep:
                for h, offsets in enumerate(per):
                    for o in offsets:
                        nodes.add(4 * (q - o) + h)
        if self.goal_cell in changed:
            nodes.update(4 * self.goal_cell + h for h in range(4))
        ordered = sorted(n for n in nodes if 0 <= n < geo.nodes)
        self.core.update_nodes(ordered)
        return len(ordered)

    def _repenalise(self, flips: Sequence[int]) -> list[int]:
        """Recompute the clearance penalties near the flipped cells; the cells whose penalty
        changed."""
        assert self._pen2d is not None
        pw, r = self.geometry.pw, self.radius
        ph = self._free2d.shape[0]
        changed: list[int] = []
        for c in flips:
            y, x = divmod(c, pw)
            y0, y1 = max(0, y - 2 * r), min(ph, y + 2 * r + 1)
            x0, x1 = max(0, x - 2 * r), min(pw, x + 2 * r + 1)
            fresh = _penalties(self._free2d[y0:y1, x0:x1], r)
            iy0, iy1 = max(y0, y - r), min(y1, y + r + 1)
            ix0, ix1 = max(x0, x - r), min(x1, x + r + 1)
            inner = fresh[iy0 - y0 : iy1 - y0, ix0 - x0 : ix1 - x0]
            old = self._pen2d[iy0:iy1, ix0:ix1]
            ys, xs = np.nonzero(inner != old)
            old[...] = inner
            changed.extend(int((iy0 + dy) * pw + ix0 + dx) for dy, dx in zip(ys, xs, strict=True))
        return changed

    def move_start(self, pose: Pose) -> None:
        """The robot is now at ``pose``: the next plan starts there (D* Lite's ``km`` grows by
        the heuristic distance moved, so the queued keys stay valid)."""
        x, y = pose.cell
        height, width = self._free2d.shape
        m = self.geometry.margin
        if not (0 <= x < width - 2 * m and 0 <= y < height - 2 * m):
            raise ProblemError(f"the start {(x, y)} is outside the maze")
        node = self._node(pose)
        core = self.core
        pw = self.geometry.pw
        a, b = node >> 2, core.start >> 2
        dist = abs(a % pw - b % pw) + abs(a // pw - b // pw)
        core.km = core.km + dist * self.rnum // self.rden
        core.start = node
        self.start = pose

    # --- planning ------------------------------------------------------------------------------

    def plan(self, max_expansions: int | None = None) -> DStarPlan:
        """The optimal plan from the current start under everything known, repairing the search
        incrementally; ``max_expansions`` bounds this call's vertex expansions (the search
        state is kept when it runs out, and a later call goes on from there)."""
        t0 = time.perf_counter_ns()
        core = self.core
        core.expansions = 0
        if not (self.free[core.start >> 2] and self.free[self.goal_cell]):
            # no plan; the search would find that out by settling every node it can reach, so
            # the queue is left as it is for a later plan (when the cell is free again)
            return DStarPlan(PlanStatus.UNSOLVABLE, (), None, 0, 0, time.perf_counter_ns() - t0)
        budget = (1 << 62) if max_expansions is None else max_expansions
        done = core.compute(budget)
        expansions = core.expansions
        if not done:
            status, walked = PlanStatus.BUDGET_EXHAUSTED, None
        else:
            walked = core.walk()
            status = PlanStatus.UNSOLVABLE if walked is None else PlanStatus.SOLVED
        wall = time.perf_counter_ns() - t0
        if walked is None:
            return DStarPlan(status, (), None, 0, expansions, wall)
        classes, total = walked
        actions = tuple(self.chosen[k] for k in classes)
        return DStarPlan(status, actions, Fraction(total, self.scale), total, expansions, wall)
