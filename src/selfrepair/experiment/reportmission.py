"""The one mission an experiment report draws: found by key prefix (:func:`pick_mission`) or
chosen as a telling one (:func:`choose_mission`), run again from its stored configuration
(:func:`rerun_mission`; results are deterministic), and its trace, picture and animation
written (:func:`mission_files`)."""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING

from selfrepair.errors import InputError, SelfRepairError
from selfrepair.experiment.findings import Row
from selfrepair.experiment.keys import Mission

if TYPE_CHECKING:
    from selfrepair.execution.result import MissionResult

__all__ = ["choose_mission", "mission_files", "pick_mission", "rerun_mission"]


def pick_mission(rows: Sequence[Row], key_prefix: str, source: str) -> Row:
    """The row whose key starts with ``key_prefix``; none or several is an
    :class:`~selfrepair.errors.InputError` naming ``source`` (the results database)."""
    hits = [r for r in rows if key_prefix and str(r["key"]).startswith(key_prefix)]
    if len(hits) != 1:
        examples = ", ".join(str(r["key"])[:12] for r in hits[:3])
        raise InputError(
            f"expected the mission key prefix to match exactly one stored mission, {len(hits)} "
            f"match {key_prefix!r}" + (f" (e.g. {examples}); give more characters" if hits else ""),
            source=source,
        )
    return hits[0]


def choose_mission(rows: Sequence[Row]) -> Row:
    """A telling mission to draw: reached, repaired by the table at least once, on a small maze,
    preferring the hand-written table, a mission that also replanned, and many replacements."""

    def score(row: Row) -> tuple[object, ...]:
        replacements = int(row.get("replacements") or 0)
        replans = int(row.get("replans") or 0)
        width = int(row.get("maze_width") or 999)
        return (
            row.get("reached") == 1,
            replacements > 0,
            width <= 32,
            row.get("table") == "handwritten",
            replans > 0 and replacements > 0,
            Fraction(str(row.get("clearance_weight") or "0")) == 0,
            min(replacements, 12),
            -width,
            str(row["key"]),
        )

    return max(rows, key=score)


def rerun_mission(row: Row, source: str = "<results database>") -> MissionResult:
    """Run a stored mission again from its canonical configuration (results are deterministic,
    so this gives its steps and repairs; the timings are new). A configuration this version
    cannot run is an :class:`~selfrepair.errors.InputError` naming ``source``."""
    from selfrepair.execution.executor import run_mission
    from selfrepair.experiment.missions import to_spec

    mission = Mission(
        str(row["key"]), str(row["experiment"]), int(row["seed"] or 0), str(row["config"]), ()
    )
    try:
        spec = to_spec(mission)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, SelfRepairError):
            raise
        raise InputError(
            f"mission {mission.key[:12]!r}: its stored configuration cannot be run again "
            f"({type(exc).__name__}: {exc})",
            source=source,
        ) from None
    return run_mission(spec)


def mission_files(row: Row, out_dir: Path, source: str) -> list[Path]:
    """Run the chosen mission again, write its trace, picture and GIF."""
    from selfrepair.execution.trace import read_trace, write_trace
    from selfrepair.experiment import missionplot
    from selfrepair.experiment.animate import animate_trace

    result = rerun_mission(row, source)
    trace_path = out_dir / "mission.jsonl"
    write_trace(result, trace_path)
    picture = missionplot.picture_from_trace(read_trace(trace_path))
    png = missionplot.figure_mission(picture, out_dir / "mission.png")
    gif = out_dir / "mission.gif"
    animate_trace(trace_path, gif, max_frames=60)
    return [trace_path, png, gif]
