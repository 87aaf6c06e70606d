"""The four-wheel robot as MuJoCo drives it: the domain identified from physics, as a plug-in.

``selfrepair physics fidelity --write-domain FILE`` measures every action in physics and writes
the actions whose end pose snaps to the lattice (the others are dropped, with why); this file
registers the bundled result (written with the default parameters) as the domain
``four-wheel-physics``, and its 65 actions that physics confirms as ``four-wheel-confirmed``,
so that tables, missions and experiments use them like any robot:

    selfrepair --plugin examples/physics/robot.py table generate --domain four-wheel-physics \
        -o table.json

Needs no MuJoCo: the identified motions are plain data (see docs/physics.md).
"""

from selfrepair.physics.identified import CONFIRMED_NAME, load_identified
from selfrepair.robots.registry import register_domain

FOUR_WHEEL_PHYSICS = register_domain(load_identified(), replace=True)
FOUR_WHEEL_CONFIRMED = register_domain(
    load_identified(name=CONFIRMED_NAME, confirmed_only=True), replace=True
)
