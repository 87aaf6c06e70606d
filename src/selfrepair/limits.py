"""The default limits on every input a user can make huge, and the bounds of numeric options.

A *limit* guards a resource (memory, time). It is checked before the work it guards starts, and a
breach raises :class:`~selfrepair.errors.LimitError`, which names the limit and the flag that
raises it. Every reader and generator takes the limit as a keyword argument of the same name
(``max_cells=...``; ``None`` turns the check off), and every command that reads or makes such an
input has a flag of the same name (``--max-cells N``). ``docs/reliability.md`` lists them with
the tests that prove each one.

A *bound* is a range a numeric option must lie in for its arithmetic to stay exact and finite; a
value outside it is bad input (there is no flag: no useful value lies beyond it).

This module sits at the bottom of the package beside :mod:`selfrepair.errors`, so that every layer
can use it.
"""

from __future__ import annotations

from selfrepair.errors import LimitError

__all__ = [
    "DEFAULT_CONFIDENCE",
    "DEFAULT_FAULT_PRIOR",
    "DEFAULT_MAX_FAULTS",
    "DEFAULT_MAX_WAIT",
    "DEFAULT_OBSERVER_RANGE",
    "DEFAULT_SENSING_RANGE",
    "MAX_CELLS",
    "MAX_CLEARANCE_WEIGHT",
    "MAX_FILE_BYTES",
    "MAX_LOOKUP_PATTERNS",
    "MAX_MISSIONS",
    "MAX_OBSERVERS",
    "MAX_ROBOTS",
    "MAX_TABLE_BYTES",
    "MAX_TABLE_CANDIDATES",
    "MAX_TASKS",
    "MAX_TRACE_BYTES",
    "check_limit",
    "maze_file_bytes",
]

# --- limits (each with a flag of the same name) ------------------------------------------------

MAX_CELLS = 2048 * 2048
"""Cells of a maze (width x height) read from a file or generated: 4,194,304.

Four times the largest MovingAI maps (1024 x 1024). A maze this size takes about 15 s and 0.5 GB
to generate and under a second to read; the planners' arrays scale with it."""

MAX_MISSIONS = 1_000_000
"""Missions of one experiment, counted from the configuration before any is built.

Six times the bundled ``full`` experiment (159,744 missions). Building a mission takes about
0.25 ms and 1.6 kB of memory before it runs (measured on ``full``: 39 s, 250 MB at the peak), and
it leaves one row in the results database after."""

MAX_TABLE_BYTES = 64 * 1024 * 1024
"""Size of a replacement-table file (64 MiB), checked before the file is read.

The bundled generated-indexed table is 240 kB. Parsing takes about 20 times the file size in
memory (measured), so about 1.3 GB at the limit."""

MAX_TABLE_CANDIDATES = 1_000_000
"""Candidates in one replacement table, counted before any is re-simulated.

Parsing and re-simulation take about 7 µs and 220 bytes per candidate (measured with a million
candidates: 6.7 s, 220 MB); the bundled generated-indexed table has 3,402."""

MAX_FILE_BYTES = 64 * 1024 * 1024
"""Size of any other text input (64 MiB): MovingAI scenario files, route files, experiment files
and team scenario files, checked before the file is read.

The largest file of these kinds that selfrepair ships or reads in its tests is a MovingAI
scenario of about 250 kB (a few thousand queries); reading takes a few times the file size in
memory, and the parsed rows more."""

MAX_TRACE_BYTES = 256 * 1024 * 1024
"""Size of a mission trace or team trace (256 MiB), checked before the file is read.

A trace takes about 200 bytes per simulated step, so this holds over a million steps; parsing and
replaying take several times the file size in memory."""

MAX_ROBOTS = 64
"""Robots of one team scenario.

Eight times the largest bundled team (8 robots). Every robot plans each drive around the
reservations of all the others and the engine looks at every robot at every event, so the work
per simulated tick grows with the square of the team; 64 robots on a 61x61 maze take seconds per
mission."""

MAX_TASKS = 256
"""Tasks of one team scenario.

Sixteen times the largest bundled load (16 tasks). The allocation solves one assignment problem
per round over robots x open tasks; a re-allocation does it again at every incident."""

