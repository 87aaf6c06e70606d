"""Baselines that repair or replan with tools from neighbouring fields: the robot's planning problem
exported as PDDL (:mod:`selfrepair.baselines.pddl`) and plan repair with LPG-adapt through
unified-planning (:mod:`selfrepair.baselines.lpg`). This package sits above ``repair`` and below
``execution``; it may import ``repair``, ``tables``, ``search``, ``world``, ``robots``,
:mod:`selfrepair.geometry` and :mod:`selfrepair.errors`, never ``execution``, ``experiment`` or
``cli``. The PDDL export needs nothing beyond the core dependencies; the LPG call needs the ``pddl``
extra (``pip install 'selfrepair[pddl]'``).

Importing the package registers the ``lpg-adapt`` strategy (:mod:`selfrepair.baselines.adapt`;
the extra is needed only to start it).
"""

import selfrepair.baselines.adapt  # noqa: F401  (registers lpg-adapt)

__all__: list[str] = []
