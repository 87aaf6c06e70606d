"""Where replacement pays off: the maze size at which its repair compute falls below 1/10 of the
replanner's (the ``scale`` experiment, ``crossover = true``).

Per mission pair (the replacing robot met a fault and never replanned; the replanner in the same
situation), the ratio of repair compute per mission (every repair's time added up; the initial
plan, the same for both robots, left out). Per maze: the median ratio with its 95% bootstrap
interval. Across mazes: a least-squares line through ``log(ratio)`` against ``log(side)`` over
every pair (``side`` = the square root of the maze's cells), and the **crossover** side where
the line reaches :data:`~selfrepair.experiment.findings.NEGLIGIBLE` (0.1). Its 95% interval comes
from the same bootstrap: pairs are resampled within each maze, the line refitted, and the
crossover recomputed. When the fitted ratio does not fall with size, there is no crossover.

Also reported: the smallest measured side whose median's interval lies wholly below 0.1.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from selfrepair.experiment.summary import Row, is_reference_replan, met_fault, num
from selfrepair.experiment.verdicts import NEGLIGIBLE, situation
from selfrepair.stats import (
    BOOTSTRAP_RESAMPLES,
    BOOTSTRAP_SEED,
    LEVEL,
    Interval,
    bootstrap_interval,
)

__all__ = ["Crossover", "MazeRatio", "crossover", "maze_side"]


@dataclass(frozen=True, slots=True)
class MazeRatio:
    """One maze: its side, and the median paired ratio with its interval (``None``: no pair)."""

    maze: str
    side: float
    ratio: Interval | None


@dataclass(frozen=True, slots=True)
class Crossover:
    """The analysis: per-maze ratios, the fitted slope of log(ratio) on log(side), the crossover
    side with its 95% interval (``None`` when the ratio does not fall with size or the data are
    too few), and the smallest measured side whose interval lies below the threshold."""

    variant: str
    mazes: tuple[MazeRatio, ...]
    pairs: int
    slope: float | None
    intercept: float | None
    side: Interval | None
    first_below: float | None
    threshold: float = NEGLIGIBLE

    def lines(self) -> list[str]:
        """A short readable account, one sentence per line."""
        out = [f"{self.variant}: {self.pairs} pairs over {len(self.mazes)} mazes."]
        for m in self.mazes:
            text = "no pair" if m.ratio is None else f"{m.ratio.text(3)} ({m.ratio.n} pairs)"
            out.append(f"  side {m.side:.0f} ({m.maze}): repair compute ratio {text}")
        if self.slope is None:
            out.append("  Too few mazes with pairs to fit a line.")
        elif self.side is None:
            out.append(
                f"  The ratio does not fall with size (slope {self.slope:.2f} of log ratio on "
                f"log side): no crossover."
            )
        else:
            out.append(
                f"  Crossover (ratio {self.threshold:g}): a maze side of {self.side.text()} cells "
                f"(95% interval), slope {self.slope:.2f}."
            )
        if self.first_below is not None:
            out.append(
                f"  Smallest measured side wholly below {self.threshold:g}: {self.first_below:.0f}."
            )
        return out


def maze_side(row: Row) -> float:
    """The side of a square maze with the same number of cells."""
    return math.sqrt(num(row, "maze_width") * num(row, "maze_height"))


def _pairs(rows: Sequence[Row], variant: str) -> list[tuple[str, float, float]]:
    """``(maze, side, ratio)`` of every usable pair for ``variant``."""
    replan = {situation(r): r for r in rows if is_reference_replan(r)}
    out = []
    for r in rows:
        if r.get("variant") != variant or not met_fault(r) or num(r, "replans") > 0:
            continue
        p = replan.get(situation(r))
        if p is not None and num(p, "repair_compute_ns") > 0:
            ratio = num(r, "repair_compute_ns") / num(p, "repair_compute_ns")
            if ratio > 0:
                out.append((str(r.get("maze")), maze_side(r), ratio))
    return out


def crossover(rows: Sequence[Row], variant: str, threshold: float = NEGLIGIBLE) -> Crossover:
    """The analysis of the module docstring for one replacement ``variant``."""
    pairs = _pairs(rows, variant)
    by_maze: dict[tuple[float, str], list[float]] = defaultdict(list)
    for maze, side, ratio in pairs:
        by_maze[(side, maze)].append(ratio)
    mazes = tuple(
        MazeRatio(maze, side, bootstrap_interval(ratios))
        for (side, maze), ratios in sorted(by_maze.items())
    )
    below = [m.side for m in mazes if m.ratio is not None and m.ratio.high < threshold]
    first_below = min(below) if below else None
    if len({side for _, side, _ in pairs}) < 3:
        return Crossover(variant, mazes, len(pairs), None, None, None, first_below, threshold)
    x = np.log([side for _, side, _ in pairs])
    y = np.log([ratio for _, _, ratio in pairs])
    slope, intercept = _fit(x, y)
    at = _crossover_interval(x, y, by_maze, threshold, slope, intercept)
    return Crossover(variant, mazes, len(pairs), slope, intercept, at, first_below, threshold)


def _fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    slope, intercept = np.polyfit(x, y, 1)
    return float(slope), float(intercept)


def _at(threshold: float, slope: float, intercept: float) -> float | None:
    if slope >= 0:
        return None
    exponent = (math.log(threshold) - intercept) / slope
    return math.inf if exponent > MAX_EXPONENT else float(math.exp(exponent))


MAX_EXPONENT = 700.0
"""Beyond ``exp(700)`` a crossover side is infinite for every purpose (and overflows a float)."""


def _crossover_interval(
    x: np.ndarray,
    y: np.ndarray,
    by_maze: dict[tuple[float, str], list[float]],
    threshold: float,
    slope: float,
    intercept: float,
) -> Interval | None:
    """The crossover side and its percentile interval, resampling pairs within each maze."""
    estimate = _at(threshold, slope, intercept)
    if estimate is None or not math.isfinite(estimate):
        return None
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    groups = [(math.log(side), np.log(np.asarray(ratios))) for (side, _), ratios in by_maze.items()]
    found = []
    for _ in range(BOOTSTRAP_RESAMPLES // 4):
        xs, ys = [], []
        for lx, ly in groups:
            pick = ly[rng.integers(0, len(ly), len(ly))]
            xs.append(np.full(len(ly), lx))
            ys.append(pick)
        s, c = _fit(np.concatenate(xs), np.concatenate(ys))
        at = _at(threshold, s, c)
        found.append(math.inf if at is None else at)
    tail = (1 - LEVEL) / 2
    # no interpolation: an infinite crossover (the line does not fall) is a value, not a nan
    low, high = np.quantile(np.asarray(found), [tail, 1 - tail], method="inverted_cdf")
    return Interval(estimate, min(float(low), estimate), max(float(high), estimate), len(x))
