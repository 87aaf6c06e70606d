"""Replacement tables: the value, its JSON file format, loading with re-simulation, and checks.

A replacement table maps each action to an ordered list of candidate sub-plans, stored relative to
the robot, so one entry serves every pose and heading. Two shapes:

``fault-agnostic``
    One entry per action: ``candidates(action, faults)`` returns that entry's list whatever the
    faults are. This is the shape of the original hand-written tables.
``fault-indexed``
    Entries keyed by (action, fault set). ``candidates(action, known)`` returns the list for
    exactly ``known`` when the table has one, else the lists of every indexed subset of ``known``,
    largest subsets first (ties in canonical fault-text order), concatenated without duplicates.

File format (JSON, written by :func:`dump_table` with sorted keys and one entry per line)::

    {"format": "selfrepair-table", "version": 1, "domain": "four-wheel",
     "shape": "fault-agnostic", "made_by": "hand", "parameters": {},
     "entries": [{"action": "FFFF", "candidates": [["FFSS"], ["FBFB", "FBFB", "BBBB", ...]]}]}

Fault-indexed entries also carry ``"faults": "FL:F,RR:B"`` (the domain's canonical fault text).
Every table, however made, is checked when it is built: each candidate is re-simulated from the
domain's canonical state on an open plane and must end where the replaced action ends, must not be
empty and must not contain the replaced action. A wrong entry raises :class:`TableError` naming the
file, the entry's line (when known), its index and action, and what was expected.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from selfrepair.errors import ProblemError, TableError
from selfrepair.robots.domain import Domain, run_open
from selfrepair.robots.registry import get_domain
from selfrepair.tables.enumerate import FAULT_SCOPES, OBJECTIVES

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "MADE_BY",
    "PRIORITIES",
    "SHAPES",
    "GenerateOptions",
    "ReplacementTable",
    "TableEntry",
    "TableProblem",
    "check_table",
]

FORMAT_NAME = "selfrepair-table"
FORMAT_VERSION = 1
SHAPES = ("fault-agnostic", "fault-indexed")
MADE_BY = ("hand", "generator")

Candidate = tuple[Any, ...]


@dataclass(frozen=True, slots=True)
class TableEntry:
    """One row of a table: an action, its fault set (fault-indexed only) and its candidates."""

    action: Any
    candidates: tuple[Candidate, ...]
    faults: frozenset[Any] | None = None
    line: int | None = field(default=None, compare=False)


@dataclass(frozen=True, slots=True)
class TableProblem:
    """Something :func:`check_table` noticed. ``severity`` is ``"error"`` or ``"warning"``."""

    severity: str
    message: str
    entry: int | None = None
    action: str | None = None

    def __str__(self) -> str:
        where = "" if self.entry is None else f"entry {self.entry} ({self.action}): "
        return f"{self.severity}: {where}{self.message}"


@dataclass(frozen=True, slots=True)
class ReplacementTable:
    """A validated replacement table (see the module docstring).

    Build one directly (entries are re-simulated in ``__post_init__``) or with :func:`parse_table`
    / :func:`load_table`. ``source`` names where it came from, for error messages only.
    Lookups through :meth:`candidates` are dictionary look-ups, memoised per (action, faults).
    """

    domain: str
    shape: str
    made_by: str
    entries: tuple[TableEntry, ...]
    parameters: Mapping[str, Any] = field(default_factory=dict, hash=False)
    version: int = FORMAT_VERSION
    source: str = field(default="<table>", compare=False)
    _index: dict[tuple[Any, frozenset[Any] | None], tuple[Candidate, ...]] = field(
        init=False, repr=False, compare=False
    )
    _memo: dict[tuple[Any, frozenset[Any]], tuple[Candidate, ...]] = field(
        init=False, repr=False, compare=False
    )
    derived: dict[Any, Any] = field(init=False, repr=False, compare=False)
    """Scratch space where other modules memoise structures derived from this (immutable) table,
    e.g. :mod:`selfrepair.repair.replacement`'s compiled flat look-ups. Not part of the value."""

    def __post_init__(self) -> None:
        dom = get_domain(self.domain)
        if self.shape not in SHAPES:
            raise TableError(
                f"expected shape one of {', '.join(SHAPES)}, got {self.shape!r}", source=self.source
            )
        if self.made_by not in MADE_BY:
            raise TableError(
                f"expected made_by one of {', '.join(MADE_BY)}, got {self.made_by!r}",
                source=self.source,
            )
        if self.version != FORMAT_VERSION:
            raise TableError(
                f"expected version {FORMAT_VERSION}, got {self.version!r}", source=self.source
            )
        index: dict[tuple[Any, frozenset[Any] | None], tuple[Candidate, ...]] = {}
        for number, entry in enumerate(self.entries):
            _validate_entry(dom, self, number, entry)
            key = (entry.action, entry.faults)
            if key in index:
                raise self._error(
                    number, entry, "expected one entry per action and fault set, got a second one"
                )
            index[key] = entry.candidates
        object.__setattr__(self, "_index", index)
        object.__setattr__(self, "_memo", {})
        object.__setattr__(self, "derived", {})

    def _error(self, number: int, entry: TableEntry, what: str) -> TableError:
        dom = get_domain(self.domain)
        label = f"entry {number} (action {dom.format_action(entry.action)}"
        if entry.faults is not None:
            label += f", faults {dom.format_faults(entry.faults)!r}"
        return TableError(f"{label}): {what}", source=self.source, line=entry.line)

    def candidates(
        self, action: Any, known_faults: Iterable[Any] = frozenset()
    ) -> tuple[Candidate, ...]:
        """The ordered candidates for replacing ``action`` when ``known_faults`` are known."""
        if self.shape == "fault-agnostic":
            return self._index.get((action, None), ())
        known = frozenset(known_faults)
        key = (action, known)
        hit = self._memo.get(key)
        if hit is None:
            hit = self._indexed_lookup(action, known)
            self._memo[key] = hit
        return hit

    def _indexed_lookup(self, action: Any, known: frozenset[Any]) -> tuple[Candidate, ...]:
        exact = self._index.get((action, known))
        if exact is not None:
            return exact
        dom = get_domain(self.domain)
        ordered = sorted(known, key=lambda f: dom.format_faults([f]))
        merged: dict[Candidate, None] = {}
        for size in range(len(ordered) - 1, -1, -1):
            for subset in itertools.combinations(ordered, size):
                for candidate in self._index.get((action, frozenset(subset)), ()):
                    merged.setdefault(candidate, None)
        return tuple(merged)

    def actions_with_entries(self) -> frozenset[Any]:
        """Every action that has at least one entry."""
        return frozenset(entry.action for entry in self.entries)


