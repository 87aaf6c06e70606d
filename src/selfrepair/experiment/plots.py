"""Figures of the experiment report over result rows (matplotlib, PNG; needs the ``viz`` extra).

Functions take result rows (dicts from the store) and a path, and return the path written. Their
look (palette, step colours, style) is :mod:`selfrepair.experiment.figstyle`; the drawing of one
mission is :mod:`selfrepair.experiment.missionplot`.
"""

from __future__ import annotations

import math
from collections import defaultdict
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from selfrepair.experiment.figstyle import OKABE_ITO, colour_of, figure, save
from selfrepair.experiment.findings import (
    NEGLIGIBLE,
    Row,
    group_label,
    repairs_of,
)
from selfrepair.experiment.scale import Crossover
from selfrepair.experiment.summary import is_reference_replan
from selfrepair.optional import matplotlib
from selfrepair.repair.strategies import RepairSource, StrategyName
from selfrepair.stats import lower_median, percentile

if TYPE_CHECKING:
    import numpy.typing as npt
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "figure_baselines",
    "figure_clearance",
    "figure_crossover",
    "figure_heatmap",
    "figure_latency",
    "figure_latency_vs_size",
    "heatmap_variant",
]


def _weight(row: Row) -> Fraction:
    return Fraction(str(row.get("clearance_weight") or "0"))


# --- latency -----------------------------------------------------------------------------------


def figure_latency(rows: Sequence[Row], path: Path) -> Path:
    """Repair latency distributions per strategy variant (weight 0), horizontal box plots on a
    log scale; whiskers at the 1st and 99th percentiles; table hits and replans of the
    replacement variants are shown as separate boxes."""
    groups: dict[str, list[float]] = defaultdict(list)
    for row in rows:
        if _weight(row) != 0:
            continue
        label = group_label(row)
        for source, latency in repairs_of(row):
            key = label if row.get("strategy") == StrategyName.REPLAN else f"{label}: {source}"
            groups[key].append(latency / 1000)
    labels = sorted(groups, key=lambda k: lower_median(groups[k]) if groups[k] else 0)
    with figure(9.5, 1.2 + 0.42 * max(1, len(labels))) as (fig, (ax,)):
        if not labels:
            ax.text(0.5, 0.5, "no repairs in these results", ha="center", transform=ax.transAxes)
        else:
            data = [groups[k] for k in labels]
            box = ax.boxplot(
                data,
                orientation="horizontal",
                whis=(1, 99),
                showfliers=False,
                patch_artist=True,
                medianprops={"color": "#111111", "linewidth": 1.5},
            )
            for patch, label in zip(box["boxes"], labels, strict=True):
                source = label.rsplit(": ", 1)[-1] if ": " in label else RepairSource.REPLAN
                patch.set_facecolor(colour_of(source, "#999999"))
                patch.set_alpha(0.8)
            ax.set_yticks(range(1, len(labels) + 1), [f"{k} (n={len(groups[k])})" for k in labels])
            ax.set_xscale("log")
            ax.set_xlabel("repair latency (µs, log scale)")
        fig.suptitle(
            "Repair latency per strategy and repair kind, clearance weight 0\n"
            "box: quartiles and median; whiskers: 1st to 99th percentile",
            fontsize=11,
        )
        return save(fig, path)


