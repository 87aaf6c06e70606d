"""The compiled mission loop: a whole mission in one numba kernel over integer arrays, so that
replacement and replanning are compared on equal footing (both compiled), next to the Python
loop that stays the reference (see :mod:`selfrepair.execution.compiled.kernel` for the kernel,
:mod:`selfrepair.execution.compiled.arrays` for the arrays, and
:mod:`selfrepair.execution.compiled.driver` for which missions it takes).
"""

from __future__ import annotations

from selfrepair.execution.compiled.driver import (
    FOOTINGS,
    LoopEnd,
    compiled_loop,
    refusal,
    runs_compiled,
)

__all__ = ["FOOTINGS", "LoopEnd", "compiled_loop", "refusal", "runs_compiled"]
