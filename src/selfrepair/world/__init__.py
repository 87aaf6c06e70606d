"""The world the robot drives in: mazes, their file formats, the generator, routes and pictures.

Holds :class:`~selfrepair.world.maze.Maze` (plain-text format and clearance map), MovingAI ``.map``
and ``.scen`` readers, the seeded maze generator, routes (a start pose and a goal cell), text
rendering and the mazes bundled with the package. It may import only :mod:`selfrepair.errors` and
:mod:`selfrepair.geometry`: it knows nothing of robots, planners or tables.
"""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
