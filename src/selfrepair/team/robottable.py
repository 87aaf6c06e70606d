"""The robots' own replacement table, for their wheel faults: one place that says which it is.

The table comes from the run's options (``team run --robot-table``, an experiment's
``[robot] table``), else from the scenario (key ``table``), else it is the robot's default
(:func:`selfrepair.tables.fileformat.default_table`: the paper's hand-written table for the
four-wheel robot, the bundled ``three-action`` table for that robot, a generated one for a robot
that ships none), exactly as a single robot's ``run`` and the Gymnasium environment choose it.
"""

from __future__ import annotations

from selfrepair.errors import ProblemError
from selfrepair.tables.fileformat import default_table, default_table_name, resolve_table
from selfrepair.tables.model import SomeTable
from selfrepair.team.model import TeamScenario
from selfrepair.team.result import TeamOptions

__all__ = ["robot_table", "robot_table_label"]


def _spec(scenario: TeamScenario, options: TeamOptions) -> str:
    return options.robot_table or scenario.table


def robot_table(scenario: TeamScenario, options: TeamOptions) -> SomeTable:
    """The table every robot of ``scenario`` repairs its own wheel faults with (bundled tables
    and files are read once per process, a generated default is made once). Raises
    :class:`ProblemError` when the table is for another robot."""
    spec = _spec(scenario, options)
    table = default_table(scenario.domain) if not spec else resolve_table(spec)
    if table.domain is not scenario.domain:
        raise ProblemError(
            f"the robots' table {spec!r} is for the {table.domain.name} robot, the scenario's "
            f"robots are {scenario.domain.name}; name a table of theirs (a bundled name or a "
            "file) or leave it out for their default"
        )
    return table


def robot_table_label(scenario: TeamScenario, options: TeamOptions) -> str:
    """How the robots' table is named in traces and rows: the name or file given, else the
    default's name (``handwritten``, ``three-action``, ``generated``)."""
    return _spec(scenario, options) or default_table_name(scenario.domain)
