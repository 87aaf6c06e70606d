"""Repair: run-time replacement (validity, recursion modes), the repair strategies that an executor
calls when the next action is faulty, and the evaluation of tables (coverage and optimality).

Domain-generic: it takes domains, tables and a free-cell test as values, and gets planning from the
executor as a function, so it imports ``tables``, ``robots.domain``/``robots.registry`` and the
search result values, never a concrete robot and never ``world``.
"""

import selfrepair.repair.dstar_lite  # noqa: F401  (registers dstar-lite)

__all__: list[str] = []
