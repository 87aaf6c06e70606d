"""The four-wheel robot as MuJoCo drives it: the domain identified from physics, as a plug-in.

``selfrepair physics fidelity --write-domain FILE`` measures every action in physics and writes
the actions whose end pose snaps to the lattice (the others are dropped, with why); this file
registers the bundled result (written with the default parameters) as the domain
``four-wheel-physics``, its 65 actions that physics confirms as ``four-wheel-confirmed``, and
the 40 of those that also hold in sequence (after other actions) as ``four-wheel-in-sequence``,
so that tables, missions and experiments use them like any robot:

    selfrepair --plugin examples/physics/robot.py table generate --domain four-wheel-physics \
        -o table.json

Needs no MuJoCo: the identified motions are plain data (see docs/physics.md).
"""

from selfrepair.physics.identified import CONFIRMED_NAME, IN_SEQUENCE_NAME, load_identified
from selfrepair.robots.registry import register_domain

FOUR_WHEEL_PHYSICS = register_domain(load_identified(), replace=True)
FOUR_WHEEL_CONFIRMED = register_domain(
    load_identified(name=CONFIRMED_NAME, confirmed_only=True), replace=True
)
FOUR_WHEEL_IN_SEQUENCE = register_domain(
    load_identified(name=IN_SEQUENCE_NAME, in_sequence_only=True), replace=True
)
