"""Caches by kind: every cache is a BoundedCache with a CacheKind, none hides elsewhere, and a
cold run empties exactly the kinds the timing policy names."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import selfrepair
from selfrepair.caching import BoundedCache, CacheKind, cache_stats, clear_caches

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
