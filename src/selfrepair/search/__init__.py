"""Search: a generic A* core, the exact planner on a robot's pose lattice (for any domain), the
MovingAI grid planner, and their compiled numba kernels.

Planning problems and results are plain values (:mod:`selfrepair.search.problem`); the kernels
import only those, and the planners choose the backend (:mod:`selfrepair.search.backend`). This
package may import ``world``, ``robots``, :mod:`selfrepair.geometry` and :mod:`selfrepair.errors`.
"""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
