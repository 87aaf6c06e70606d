"""The compiled mission loop: a whole mission in one numba kernel over integer arrays, so that
replacement and replanning are compared on equal footing (both compiled), next to the Python
loop that stays the reference (see :mod:`selfrepair.execution.compiled.kernel` for the kernel,
:mod:`selfrepair.execution.compiled.arrays` for the arrays,
:mod:`selfrepair.execution.compiled.footing` for which missions it takes,
:mod:`selfrepair.execution.compiled.driver` for one mission's arrays and the kernel's exits, and
:mod:`selfrepair.execution.compiled.loop` for the entry and what it leaves behind).
"""

from __future__ import annotations

from selfrepair.execution.compiled.footing import FOOTINGS, refusal, runs_compiled
from selfrepair.execution.compiled.loop import LoopEnd, compiled_loop

__all__ = ["FOOTINGS", "LoopEnd", "compiled_loop", "refusal", "runs_compiled"]
