"""Caches by kind: every cache is a BoundedCache with a CacheKind, none hides elsewhere, a cold
run empties exactly the kinds the timing policy names, and every cache keyed by a map is marked
per-map."""

from __future__ import annotations

import ast
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import selfrepair
from extras import NUMBA
from selfrepair.caching import BoundedCache, CacheKind, cache_stats, caches, clear_caches
from selfrepair.execution.executor import run_mission
from selfrepair.execution.faults import FaultSchedule
from selfrepair.execution.result import MissionSpec
from selfrepair.geometry import FreeGrid
from selfrepair.repair.strategies import StrategyName
from selfrepair.repair.tolerance import fault_model
from selfrepair.repair.tolerance_masks import tolerance_term
from selfrepair.robots.four_wheel import FOUR_WHEEL
from selfrepair.search.lattice import plan, planning_actions
from selfrepair.search.problem import PlanningProblem
from selfrepair.tables.fileformat import resolve_table
from selfrepair.world.maze import Maze
from selfrepair.world.mazegen import generate_maze
from selfrepair.world.routes import random_routes

SRC = Path(selfrepair.__file__).parent

REGISTRIES = {
    # module-level dicts filled on demand that are registries, not caches: they hold what the
    # user registered, and clearing them would lose it
    ("robots/registry.py", "_REGISTERED"),
    ("robots/registry.py", "_PLUGINS"),
    ("robots/registry.py", "_ORIGINS"),
    ("repair/strategies/registry.py", "_REGISTRY"),
}


def _module_dicts(tree: ast.Module) -> set[str]:
    """Names bound at module level to an empty dict, OrderedDict or defaultdict."""
    names = set()
    for node in tree.body:
        target, value = None, None
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            target, value = node.targets[0], node.value
        elif isinstance(node, ast.AnnAssign):
            target, value = node.target, node.value
        if not isinstance(target, ast.Name) or value is None:
            continue
        empty_dict = isinstance(value, ast.Dict) and not value.keys
        made = (
            isinstance(value, ast.Call)
            and isinstance(value.func, ast.Name)
            and value.func.id in {"dict", "OrderedDict", "defaultdict"}
            and not value.args
        )
        if empty_dict or made:
            names.add(target.id)
    return names


def _filled_in_functions(tree: ast.Module, names: set[str]) -> set[str]:
    """Which of ``names`` a function body stores into (``NAME[k] = v``, ``NAME.setdefault``,
    ``NAME.update``): a dict filled on demand, i.e. a cache or a registry."""
    filled = set()
    for func in ast.walk(tree):
        if not isinstance(func, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for node in ast.walk(func):
            if (
                isinstance(node, ast.Subscript)
                and isinstance(node.ctx, ast.Store)
                and isinstance(node.value, ast.Name)
                and node.value.id in names
            ):
                filled.add(node.value.id)
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr in {"setdefault", "update", "__setitem__"}
                and isinstance(node.func.value, ast.Name)
                and node.func.value.id in names
            ):
                filled.add(node.func.value.id)
    return filled


def _hidden_caches() -> list[str]:
    found = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        if rel == "caching.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                for deco in node.decorator_list:
                    fn = deco.func if isinstance(deco, ast.Call) else deco
                    name = fn.attr if isinstance(fn, ast.Attribute) else getattr(fn, "id", "")
                    if name in {"cache", "lru_cache", "cached_property"}:
                        found.append(f"{rel}:{node.lineno} @{name} on {node.name}")
        dicts = _module_dicts(tree)
        for name in sorted(_filled_in_functions(tree, dicts)):
            if (rel, name) not in REGISTRIES:
                found.append(f"{rel}: module-level dict {name} filled on demand")
    return found


def test_no_cache_outside_the_caching_module() -> None:
    assert _hidden_caches() == []


def test_the_scan_finds_what_it_looks_for(tmp_path: Path) -> None:
    tree = ast.parse(
        "from functools import cache\n_SEEN: dict[int, int] = {}\n"
        "@cache\ndef f(x): return x\n"
        "def g(x):\n    _SEEN[x] = x\n    return x\n"
    )
    assert _filled_in_functions(tree, _module_dicts(tree)) == {"_SEEN"}
    decorated = [
        n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.decorator_list
    ]
    assert decorated == ["f"]


def test_every_cache_declares_a_kind() -> None:
    import selfrepair.experiment.missions
    import selfrepair.team.engine  # noqa: F401

    stats = cache_stats()
    assert {s.kind for s in stats} >= {CacheKind.INPUT, CacheKind.PLAN, CacheKind.REPAIR}
    assert all(isinstance(s.kind, CacheKind) for s in stats)
    with pytest.raises(TypeError):
        BoundedCache("no kind", 4)  # type: ignore[call-arg]


def test_clear_caches_by_kind() -> None:
    plan = BoundedCache[int, int]("test plan cache", 4, kind=CacheKind.PLAN)
    kept = BoundedCache[int, int]("test input cache", 4, kind=CacheKind.INPUT)
    plan.get(1, lambda: 1)
    kept.get(1, lambda: 1)
    clear_caches([CacheKind.PLAN])
    assert len(plan) == 0 and len(kept) == 1
    clear_caches()
    assert len(kept) == 0


