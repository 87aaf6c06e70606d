"""Team missions: several robots in one maze deliver items, and a faulty robot's higher-level
action is replaced by a sub-plan of its teammates' actions (the original work's last future-work
item).

The package sits between ``experiment`` and ``execution``: it may import ``execution``,
``repair``, ``tables``, ``search``, ``world``, ``robots`` and the ground modules, never
``experiment`` or ``cli``. Values flow as in the single-robot core: a
:class:`~selfrepair.team.model.TeamScenario` and a strategy go in
(:func:`selfrepair.team.engine.run_team`), a :class:`~selfrepair.team.result.TeamResult` comes
out, and rows (:mod:`selfrepair.team.metrics`) and JSON Lines traces
(:mod:`selfrepair.team.trace`) are made from it. See docs/team.md.
"""

__all__: list[str] = []  # the names live in the modules; the curated ones are `selfrepair.*`
