"""Team traces (JSON Lines) and their re-simulation: the public names in one place.

The format is described in :mod:`selfrepair.team.traceformat`; traces are written by
:mod:`selfrepair.team.tracewrite`, read by :mod:`selfrepair.team.traceread` and re-simulated,
trusting nothing but the header and the scenario file it names, by :mod:`selfrepair.team.replay`.
"""

from __future__ import annotations

from selfrepair.team.replay import TeamReplayReport, replay_team
from selfrepair.team.traceformat import TEAM_TRACE_FORMAT, TEAM_TRACE_VERSION, TeamTrace
from selfrepair.team.traceread import is_team_trace, parse_team_trace, read_team_trace
from selfrepair.team.tracewrite import header_json, team_trace_lines, write_team_trace

__all__ = [
    "TEAM_TRACE_FORMAT",
    "TEAM_TRACE_VERSION",
    "TeamReplayReport",
    "TeamTrace",
    "header_json",
    "is_team_trace",
    "parse_team_trace",
    "read_team_trace",
    "replay_team",
    "team_trace_lines",
    "write_team_trace",
]