def test_a_cold_run_empties_the_kinds_it_must_and_keeps_the_others(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from selfrepair.cli.experiments import resolve_experiment
    from selfrepair.execution import executor
    from selfrepair.experiment.config import load_config
    from selfrepair.experiment.missions import expand
    from selfrepair.experiment.timing import COLD_CLEARS, execute_mission

    missions = expand(load_config(resolve_experiment("paper")))
    mission = next(m for m in missions if dict(m.labels).get("strategy") == "replacement")
    execute_mission(mission)  # fills caches of every kind a mission uses
    before = {s.name: s for s in cache_stats()}
    seen: list[dict[str, int]] = []
    real = executor.run_mission

    def spy(*args: object, **kwargs: object) -> object:
        if not seen:  # the cold run: right after the caches were cleared
            seen.append({s.name: s.size for s in cache_stats()})
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(executor, "run_mission", spy)
    execute_mission(mission)
    at_cold = seen[0]
    cleared = [s for s in before.values() if s.kind in COLD_CLEARS and s.size]
    kept = [s for s in before.values() if s.kind not in COLD_CLEARS and s.size]
    assert cleared and kept  # the mission filled caches of both sorts
    assert {s.name: at_cold[s.name] for s in cleared} == {s.name: 0 for s in cleared}
    assert {s.name: at_cold[s.name] for s in kept} == {s.name: s.size for s in kept}
    assert CacheKind.INPUT not in COLD_CLEARS and CacheKind.PLAN in COLD_CLEARS


def _holds(value: object, maze: Maze, depth: int = 0) -> bool:
    """Whether ``value`` (a cache key) holds ``maze``: the maze itself, one of its free grids, or
    a tuple, set or slotted value with one of those inside (a lattice, a step term's source)."""
    if isinstance(value, Maze):
        return value == maze
    if isinstance(value, FreeGrid):
        return value == maze.free_grid(value.margin)
    if depth >= 4 or isinstance(value, str | bytes | int | float | Fraction | np.ndarray | type):
        return False
    if isinstance(value, tuple | list | frozenset | set):
        return any(_holds(v, maze, depth + 1) for v in value)
    names = getattr(type(value), "__dataclass_fields__", None) or getattr(value, "__slots__", ())
    return any(_holds(getattr(value, n, None), maze, depth + 1) for n in names)


def _plans_on(maze: Maze, *, backend: str) -> None:
    """Every kind of work that keeps data per map: plans with and without clearance, a tolerant
    plan (masks and terms), and missions with a fault, with and without the compiled loop."""
    route = random_routes(maze, 1, seed=3)[0]
    start, goal = route.start, route.goal
    plan(PlanningProblem(maze, start, goal), backend=backend)
    plan(PlanningProblem(maze, start, goal, clearance_weight=Fraction(1)), backend=backend)
    actions = planning_actions(FOUR_WHEEL, frozenset())
    model = fault_model(FOUR_WHEEL, 1)
    term = tolerance_term(resolve_table("handwritten"), maze.free_grid(), actions, model)
    plan(PlanningProblem(maze, start, goal, step_term=term), backend=backend)
    fault = FOUR_WHEEL.parse_faults("FL:F")
    for strategy in (StrategyName.REPLACEMENT, StrategyName.REPLAN):
        for footing in ("python", "compiled") if backend == "numba" else ("python",):
            run_mission(
                MissionSpec(
                    maze, start, goal, schedule=FaultSchedule.permanent(fault),
                    strategy=strategy, backend=backend, clearance_weight=Fraction(1),
                    footing=footing,
                )
            )  # fmt: skip


@pytest.mark.parametrize("backend", ["python", pytest.param("numba", marks=NUMBA)])
def test_every_cache_keyed_by_a_map_is_marked_per_map(backend: str) -> None:
    """Plan on a maze no other test makes: every cache whose keys then hold it (or its grid) says
    ``per_map``, so ``clear_caches(per_map=True)`` forgets the map entirely."""
    maze = generate_maze(13, 11, corridor=1, braid=0.4, seed=20261203)
    _plans_on(maze, backend=backend)
    holding = {c.name: c.per_map for c in caches() if any(_holds(k, maze) for k in c)}
    assert len(holding) >= 8  # the walk finds the maze inside the keys
    assert {name for name, marked in holding.items() if not marked} == set()
    clear_caches(per_map=True)
    assert [c.name for c in caches() if any(_holds(k, maze) for k in c)] == []
    assert any(len(c) for c in caches() if not c.per_map)  # process-wide data is kept


def test_clear_caches_per_map_keeps_the_others() -> None:
    mapped = BoundedCache[int, int]("test per-map cache", 4, kind=CacheKind.PLAN, per_map=True)
    shared = BoundedCache[int, int]("test process-wide cache", 4, kind=CacheKind.PLAN)
    mapped.get(1, lambda: 1)
    shared.get(1, lambda: 1)
    clear_caches(per_map=True)
    assert len(mapped) == 0 and len(shared) == 1
    assert {s.name: s.per_map for s in cache_stats() if s.name.startswith("test per")} == {
        "test per-map cache": True
    }
