"""Which missions the compiled mission loop takes: the footings a mission may ask for, and why
the compiled loop cannot run a mission (one line) when it cannot.

:func:`runs_compiled` is asked by :func:`~selfrepair.execution.compiled.loop.compiled_loop`
before it runs a mission, and by the executor for the footing of a mission that ends before its
loop; :func:`refusal` is the one list of what runs in Python only.
"""

from __future__ import annotations

from selfrepair.errors import ProblemError
from selfrepair.execution.compiled import kernel as k
from selfrepair.execution.compiled.arrays import MAX_SCHEDULE_FAULTS
from selfrepair.execution.compiled.draws import MAX_SEED, MAX_WORD
from selfrepair.execution.faults import Detection, Persistence
from selfrepair.execution.result import MissionSpec
from selfrepair.execution.simulator import Simulator
from selfrepair.execution.stepper import Stepper
from selfrepair.repair.replacement import DEFERRING
from selfrepair.repair.strategies import StrategyName

__all__ = ["FOOTINGS", "refusal", "runs_compiled"]

FOOTINGS = ("auto", "compiled", "python")
"""What a mission's ``footing`` may ask for: the compiled loop where it can run (``auto``), the
compiled loop or an error (``compiled``), or the Python loop."""

_COMPILED = (StrategyName.REPLAN, StrategyName.REPLACEMENT, StrategyName.LOOKAHEAD)


def refusal(spec: MissionSpec, stepper: Stepper | None = None) -> str | None:
    """Why the compiled loop cannot run ``spec`` (one line), or ``None`` when it can."""
    if not k.NUMBA:
        return "numba is not installed (the 'fast' extra)"
    if spec.strategy not in _COMPILED:
        compiled = "replan, replacement, lookahead"
        return f"strategy {spec.strategy!s} runs in Python (compiled: {compiled})"
    if spec.strategy == StrategyName.LOOKAHEAD and spec.options.recursion in DEFERRING:
        mode = spec.options.recursion
        return f"lookahead's fallback in {mode!s} recursion defers actions (Python only)"
    if spec.objective is not None:
        return "a tolerant planning objective runs in Python"
    if stepper is not None and stepper.horizon and spec.strategy != StrategyName.LOOKAHEAD:
        return "a repair horizon runs in Python (compiled: lookahead's)"
    if spec.world:
        return "world events (a changing maze) run in Python"
    if spec.schedule.detection is Detection.HIDDEN:
        return "faults hidden from the robot (detection hidden) run in Python"
    events = spec.schedule.events
    if any(e.persistence is Persistence.INTERMITTENT for e in events) and (
        spec.seed > MAX_SEED or len(events) > MAX_WORD or spec.step_limit() > MAX_WORD
    ):
        return (
            f"intermittent faults run in Python with a seed above {MAX_SEED} or more than "
            f"{MAX_WORD} steps or events (the compiled draw takes 64-bit seeds, 32-bit steps)"
        )
    if len({e.fault for e in events}) > MAX_SCHEDULE_FAULTS:
        return f"more than {MAX_SCHEDULE_FAULTS} distinct faults in the schedule"
    if not spec.maze.in_bounds(spec.start.x, spec.start.y):
        return "the start lies off the maze"
    return None


def runs_compiled(spec: MissionSpec, sim: Simulator, stepper: Stepper) -> bool:
    """Whether the compiled loop runs ``spec`` with ``sim`` and ``stepper`` (for footing
    ``compiled`` a refusal raises :class:`ProblemError` with the reason)."""
    if spec.footing == "python":
        return False
    reason = refusal(spec, stepper)
    if reason is None and type(sim) is not Simulator:  # another world holds the truth (physics)
        reason = f"its simulator is a {type(sim).__name__}, not the lattice Simulator"
    if reason is not None and spec.footing == "compiled":
        raise ProblemError(f"footing 'compiled' cannot run this mission: {reason}")
    return reason is None