def figure_latency_vs_size(rows: Sequence[Row], path: Path) -> Path:
    """Median repair latency (with the 99th percentile as a bar) against maze size, for replans
    of the replanning robot and table hits of the replacing robot."""
    series: dict[str, dict[int, list[float]]] = {
        "replan (replanning robot)": defaultdict(list),
        "table hit (replacing robot)": defaultdict(list),
    }
    names: dict[int, set[str]] = defaultdict(set)
    for row in rows:
        if _weight(row) != 0:
            continue
        cells = row.get("maze_free_cells")
        if not isinstance(cells, int):
            continue
        for source, latency in repairs_of(row):
            if is_reference_replan(row) and source == RepairSource.REPLAN:
                series["replan (replanning robot)"][cells].append(latency / 1000)
            elif (
                row.get("strategy") == StrategyName.REPLACEMENT
                and source == RepairSource.REPLACEMENT
            ):
                series["table hit (replacing robot)"][cells].append(latency / 1000)
            else:
                continue
            names[cells].add(str(row.get("maze")))
    with figure(7.0, 4.8) as (fig, (ax,)):
        for (label, by_size), colour in zip(series.items(), ("#E69F00", "#009E73"), strict=True):
            sizes = sorted(by_size)
            if not sizes:
                continue
            med = np.array([lower_median(by_size[s]) for s in sizes], dtype=float)
            p99 = np.array([percentile(by_size[s], 0.99) for s in sizes], dtype=float)
            ax.errorbar(
                sizes,
                med,
                yerr=[np.zeros_like(med), p99 - med],
                marker="o",
                color=colour,
                capsize=4,
                label=f"{label}: median, bar to p99",
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("maze size (free cells, log scale)")
        ax.set_ylabel("repair latency (µs, log scale)")
        sizes = sorted(names)
        ax.set_xticks(sizes, [f"{c}\n" + "\n".join(sorted(names[c])) for c in sizes], fontsize=8)
        ax.minorticks_off()
        if sizes:
            ax.set_xlim(sizes[0] / 1.4, sizes[-1] * 1.4)
        ax.set_title("How repair latency grows with maze size")
        if ax.get_legend_handles_labels()[0]:
            fig.legend(loc="outside lower center", fontsize=8, ncols=2)
        return save(fig, path)


# --- clearance -----------------------------------------------------------------------------------


def figure_clearance(rows: Sequence[Row], path: Path) -> Path | None:
    """Share of faulty encounters resolved by replacement, and mean extra ticks, against the
    clearance weight, one line per table and recursion mode. ``None`` (nothing written) when no
    replacement variant ran at two weights or more: there would be nothing to draw."""
    groups: dict[str, dict[Fraction, list[Row]]] = defaultdict(lambda: defaultdict(list))
    for row in rows:
        if row.get("strategy") == StrategyName.REPLACEMENT:
            groups[str(row.get("variant"))][_weight(row)].append(row)
    groups = {k: v for k, v in groups.items() if len(v) > 1}
    if not groups:
        return None
    with figure(10.0, 4.0, ncols=2) as (fig, (left, right)):
        weights = sorted({w for g in groups.values() for w in g})
        positions = {w: i for i, w in enumerate(weights)}
        for (label, by_weight), colour in zip(sorted(groups.items()), OKABE_ITO, strict=False):
            ws = sorted(by_weight)
            xs = [positions[w] for w in ws]
            shares, extra = [], []
            for w in ws:
                enc = sum(float(r.get("faulty_encounters") or 0) for r in by_weight[w])
                rep = sum(float(r.get("replacements") or 0) for r in by_weight[w])
                shares.append(100 * rep / enc if enc else math.nan)
                ticks = [
                    float(v)
                    for r in by_weight[w]
                    if isinstance(v := r.get("extra_ticks"), int | float)
                ]
                extra.append(sum(ticks) / len(ticks) if ticks else math.nan)
            left.plot(xs, shares, marker="o", color=colour, label=label)
            right.plot(xs, extra, marker="o", color=colour, label=label)
        for ax in (left, right):
            ax.set_xticks(range(len(weights)), [str(w) for w in weights])
            ax.set_xlabel("clearance weight")
        left.set_ylabel("encounters resolved by replacement (%)")
        left.set_title("Replacement success vs clearance weight")
        right.set_ylabel("mean extra ticks vs fault-free plan")
        right.set_title("Price paid in execution time")
        # Below the axes, never on top of a data point.
        fig.legend(*left.get_legend_handles_labels(), loc="outside lower center", ncols=2)
        return save(fig, path)


# --- heat map ----------------------------------------------------------------------------------


def heatmap_variant(rows: Sequence[Row]) -> str | None:
    """The variant drawn in the heat map: the hand-written table without recursion if present,
    else the first replacement variant, else the first variant (all at weight 0)."""
    variants = sorted({str(r.get("variant")) for r in rows if _weight(r) == 0})
    for wanted in ("replacement[handwritten,flat]", "replacement[handwritten,guarded]"):
        if wanted in variants:
            return wanted
    replacing = [v for v in variants if v.startswith(StrategyName.REPLACEMENT)]
    chosen = replacing or variants
    return chosen[0] if chosen else None


def figure_heatmap(rows: Sequence[Row], path: Path, variant: str | None = None) -> Path:
    """Fault set x maze: share of encounters resolved locally and mean extra ticks."""
    variant = variant or heatmap_variant(rows)
    chosen = [r for r in rows if str(r.get("variant")) == variant and _weight(r) == 0]
    mazes = sorted({str(r.get("maze")) for r in chosen}, key=lambda m: (_first_int(chosen, m), m))
    sizes = {str(r.get("faults")): int(str(r.get("fault_count") or 0)) for r in chosen}
    faults = sorted(sizes, key=lambda f: (sizes[f], f))  # singles first: the robot's count
    share = np.full((len(faults), len(mazes)), np.nan)
    extra = np.full((len(faults), len(mazes)), np.nan)
    for i, f in enumerate(faults):
        for j, m in enumerate(mazes):
            cell = [r for r in chosen if r.get("faults") == f and r.get("maze") == m]
            enc = sum(float(r.get("faulty_encounters") or 0) for r in cell)
            res = sum(
                float(r.get("replacements") or 0) + float(r.get("lookaheads") or 0) for r in cell
            )
            if enc:
                share[i, j] = 100 * res / enc
            ticks = [float(v) for r in cell if isinstance(v := r.get("extra_ticks"), int | float)]
            if ticks:
                extra[i, j] = sum(ticks) / len(ticks)
    numbers = len(faults) <= HEATMAP_NUMBERED_ROWS
    row_height = 0.32 if numbers else 0.13
    with figure(
        3.0 + 1.35 * max(2, len(mazes)) * 2, 1.6 + row_height * max(4, len(faults)), ncols=2
    ) as (fig, (left, right)):
        _heat(
            fig,
            left,
            share,
            faults,
            mazes,
            "encounters resolved locally (%)",
            "viridis",
            (0, 100),
            "{:.0f}" if numbers else None,
        )
        _heat(
            fig,
            right,
            extra,
            faults,
            mazes,
            "mean extra ticks vs fault-free plan",
            "magma_r",
            None,
            "{:.1f}" if numbers else None,
        )
        right.set_yticks(range(len(faults)), [""] * len(faults))
        fig.suptitle(f"{variant}, clearance weight 0 (grey: no faulty encounter)")
        return save(fig, path)


HEATMAP_NUMBERED_ROWS = 30
"""Up to this many fault sets the heat map prints each cell's value; with more (the 78 fault sets
of the full study) the rows are drawn thinner, with smaller labels and colour alone, so the
figure stays a readable size."""


def _first_int(rows: Sequence[Row], maze: str) -> int:
    for r in rows:
        if r.get("maze") == maze and isinstance(v := r.get("maze_free_cells"), int):
            return v
    return 0


def _heat(
    fig: Figure,
    ax: Axes,
    data: npt.NDArray[np.float64],
    faults: list[str],
    mazes: list[str],
    label: str,
    cmap_name: str,
    limits: tuple[float, float] | None,
    fmt: str | None,
) -> None:
    mpl = matplotlib()
    cmap = mpl.colormaps[cmap_name].with_extremes(bad="#cccccc")
    finite = data[np.isfinite(data)]
    lo, hi = (
        limits
        if limits
        else ((float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0))
    )
    if hi <= lo:
        hi = lo + 1
    image = ax.imshow(np.ma.masked_invalid(data), cmap=cmap, vmin=lo, vmax=hi, aspect="auto")
    ax.grid(False)
    ax.set_xticks(range(len(mazes)), mazes, rotation=20, ha="right")
    ax.set_yticks(range(len(faults)), faults, fontsize=None if fmt is not None else 6)
    fig.colorbar(image, ax=ax, label=label, shrink=0.9)
    if fmt is None:
        return
    for (i, j), value in np.ndenumerate(data):
        if math.isfinite(value):
            r, g, b, _ = cmap((value - lo) / (hi - lo))
            light = 0.299 * r + 0.587 * g + 0.114 * b > 0.5
            ax.text(
                j,
                i,
                fmt.format(value),
                ha="center",
                va="center",
                fontsize=7,
                color="#111111" if light else "white",
            )
        else:
            ax.text(j, i, "-", ha="center", va="center", fontsize=7, color="#555555")


def figure_crossover(results: Sequence[Crossover], path: Path) -> Path:
    """Per maze, the median paired ratio of repair compute (replacing / replanning robot) with its
    95% interval against the maze side, log-log; the fitted line, the 1/10 threshold and the
    crossover side with its interval, one colour per replacement variant."""
    colours = ("#009E73", "#0072B2", "#D55E00", "#CC79A7", "#E69F00")
    with figure(7.0, 4.8) as (fig, (ax,)):
        sides: list[float] = []
        for result, colour in zip(results, colours, strict=False):
            points = [m for m in result.mazes if m.ratio is not None]
            if not points:
                continue
            x = np.array([m.side for m in points])
            mid = np.array([m.ratio.estimate for m in points if m.ratio is not None])
            low = np.array([m.ratio.low for m in points if m.ratio is not None])
            high = np.array([m.ratio.high for m in points if m.ratio is not None])
            sides += list(x)
            ax.errorbar(
                x,
                mid,
                yerr=[mid - low, high - mid],
                fmt="o",
                color=colour,
                capsize=3,
                label=f"{result.variant}: median ratio, 95% interval",
            )
            if result.slope is not None and result.intercept is not None:
                ends = [min(x), max(x)]
                if result.side is not None and math.isfinite(result.side.estimate):
                    ends[1] = max(ends[1], result.side.estimate)
                line = np.geomspace(ends[0], ends[1], 50)
                ax.plot(line, np.exp(result.intercept) * line**result.slope, color=colour, lw=1)
            if result.side is not None and math.isfinite(result.side.estimate):
                ax.axvline(result.side.estimate, color=colour, ls="--", lw=1)
                if math.isfinite(result.side.high):
                    ax.axvspan(result.side.low, result.side.high, color=colour, alpha=0.12)
                sides.append(result.side.estimate)
        ax.axhline(NEGLIGIBLE, color="#333333", ls=":", lw=1, label=f"1/10 ({NEGLIGIBLE:g})")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("maze side (square root of the cells, log scale)")
        ax.set_ylabel("repair compute per mission, replacing / replanning")
        ax.set_title("Where replacement's repair compute falls below 1/10 of replanning")
        if ax.get_legend_handles_labels()[0]:
            fig.legend(loc="outside lower center", fontsize=8, ncols=1)
        return save(fig, path)


# --- baselines -----------------------------------------------------------------------------------


def figure_baselines(rows: Sequence[Row], path: Path) -> Path:
    """Repair latency at the first faulty action (left) and repair time per mission (right) by
    strategy variant and maze (mazes by size, left to right): median with its 95% bootstrap
    interval, log scale (:func:`comparison.per_maze`)."""
    from selfrepair.experiment.comparison import FIRST_REPAIR, REPAIR_COMPUTE, per_maze

    panels = (
        (per_maze(rows, FIRST_REPAIR), "first repair latency (ms, log scale)"),
        (per_maze(rows, REPAIR_COMPUTE), "repair time per mission (ms, log scale)"),
    )
    labels = list(dict.fromkeys(m.label for cells, _ in panels for m in cells))
    markers = "osD^v<>Ph"
    colours = [c for c in OKABE_ITO if c != "#F0E442"] + ["#999999"]  # yellow is too pale
    with figure(12.0, 5.0, ncols=2) as (fig, axes):
        for ax, (cells, ylabel) in zip(axes, panels, strict=True):
            mazes = list(dict.fromkeys((m.maze, m.free_cells) for m in cells))
            position = {maze: i for i, (maze, _) in enumerate(mazes)}
            width = 0.7 / max(1, len(labels))
            for k, label in enumerate(labels):
                mine = [m for m in cells if m.label == label]
                if not mine:
                    continue
                x = [position[m.maze] - 0.35 + width * (k + 0.5) for m in mine]
                mid = np.array([m.ms.estimate for m in mine])
                low = np.array([m.ms.low for m in mine])
                high = np.array([m.ms.high for m in mine])
                ax.errorbar(
                    x,
                    mid,
                    yerr=[mid - low, high - mid],
                    fmt=markers[k % len(markers)],
                    color=colours[k % len(colours)],
                    capsize=3,
                    label=label if ax is axes[0] else None,
                )
            ax.set_yscale("log")
            ax.set_xticks(range(len(mazes)), [f"{maze}\n{free} free cells" for maze, free in mazes])
            ax.set_ylabel(ylabel)
        fig.suptitle(
            "Repair latency by strategy and maze size: median and 95% bootstrap interval "
            "over missions that met a fault"
        )
        if labels:
            fig.legend(loc="outside lower center", fontsize=8, ncols=3)
        else:
            axes[0].text(0.5, 0.5, "no repairs", ha="center", transform=axes[0].transAxes)
        return save(fig, path)
