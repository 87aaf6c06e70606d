"""The options of the strategies (:class:`StrategyOptions`): which table, which recursion mode,
the lookahead window and budget, whole-plan rewriting, the LPG-adapt limits."""

from __future__ import annotations

from dataclasses import dataclass

from selfrepair.errors import ProblemError, choice
from selfrepair.limits import (
    DEFAULT_CONFIDENCE,
    DEFAULT_FAULT_PRIOR,
    DEFAULT_MAX_FAULTS,
    DEFAULT_MAX_WAIT,
    MAX_LOOKUP_PATTERNS,
)
from selfrepair.repair.replacement import DEFAULT_MAX_DEPTH, DEFERRING, RecursionMode
from selfrepair.tables.fileformat import resolve_table
from selfrepair.tables.model import ReplacementTable, SomeTable

__all__ = ["StrategyOptions"]


@dataclass(frozen=True, slots=True)
class StrategyOptions:
    """Options of the strategies.

    ``table`` is a bundled table name, a table file path or a :class:`ReplacementTable`;
    ``recursion`` a :class:`~selfrepair.repair.replacement.RecursionMode` (or its name);
    ``max_depth`` the depth bound of ``guarded`` mode; ``window`` the lookahead window (actions
    after the faulty one); ``before`` the actions before the faulty one that a lookahead window
    may take in as well, when the fault is known that early (see :func:`lookahead`);
    ``lookahead_expansions`` the budget of one window search; ``rewrite``: the ``replacement``
    strategy substitutes, when it first meets a faulty action under the faults known, every
    faulty action of the rest of the plan that has a valid replacement at its predicted pose
    (whole-plan rewriting; in a changing world the detour of a blocked action likewise
    replaces every later blocked window by its detour; other strategies ignore it; not in a
    deferring recursion mode such as ``primitive``, whose replacements may keep faulty actions
    for later);
    ``max_lookup_patterns`` the patterns one compiled look-up stores at most
    (:data:`~selfrepair.limits.MAX_LOOKUP_PATTERNS`). ``lpg_time_limit_s`` and ``lpg_seed`` are
    the wall-clock limit (seconds) and the seed of each LPG-adapt call of the ``lpg-adapt``
    strategy. ``max_wait`` bounds the steps the robot spends waiting in place, in all, when a
    repair finds that no plan exists under the known faults (faults that may clear: transient or
    intermittent, sensed with detection ``now``); 0 gives up at once (see
    :mod:`selfrepair.execution.stepper`). The diagnosing strategies (faults hidden; see
    docs/diagnosis.md) take hypotheses of up to ``max_faults`` faults, each fault present a
    priori with probability ``fault_prior``, and need posterior mass ``1 - confidence`` to take a
    class as isolated or a set of classes as all that is possible (the defaults are the one
    constants ``DEFAULT_MAX_FAULTS``, ``DEFAULT_FAULT_PRIOR`` and ``DEFAULT_CONFIDENCE`` of
    :mod:`selfrepair.limits`, the same on the command line and in experiment files).
    """

    table: str | SomeTable = "handwritten"
    recursion: RecursionMode = RecursionMode.FLAT
    max_depth: int = DEFAULT_MAX_DEPTH
    window: int = 3
    lookahead_expansions: int = 20_000
    before: int = 0
    lpg_time_limit_s: float = 5.0
    lpg_seed: int = 0
    rewrite: bool = False
    max_lookup_patterns: int = MAX_LOOKUP_PATTERNS
    max_wait: int = DEFAULT_MAX_WAIT
    max_faults: int = DEFAULT_MAX_FAULTS
    fault_prior: float = DEFAULT_FAULT_PRIOR
    confidence: float = DEFAULT_CONFIDENCE

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "recursion", choice(RecursionMode, self.recursion, "recursion mode")
        )
        if min(self.window, self.max_depth, self.before) < 0 or self.lookahead_expansions < 1:
            raise ProblemError(
                "window, before and max_depth must be >= 0 and lookahead_expansions >= 1"
            )
        if not self.lpg_time_limit_s > 0 or self.lpg_seed < 0:
            raise ProblemError("lpg_time_limit_s must be above 0 and lpg_seed >= 0")
        if self.max_lookup_patterns < 0:
            raise ProblemError(
                f"max_lookup_patterns must be at least 0, got {self.max_lookup_patterns}"
            )
        if self.max_wait < 0:
            raise ProblemError(f"max_wait must be at least 0, got {self.max_wait}")
        if not isinstance(self.max_faults, int) or self.max_faults < 0:
            raise ProblemError(f"max_faults must be an integer >= 0, got {self.max_faults!r}")
        if not 0.0 < self.fault_prior < 1.0:
            raise ProblemError(f"fault_prior must be in (0, 1), got {self.fault_prior!r}")
        if not 0.0 <= self.confidence < 1.0:
            raise ProblemError(f"confidence must be in [0, 1), got {self.confidence!r}")
        if not isinstance(self.rewrite, bool):
            raise ProblemError(f"rewrite must be True or False, got {self.rewrite!r}")
        if self.rewrite and self.recursion in DEFERRING:
            raise ProblemError(
                f"rewrite is not available in {self.recursion} recursion (its replacements may "
                "keep faulty actions for later)"
            )

    @property
    def table_label(self) -> str:
        """How the table is named in traces and result rows."""
        if isinstance(self.table, ReplacementTable):
            source = self.table.source
            if source.startswith("<bundled:") and source.endswith(">"):
                return source[len("<bundled:") : -1]  # a name resolve_table understands
            return source
        return str(self.table)

    def resolved_table(self) -> SomeTable:
        """The table itself (bundled tables and files are read once per process)."""
        if isinstance(self.table, ReplacementTable):
            return self.table
        return resolve_table(str(self.table))