def _validate_entry(
    dom: Domain[Any, Any], table: ReplacementTable, number: int, entry: TableEntry
) -> None:
    """Raise :class:`TableError` unless every candidate of ``entry`` re-simulates correctly."""
    if entry.action not in dom.actions:
        raise table._error(number, entry, f"expected an action of domain {dom.name}")
    if (entry.faults is None) != (table.shape == "fault-agnostic"):
        want = 'no "faults" key' if table.shape == "fault-agnostic" else 'a "faults" key'
        raise table._error(number, entry, f"expected {want} in a {table.shape} table")
    target = dom.apply(dom.canonical, entry.action)
    name = dom.format_action(entry.action)
    for k, candidate in enumerate(entry.candidates):
        text = " ".join(dom.format_action(a) for a in candidate)
        if not candidate:
            raise table._error(
                number, entry, f"candidate {k} is empty; expected at least one action"
            )
        if entry.action in candidate:
            raise table._error(
                number,
                entry,
                f"candidate {k} [{text}] contains the replaced "
                f"action {name}; expected a sub-plan without it",
            )
        end = run_open(dom, dom.canonical, candidate)
        if end != target:
            raise table._error(
                number,
                entry,
                f"candidate {k} [{text}] ends at {end} from "
                f"{dom.canonical}; expected {target} as {name} does",
            )


# --- text format ------------------------------------------------------------------------------


# --- checks -----------------------------------------------------------------------------------


def check_table(table: ReplacementTable) -> list[TableProblem]:
    """Problems that loading does not reject: gaps and dead candidates.

    Errors: a fault-indexed candidate that uses an action its own fault set forbids (it can never
    be valid under exactly those faults). Warnings: an action of the domain with no entry or with
    an empty candidate list, and a candidate listed twice in one entry.
    """
    dom = get_domain(table.domain)
    problems: list[TableProblem] = []
    covered = set()
    for number, entry in enumerate(table.entries):
        name = dom.format_action(entry.action)
        covered.add(entry.action)
        if not entry.candidates:
            problems.append(TableProblem("warning", "no candidates", number, name))
        seen: set[Candidate] = set()
        for k, candidate in enumerate(entry.candidates):
            if candidate in seen:
                problems.append(
                    TableProblem("warning", f"candidate {k} is listed twice", number, name)
                )
            seen.add(candidate)
            if entry.faults is not None:
                bad = [a for a in candidate if not dom.available(a, entry.faults)]
                if bad:
                    problems.append(
                        TableProblem(
                            "error",
                            f"candidate {k} uses {dom.format_action(bad[0])}, which its fault set "
                            f"{dom.format_faults(entry.faults)!r} forbids",
                            number,
                            name,
                        )
                    )
    for action in dom.actions:
        if action not in covered:
            problems.append(
                TableProblem("warning", f"action {dom.format_action(action)} has no candidates")
            )
    return problems


# --- bundled tables ---------------------------------------------------------------------------


# --- generation options ---------------------------------------------------------------------


SHAPES = ("fault-agnostic", "fault-indexed")


PRIORITIES = ("cost", "walls")
"""Fault-agnostic tie-break after coverage: cheapest replacements first (the issue's order), or
first the candidates that fit wherever the replaced action fits."""


@dataclass(frozen=True, slots=True)
class GenerateOptions:
    """Everything that determines a generated table; recorded in its header ``parameters``."""

    domain: str = "four-wheel"
    shape: str = "fault-agnostic"
    max_length: int = 5
    per_action: int = 5
    faults: str = "all"
    objective: str = "duration"
    priority: str = "cost"

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ProblemError(
                f"unknown table shape {self.shape!r}; expected one of {', '.join(SHAPES)}"
            )
        if self.faults not in FAULT_SCOPES:
            raise ProblemError(
                f"unknown fault scope {self.faults!r}; expected one of {', '.join(FAULT_SCOPES)}"
            )
        if self.objective not in OBJECTIVES:
            raise ProblemError(
                f"unknown objective {self.objective!r}; expected one of {', '.join(OBJECTIVES)}"
            )
        if self.priority not in PRIORITIES:
            raise ProblemError(
                f"unknown priority {self.priority!r}; expected one of {', '.join(PRIORITIES)}"
            )
        if not 1 <= self.max_length <= 12:
            raise ProblemError(f"max_length must be from 1 to 12, got {self.max_length}")
        if self.per_action < 1:
            raise ProblemError(f"per_action must be at least 1, got {self.per_action}")

    def parameters(self) -> dict[str, Any]:
        """The options as the JSON header's ``parameters`` object."""
        return {
            "faults": self.faults,
            "max_length": self.max_length,
            "objective": self.objective,
            "per_action": self.per_action,
            "priority": self.priority,
        }
