"""Execution: fault schedules, the simulator (which holds the true faults), the fault-tolerant
executor, mission results and metrics, and JSON Lines traces with their replay.

A mission flows down this package as values: a :class:`~selfrepair.execution.result.MissionSpec`
goes in, a :class:`~selfrepair.execution.result.MissionResult` comes out, and rows and traces are
built from it. It may import ``repair``, ``tables``, ``search``, ``world``, ``robots`` and the
ground modules, never ``experiment`` or ``cli``. Importing it imports :mod:`selfrepair.baselines`,
so that every robot strategy the package ships is in the registry wherever missions run.
"""

import selfrepair.baselines  # noqa: F401  (registers lpg-adapt with the strategies)

__all__: list[str] = []
