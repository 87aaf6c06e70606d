"""The mission viewer's diagnosis panel data (faults hidden): per frame, what the robot believed.

For a trace that records what the robot observed and believed after each step (trace version 2,
:mod:`selfrepair.execution.traceobserve`), :func:`diagnosis_json` gives the page, per frame
(frame 0 before any step, frame ``k`` after step ``k - 1``): the hypotheses and classes still
possible (counted from the recorded bit set with the header's classes), the most probable class
(its fault sets as text), whether the step surprised the robot and how many readings it got
(its own and its teammates'). The page only draws them: a strip of the hypotheses left per step
with the surprises marked, and the facts of the frame shown.
"""

from __future__ import annotations

from typing import Any

from selfrepair.execution.trace import Trace
from selfrepair.execution.traceobserve import header_classes

__all__ = ["MAX_CLASS_NAMES", "diagnosis_json"]

MAX_CLASS_NAMES = 4
"""Fault sets named for the most probable class (the rest counted)."""


def _class_text(names: list[str], members: list[int]) -> str:
    shown = [names[i] for i in members[:MAX_CLASS_NAMES] if 0 <= i < len(names)]
    more = len(members) - len(shown)
    return " | ".join(shown) + (f" (+{more})" if more > 0 else "")


def diagnosis_json(trace: Trace) -> dict[str, Any] | None:
    """The diagnosis panel's data of ``trace`` (see the module docstring); ``None`` for a trace
    that records no observation."""
    if not trace.observations:
        return None
    names, classes = header_classes(trace.header, trace.source)
    total = len(names)
    frames: list[dict[str, Any]] = [
        {"alive": total or None, "classes": len(classes) or None, "best": None,
         "surprise": False, "readings": 0}
    ]  # fmt: skip
    for seen in trace.observations:
        if seen is None:
            frames.append({"alive": None, "classes": None, "best": None, "surprise": False,
                           "readings": 0})  # fmt: skip
            continue
        alive = classes_left = best = None
        if seen.belief is not None:
            bits = seen.belief
            alive = bin(bits).count("1")
            classes_left = sum(1 for c in classes if any(bits >> i & 1 for i in c))
        if seen.best is not None and seen.best < len(classes):
            best = _class_text(names, classes[seen.best])
        frames.append({
            "alive": alive, "classes": classes_left, "best": best, "surprise": seen.surprise,
            "readings": 1 + len(seen.seen),
        })  # fmt: skip
    return {
        "hypotheses": total,
        "classes": len(classes),
        "believes": any(o is not None and o.belief is not None for o in trace.observations),
        "frames": frames,
    }
