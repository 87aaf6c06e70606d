"""Robots: the :class:`~selfrepair.robots.domain.Domain` value, the registry of domains, and the
robots that ship with the package (the four-wheel skid-steer robot and the paper's three-action
robot).

A domain is the single definition of what a robot's actions do (motion, footprint, duration) and of
its faults; every layer above calls it and nobody re-derives it. This package may import only
:mod:`selfrepair.errors` and :mod:`selfrepair.geometry`. The generic layers (``tables``, ``repair``)
import ``robots.domain`` and ``robots.registry``, never a concrete robot.
"""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
