"""Mission keys and seeds: what makes a sweep resumable and its comparisons paired.

A :class:`Mission` carries the *canonical configuration* of one run as a JSON string with sorted
keys: maze identity (bundled name, file path plus content hash, or generator options), route,
fault set, fault timing and detection, strategy and its options, clearance weight and radius,
replicate and seed. The mission key is the SHA-256 of that string, so the same mission gets the
same key in every run and on every machine, and changing anything about a mission (including the
content of a maze, table or plug-in file) gives it a new key. Files enter the key by name and
content hash, not by absolute path (:func:`portable`), so moving a checkout keeps every key.

The seed of a mission derives from the experiment's base seed and the mission's *situation*
(maze, route, faults, timing, detection, replicate) but not from its strategy: every strategy
meets the same random events (e.g. intermittent faults), so comparisons are paired.
Single-robot missions (:mod:`selfrepair.experiment.missions`) and team missions
(:mod:`selfrepair.experiment.teams`) share these functions.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from selfrepair.experiment.schema import ExperimentConfig
from selfrepair.robots.registry import load_plugin, plugin_file

__all__ = [
    "SCHEMA",
    "Mission",
    "canonical_json",
    "derive_seed",
    "keyed_mission",
    "mission_key",
    "plugin_identities",
    "portable",
]

SCHEMA = 1
"""Version of the canonical mission configuration; part of every key."""


@dataclass(frozen=True, slots=True)
class Mission:
    """One run of the executor, as plain data.

    ``config`` is the canonical JSON (sorted keys, no spaces) that ``key`` hashes; ``labels`` are
    the readable dimension columns stored next to the metrics (maze, route, faults, variant, ...).
    """

    key: str
    experiment: str
    seed: int
    config: str
    labels: tuple[tuple[str, str | int | None], ...]

    @property
    def settings(self) -> dict[str, Any]:
        """The canonical configuration as a dict."""
        return dict(json.loads(self.config))


def canonical_json(data: object) -> str:
    """Sorted-key, compact JSON: the exact text a mission key hashes."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def mission_key(config_json: str) -> str:
    """The stable key of a mission: the first 32 hex digits of SHA-256 of its canonical JSON."""
    return hashlib.sha256(config_json.encode("ascii")).hexdigest()[:32]


def keyed_mission(
    experiment: str,
    seed: int,
    settings: dict[str, Any],
    labels: tuple[tuple[str, str | int | None], ...],
) -> Mission:
    """The mission of ``settings``: their canonical JSON, keyed as :func:`portable` sees them
    (the one rule of a mission's key, for single-robot and team missions alike)."""
    key = mission_key(canonical_json(portable(settings)))
    return Mission(key, experiment, seed, canonical_json(settings), labels)


def derive_seed(base_seed: int, situation: dict[str, Any]) -> int:
    """A 32-bit seed from the base seed and a mission's situation (strategy-independent)."""
    digest = hashlib.sha256(f"{base_seed}|{canonical_json(situation)}".encode("ascii")).digest()
    return int.from_bytes(digest[:4], "big")


def plugin_identities(config: ExperimentConfig) -> list[dict[str, str]]:
    """Each plug-in file of ``config`` by absolute path (to load it in workers) and content hash
    (so editing the robot gives its missions new keys), then the file that registered the
    config's robot when the config does not name it (a robot given with ``--plugin``): the
    robot file's content enters the keys however the robot was loaded. A built-in or installed
    robot adds nothing, so its keys do not change."""
    out = []
    for plugin in config.plugins:
        path = (config.base_dir / plugin).resolve()
        out.append({"file": str(path), "sha256": load_plugin(path)})
    origin = plugin_file(config.domain)
    if origin is not None and all(p["sha256"] != origin.sha256 for p in out):
        out.append({"file": origin.path, "sha256": origin.sha256})
    return out


def portable(settings: dict[str, Any]) -> dict[str, Any]:
    """``settings`` as the key and seed see them: files by name and content hash, not by their
    absolute path, so a checkout or data directory can move without changing any key."""
    out = dict(settings)
    maze = out.get("maze")
    if isinstance(maze, dict) and "file" in maze:
        out["maze"] = {**maze, "file": Path(maze["file"]).name}
    plugins = out.get("plugins")
    if isinstance(plugins, list):
        out["plugins"] = [{**p, "file": Path(p["file"]).name} for p in plugins]
    options = out.get("options")
    if isinstance(options, dict) and "table_sha256" in options:
        out["options"] = {**options, "table": Path(options["table"]).name}
    return out
