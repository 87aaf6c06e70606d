"""The look of every figure: palette, step colours by source, matplotlib style, figure and save.

Every figure is drawn with matplotlib's object API (no pyplot state, no GUI backend) on an
explicitly white background with dark text, so it reads the same in light and dark viewers.
Colours come from the Okabe-Ito palette, which stays distinguishable for colour-blind readers.
matplotlib is imported only when a figure is made (:func:`figure`), so the HTML viewer can read
:data:`SOURCE_COLOURS` without it.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

from selfrepair.execution.result import StepSource
from selfrepair.optional import matplotlib

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt
    from matplotlib.figure import Figure

__all__ = ["OKABE_ITO", "SOURCE_COLOURS", "STYLE", "WALL", "colour_of", "figure", "save"]

OKABE_ITO = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#F0E442", "#000000")
"""The Okabe-Ito palette (colour-blind safe)."""

SOURCE_COLOURS: Mapping[StepSource, str] = MappingProxyType(
    {
        StepSource.PLAN: "#0072B2",
        StepSource.REPLACEMENT: "#009E73",
        StepSource.LOOKAHEAD: "#CC79A7",
        StepSource.REPLAN: "#E69F00",
        StepSource.PLAN_REPAIR: "#56B4E9",
        StepSource.FAILED_ATTEMPT: "#D55E00",
        StepSource.WAIT: "#F0E442",
        StepSource.BUMPED: "#000000",
        StepSource.PROBE: "#999999",
        StepSource.DETOUR: "#8C564B",
    }
)
"""Step colours by source, in every figure, animation and the HTML viewer. A repair's source
(:class:`~selfrepair.repair.strategies.RepairSource`) has the colour of the steps it made, as
both enums share their values."""


def colour_of(source: str, default: str) -> str:
    """The colour of ``source``, a step source or a repair source as written in a trace or a
    row (both enums share their values), or ``default`` for anything else (``"failed"``)."""
    try:
        return SOURCE_COLOURS[StepSource(source)]
    except ValueError:
        return default


WALL = "#3b3b3b"
"""The colour of maze walls."""

STYLE = {
    "figure.facecolor": "white",
    "axes.facecolor": "white",
    "savefig.facecolor": "white",
    "savefig.edgecolor": "white",
    "text.color": "#111111",
    "axes.labelcolor": "#111111",
    "axes.edgecolor": "#333333",
    "xtick.color": "#111111",
    "ytick.color": "#111111",
    "axes.grid": True,
    "grid.color": "#d9d9d9",
    "grid.linewidth": 0.6,
    "font.size": 10,
    "axes.titlesize": 11,
    "legend.framealpha": 1.0,
    "legend.facecolor": "white",
}


"""matplotlib rc settings of every figure: white background, dark text."""


@contextmanager
def figure(
    width: float, height: float, ncols: int = 1
) -> Iterator[tuple[Figure, npt.NDArray[np.object_]]]:
    """A white figure with ``ncols`` axes in the report's style."""
    mpl = matplotlib()
    from matplotlib.figure import Figure

    with mpl.rc_context(STYLE):
        fig = Figure(figsize=(width, height), dpi=110, layout="constrained")
        axes = fig.subplots(1, ncols, squeeze=False)[0]
        yield fig, axes


def save(fig: Figure, path: Path) -> Path:
    """Write ``fig`` as a PNG on white to ``path``; returns ``path``."""
    fig.savefig(path, format="png", facecolor="white", transparent=False)
    return path
