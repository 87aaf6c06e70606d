"""Strategy variants of an experiment: the options each strategy entry is crossed over.

A replacement strategy entry crosses tables, recursion modes, lookahead windows and ``before``
lengths, and whole-plan rewriting; other strategies have one variant. Each variant is the
``{"strategy": ..., "options": ...}`` part of a mission's canonical configuration; options at
their default are left out, so that the keys of missions made before an option existed stay
valid. Table files enter by path and content hash and are loaded once with the default limits,
so a bad table stops the experiment before its sweep.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Iterator, Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

from selfrepair.errors import ConfigError, LimitError
from selfrepair.experiment.schema import (
    DiagnosisStrategy,
    DStarLiteStrategy,
    ExperimentConfig,
    LookaheadStrategy,
    LpgAdaptStrategy,
    ReplacementStrategy,
    ReplanStrategy,
    StrategyConfig,
)
from selfrepair.limits import DEFAULT_CONFIDENCE, DEFAULT_FAULT_PRIOR, DEFAULT_MAX_FAULTS
from selfrepair.repair.tolerance import OPTIMAL
from selfrepair.textio import JSONObject

__all__ = [
    "BUNDLED_TABLES",
    "REWRITE_LABEL",
    "left_out",
    "maze_filter",
    "objective_label",
    "short_table",
    "strategy_variants",
    "variant_count",
    "variant_label",
    "variants_of",
]

BUNDLED_TABLES = ("handwritten", "generated-agnostic", "generated-indexed")
"""Table names resolved from package data; anything else is a path to a table file."""

REWRITE_LABEL = "rewrite"
"""The part of a variant label that marks whole-plan rewriting, e.g.
``replacement[handwritten,guarded,rewrite]``."""


def strategy_variants(config: ExperimentConfig) -> Iterator[tuple[dict[str, Any], tuple[str, ...]]]:
    """Every (strategy settings, clearance weights) pair the config asks for."""
    for strategy in config.strategies:
        yield from variants_of(strategy, config)


def left_out(config: ExperimentConfig) -> tuple[tuple[str, str], ...]:
    """The optional strategy entries that cannot run here, as ``(name, reason)``."""
    return tuple(
        (str(s.name), s.refusal)
        for s in config.strategies
        if isinstance(s, LpgAdaptStrategy) and s.refusal is not None
    )


def variants_of(
    strategy: StrategyConfig, config: ExperimentConfig
) -> Iterator[tuple[dict[str, Any], tuple[str, ...]]]:
    """The (strategy settings, clearance weights) pairs of one strategy entry (none for an
    optional entry that cannot run here: :func:`left_out`)."""
    if isinstance(strategy, LpgAdaptStrategy) and strategy.refusal is not None:
        return
    weights = strategy.clearance_weights or config.planner.clearance_weights
    if isinstance(strategy, ReplacementStrategy):
        windows: tuple[tuple[int | None, int], ...] = (
            tuple((w, b) for w in strategy.window for b in strategy.before)
            if isinstance(strategy, LookaheadStrategy)
            else ((None, 0),)
        )
        for table in strategy.tables:
            for recursion in strategy.recursion:
                for window, before in windows:
                    for rewrite in strategy.rewrite:
                        for objective in strategy.objectives:
                            options: JSONObject = {
                                **_table_identity(table, config),
                                "recursion": recursion,
                            }
                            if window is not None:
                                options["window"] = window
                            if before:  # absent when 0, so older mission keys stay valid
                                options["before"] = before
                            if rewrite:  # absent when false, so older mission keys stay valid
                                options["rewrite"] = True
                            if objective != OPTIMAL:  # absent when optimal, likewise
                                options["objective"] = objective
                            yield {"strategy": strategy.name, "options": options}, weights
    elif isinstance(strategy, DiagnosisStrategy):
        for table in strategy.tables:
            for recursion in strategy.recursion:
                options = {**_table_identity(table, config), "recursion": recursion}
                for key, default in _DIAGNOSIS_DEFAULTS:
                    if getattr(strategy, key) != default:  # defaults left out (stable keys)
                        options[key] = getattr(strategy, key)
                yield {"strategy": strategy.name, "options": options}, weights
    else:
        yield {"strategy": strategy.name, "options": _plain_options(strategy)}, weights


_DIAGNOSIS_DEFAULTS = (
    ("max_faults", DEFAULT_MAX_FAULTS),
    ("fault_prior", DEFAULT_FAULT_PRIOR),
    ("confidence", DEFAULT_CONFIDENCE),
)
"""The diagnosis options of a strategy entry and their defaults (as ``StrategyOptions``)."""


def variant_count(strategy: StrategyConfig, config: ExperimentConfig) -> int:
    """How many (variant, clearance weight) pairs :func:`variants_of` gives, by arithmetic
    (without reading any table file)."""
    if isinstance(strategy, LpgAdaptStrategy) and strategy.refusal is not None:
        return 0
    weights = len(strategy.clearance_weights or config.planner.clearance_weights)
    if isinstance(strategy, DiagnosisStrategy):
        return len(strategy.tables) * len(strategy.recursion) * weights
    if not isinstance(strategy, ReplacementStrategy):
        return weights
    windows = (
        len(strategy.window) * len(strategy.before)
        if isinstance(strategy, LookaheadStrategy)
        else 1
    )
    return (
        len(strategy.tables)
        * len(strategy.recursion)
        * windows
        * len(strategy.rewrite)
        * len(strategy.objectives)
        * weights
    )


def maze_filter(
    strategy: StrategyConfig, index: int, labels: Sequence[str], source: str
) -> frozenset[str] | None:
    """The maze labels strategy ``index`` is limited to (``None``: all), each checked to name a
    maze of the experiment."""
    if strategy.mazes is None:
        return None
    for name in strategy.mazes:
        if name not in labels:
            raise ConfigError(
                f"key 'strategies[{index}].mazes': expected names of this experiment's mazes "
                f"({', '.join(dict.fromkeys(labels))}), got {name!r}",
                source=source,
            )
    return frozenset(strategy.mazes)


def _plain_options(strategy: StrategyConfig) -> JSONObject:
    """The options of a strategy without a table, as its missions record them (defaults left
    out, so that the keys of missions made before an option existed stay valid)."""
    if isinstance(strategy, ReplanStrategy | DStarLiteStrategy) and strategy.backend != "auto":
        return {"backend": strategy.backend}
    if isinstance(strategy, LpgAdaptStrategy):
        return {"lpg_time_limit_s": strategy.time_limit, "lpg_seed": strategy.seed}
    return {}


def _table_identity(table: str, config: ExperimentConfig) -> dict[str, str]:
    """A bundled table by name; a table file by its absolute path (to load it) and the SHA-256
    of its content (so editing the file gives its missions new keys)."""
    if table in BUNDLED_TABLES:
        return {"table": table}
    path = (config.base_dir / table).resolve()
    if not path.is_file():
        raise ConfigError(
            f"key 'strategies[].tables': expected one of {', '.join(BUNDLED_TABLES)} or a "
            f"readable table file, got {table!r}",
            source=config.source,
        )
    _check_table(path)
    try:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as exc:
        raise ConfigError(
            f"key 'strategies[].tables': cannot read table file {table!r}: {exc.strerror}",
            source=config.source,
        ) from None
    return {"table": str(path), "table_sha256": digest}


def _check_table(path: Path) -> None:
    """Load a table file once, with the default limits, so that a bad or oversized table stops
    the experiment before its sweep (the workers load it again, with the same limits)."""
    from selfrepair.tables.fileformat import load_table

    try:
        load_table(path)
    except LimitError as exc:
        raise LimitError(
            exc.message,
            limit=exc.limit,
            note="experiment workers load tables with the default limits, not raised by flags",
            source=exc.source,
            line=exc.line,
        ) from None


def short_table(table: object) -> str | None:
    """A table's readable name: a bundled name, or a table file's stem."""
    if table is None:
        return None
    return table if table in BUNDLED_TABLES else Path(str(table)).stem


_LABEL_PARTS: tuple[tuple[str, bool, Callable[[object], str]], ...] = (
    ("table", True, lambda table: str(short_table(table))),
    ("recursion", True, str),
    ("window", True, "k={}".format),
    ("before", False, "before={}".format),
    ("backend", True, str),
    ("lpg_time_limit_s", True, "{:g}s".format),
    ("lpg_seed", False, "seed={}".format),
    ("rewrite", False, lambda _: REWRITE_LABEL),
    ("objective", False, str),
)
"""The parts of a variant label, in order: the option, whether it shows whenever it is given
(``True``) or only when it is set (not 0, false or empty), and how it reads."""


def variant_label(strategy: str, options: dict[str, Any]) -> str:
    """A short readable strategy variant, e.g. ``replacement[handwritten,guarded]``."""
    if not options:
        return strategy
    parts = [
        show(options[key])
        for key, whenever_given, show in _LABEL_PARTS
        if (key in options if whenever_given else options.get(key))
    ]
    return f"{strategy}[{','.join(parts)}]"


def objective_label(options: dict[str, Any], weight: str) -> str:
    """The ``objective`` column: ``optimal``, ``clearance W``, ``tolerant k=K``, ``tolerant soft
    L k=K`` (with ``, clearance W`` when a tolerant objective also has a weight)."""
    clearance = "" if Fraction(weight) == 0 else f"clearance {weight}"
    tolerant = str(options.get("objective") or "")
    if not tolerant:
        return clearance or OPTIMAL
    return f"{tolerant}, {clearance}" if clearance else tolerant