DEFAULT_MAX_WAIT = 20
"""Steps a mission may spend waiting in place, in all, when no plan exists under the faults it
knows and they may clear (``StrategyOptions.max_wait``; ``--max-wait`` of ``selfrepair run`` and
``compare``; see :mod:`selfrepair.execution.stepper`). A bound, so that a robot whose faults are
permanent gives up after at most this many steps."""

DEFAULT_SENSING_RANGE = 2
"""Chebyshev cells a robot sees around its own cell in ``range`` sensing of world events
(:mod:`selfrepair.world.events`; ``--sensing-range``): the four-wheel robot's reach, so that with
the default it sees every cell its next motion sweeps."""

DEFAULT_MAX_FAULTS = 2
"""The one default of the most faults a diagnosing robot's hypothesis holds
(``StrategyOptions.max_faults``, ``--max-faults``, experiment files, traces): the four-wheel
robot's singles and doubles (:mod:`selfrepair.diagnosis.hypotheses`)."""

DEFAULT_FAULT_PRIOR = 0.05
"""The one default a priori probability of each fault (``StrategyOptions.fault_prior``,
``--fault-prior``, experiment files, traces)."""

MAX_OBSERVERS = 8
"""Observing teammates one mission may have (experiment files, ``--observers``)."""

DEFAULT_OBSERVER_RANGE = 3
"""The observers' sensing range in cells unless told otherwise (experiment files,
``--observer-range``; the cooperative benchmark's)."""

DEFAULT_CONFIDENCE = 0.01
"""The one default of the error ``e`` a diagnosing robot accepts (``StrategyOptions.confidence``,
``--confidence``, the experiment files' ``confidence``, traces without one): a class is isolated
at posterior mass ``1 - e`` (with its confirmation), and the classes a conformant robot assumes
hold that mass. 1%, the wrong-isolation rate the diagnosis targets allow at 1% noise
(:mod:`selfrepair.diagnosis.belief`).

The three diagnosis defaults live here, at the bottom of the package, rather than in
:mod:`selfrepair.diagnosis`, so that the command line can show them in ``--help`` without loading
NumPy (``tests/test_cli_shape.py``); :mod:`selfrepair.diagnosis` re-exports them."""

MAX_LOOKUP_PATTERNS = 4096
"""Occupancy patterns stored by one compiled replacement look-up (one table, fault set and
recursion mode; :mod:`selfrepair.repair.lookups`), all its actions and headings together.

A cap, not an error: past it, answers are still exact but computed by the reference search each
time instead of stored. A stored pattern costs about 100 bytes, so one look-up holds at most
about 0.4 MB and the at most 512 kept in a process about 210 MB; on the bundled experiments one
holds 1 to 30 KB (measured by ``benchmarks/repair_latency.py``). Raise it with
``--max-lookup-patterns`` (``selfrepair run``) or ``StrategyOptions.max_lookup_patterns``."""

# --- bounds (no flag) --------------------------------------------------------------------------

MAX_CLEARANCE_WEIGHT = 1_000_000
"""Largest clearance weight a planning problem accepts.

The experiments use 0 to 2; at this weight one cell of missing clearance already outweighs any
difference in duration between two routes of a maze within :data:`MAX_CELLS`, while plan costs
stay far inside the range of a float (a weight of 1e308 made them overflow)."""


def check_limit(
    value: int,
    limit: int | None,
    *,
    name: str,
    what: str,
    source: str,
    detail: str = "",
    line: int | None = None,
    column: int | None = None,
) -> None:
    """Raise :class:`LimitError` when ``value`` exceeds ``limit`` (``None``: no limit).

    ``what`` says what was counted, e.g. ``"cells"``; ``name`` is the limit's name (``max_cells``);
    ``detail`` (optional) says how ``value`` came about, e.g. ``"1000000000 x 15"``.
    """
    if limit is not None and value > limit:
        raise LimitError(
            f"expected at most {limit:,} {what}, got {value:,}"
            + (f" ({detail})" if detail else ""),
            limit=name,
            source=source,
            line=line,
            column=column,
        )


def maze_file_bytes(max_cells: int | None) -> int | None:
    """The largest maze file that can hold ``max_cells`` cells, for a check before reading.

    A text maze or MovingAI map takes one byte per cell plus a line end per row (two with CRLF),
    so no file of more than three bytes per cell (1-cell rows with CRLF) plus a 64 kB allowance for
    a header, a byte-order mark and trailing blank lines can be within the cell limit.
    """
    return None if max_cells is None else 3 * max_cells + 65536
