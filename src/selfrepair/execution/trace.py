"""Mission traces (JSON Lines) and their replay: the public names in one place.

The format is described in :mod:`selfrepair.execution.traceformat`; traces are written by
:mod:`selfrepair.execution.tracewrite`, read (and a header turned back into its mission spec) by
:mod:`selfrepair.execution.traceread`, and re-simulated with the robot's domain and the fault
schedule by :mod:`selfrepair.execution.replay`, which names the first step that does not hold.
"""

from __future__ import annotations

from selfrepair.execution.replay import ReplayReport, replay
from selfrepair.execution.traceformat import (
    TRACE_FORMAT,
    TRACE_VERSION,
    Trace,
    TraceFields,
    TraceRepair,
)
from selfrepair.execution.traceread import parse_trace, read_trace, spec_from_header
from selfrepair.execution.tracewrite import header_json, trace_lines, write_trace

__all__ = [
    "TRACE_FORMAT",
    "TRACE_VERSION",
    "ReplayReport",
    "Trace",
    "TraceFields",
    "TraceRepair",
    "header_json",
    "parse_trace",
    "read_trace",
    "replay",
    "spec_from_header",
    "trace_lines",
    "write_trace",
]
