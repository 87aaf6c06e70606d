"""Replacement tables: the table value, how it is checked, and the options that generate one.

A replacement table maps each action of a robot (a :class:`~selfrepair.robots.domain.Domain`) to
an ordered list of candidate sub-plans, stored relative to the robot, so one entry serves every
pose and heading. Two shapes (:class:`TableShape`):

``fault-agnostic``
    One entry per action: ``candidates(action, faults)`` returns that entry's list whatever the
    faults are. This is the shape of the original hand-written tables.
``fault-indexed``
    Entries keyed by (action, fault set). ``candidates(action, known)`` returns the list for
    exactly ``known`` when the table has one, else the lists of every indexed subset of ``known``,
    largest subsets first (ties in canonical fault-text order), concatenated without duplicates.

Every table, however made, is checked when it is built: each candidate is re-simulated on an open
plane from the canonical state facing each of the four headings, and must end where the replaced
action ends, must not be empty and must not contain the replaced action. A wrong entry raises
:class:`~selfrepair.errors.TableError` naming the source, the entry's line (when known), its index
and action, and what was expected. The file format is :mod:`selfrepair.tables.fileformat`.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, Generic, TypeAlias, cast

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import ProblemError, TableError, choice
from selfrepair.geometry import Heading, Pose
from selfrepair.robots.domain import A, Domain, F, run_open
from selfrepair.tables.enumerate import FaultScope, Objective
from selfrepair.textio import JSONValue

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "GenerateOptions",
    "MadeBy",
    "Priority",
    "ReplacementTable",
    "SomeTable",
    "TableEntry",
    "TableProblem",
    "TableShape",
    "check_table",
]

FORMAT_NAME = "selfrepair-table"
FORMAT_VERSION = 1

Candidate = tuple[A, ...]
"""One replacement sub-plan: actions of the table's domain, relative to the robot."""


class TableShape(StrEnum):
    """How entries are keyed (see the module docstring)."""

    FAULT_AGNOSTIC = "fault-agnostic"
    FAULT_INDEXED = "fault-indexed"


class MadeBy(StrEnum):
    """Who wrote a table."""

    HAND = "hand"
    GENERATOR = "generator"


@dataclass(frozen=True, slots=True)
class TableEntry(Generic[A, F]):
    """One row of a table: an action, its fault set (fault-indexed only) and its candidates."""

    action: A
    candidates: tuple[Candidate[A], ...]
    faults: frozenset[F] | None = None
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


_Key = tuple[A, frozenset[F] | None]


@dataclass(frozen=True, slots=True, eq=False)
class ReplacementTable(Generic[A, F]):
    """A validated replacement table for ``domain`` (see the module docstring).

    Build one directly (entries are re-simulated in ``__post_init__``) or with
    :func:`~selfrepair.tables.fileformat.parse_table` /
    :func:`~selfrepair.tables.fileformat.load_table`. ``source`` names where it came from, for
    error messages only. Two tables are equal when they are for the same domain and have the same
    shape, author, entries, parameters and version; the hash is computed once.
    """

    domain: Domain[A, F]
    shape: TableShape
    made_by: MadeBy
    entries: tuple[TableEntry[A, F], ...]
    parameters: Mapping[str, JSONValue] = field(default_factory=dict)
    version: int = FORMAT_VERSION
    source: str = "<table>"
    _index: dict[_Key[A, F], tuple[Candidate[A], ...]] = field(init=False, repr=False)
    _hash: int = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.domain, Domain):
            raise ProblemError(
                f"a table's domain must be a Domain value, got {self.domain!r} "
                "(look a name up with selfrepair.robots.registry.get_domain)"
            )
        for name, kind in (("shape", TableShape), ("made_by", MadeBy)):
            value = getattr(self, name)
            if value not in set(kind):
                allowed = ", ".join(kind)
                raise TableError(
                    f"expected {name} one of {allowed}, got {value!r}", source=self.source
                )
            object.__setattr__(self, name, kind(value))
        if type(self.version) is not int or self.version != FORMAT_VERSION:
            raise TableError(
                f"expected version {FORMAT_VERSION}, got {self.version!r}", source=self.source
            )
        index: dict[_Key[A, F], tuple[Candidate[A], ...]] = {}
        checked: set[tuple[A, Candidate[A]]] = set()
        for number, entry in enumerate(self.entries):
            _validate_entry(self, number, entry, checked)
            key = (entry.action, entry.faults)
            if key in index:
                raise self._error(
                    number, entry, "expected one entry per action and fault set, got a second one"
                )
            index[key] = entry.candidates
        object.__setattr__(self, "_index", index)
        params = tuple(sorted((k, repr(v)) for k, v in self.parameters.items()))
        content = (self.domain, self.shape, self.made_by, self.entries, params, self.version)
        object.__setattr__(self, "_hash", hash(content))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ReplacementTable):
            return NotImplemented
        return (
            self._hash == other._hash
            and self.domain is other.domain
            and self.shape == other.shape
            and self.made_by == other.made_by
            and self.entries == other.entries
            and dict(self.parameters) == dict(other.parameters)
            and self.version == other.version
        )

    def __hash__(self) -> int:
        return self._hash

    def _error(self, number: int, entry: TableEntry[A, F], what: str) -> TableError:
        dom = self.domain
        label = f"entry {number} (action {dom.format_action(entry.action)}"
        if entry.faults is not None:
            label += f", faults {dom.format_faults(entry.faults)!r}"
        return TableError(f"{label}): {what}", source=self.source, line=entry.line)

    def candidates(
        self, action: A, known_faults: Iterable[F] = frozenset()
    ) -> tuple[Candidate[A], ...]:
        """The ordered candidates for replacing ``action`` when ``known_faults`` are known."""
        if self.shape is TableShape.FAULT_AGNOSTIC:
            return self._index.get((action, None), ())
        known = frozenset(known_faults)
        exact = self._index.get((action, known))
        if exact is not None:
            return exact
        merged = _MERGED.get((self, action, known), lambda: self._merged(action, known))
        # the key holds this table, so the value is its own candidates
        return cast("tuple[Candidate[A], ...]", merged)

    def _merged(self, action: A, known: frozenset[F]) -> tuple[Candidate[A], ...]:
        dom = self.domain
        ordered = sorted(known, key=lambda f: dom.format_faults([f]))
        merged: dict[Candidate[A], None] = {}
        for size in range(len(ordered) - 1, -1, -1):
            for subset in itertools.combinations(ordered, size):
                for candidate in self._index.get((action, frozenset(subset)), ()):
                    merged.setdefault(candidate, None)
        return tuple(merged)

    def actions_with_entries(self) -> frozenset[A]:
        """Every action that has at least one entry."""
        return frozenset(entry.action for entry in self.entries)


SomeTable: TypeAlias = "ReplacementTable[Any, Any]"
"""A table for a robot known only at run time: one read from a file or looked up by name, whose
domain comes from the registry (:data:`~selfrepair.robots.domain.SomeDomain`)."""


_MERGED: BoundedCache[tuple[object, object, frozenset[object]], tuple[tuple[object, ...], ...]] = (
    BoundedCache("fault-indexed merged look-ups", 4096, kind=CacheKind.REPAIR)
)
"""Candidates for fault sets a fault-indexed table has no entry of its own for."""

_STARTS = tuple(Pose(0, 0, heading) for heading in Heading)


def _validate_entry(
    table: ReplacementTable[A, F],
    number: int,
    entry: TableEntry[A, F],
    checked: set[tuple[A, Candidate[A]]],
) -> None:
    """Raise :class:`TableError` unless every candidate of ``entry`` re-simulates correctly from
    every heading (``checked`` remembers (action, candidate) pairs already found correct)."""
    dom = table.domain
    if entry.action not in dom.actions:
        raise table._error(number, entry, f"expected an action of domain {dom.name}")
    agnostic = table.shape is TableShape.FAULT_AGNOSTIC
    if (entry.faults is None) != agnostic:
        want = 'no "faults" key' if agnostic else 'a "faults" key'
        raise table._error(number, entry, f"expected {want} in a {table.shape} table")
    name = dom.format_action(entry.action)
    for k, candidate in enumerate(entry.candidates):
        if (entry.action, candidate) in checked:
            continue
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
        for start in _STARTS:
            target = dom.apply(start, entry.action)
            end = run_open(dom, start, candidate)
            if end != target:
                raise table._error(
                    number,
                    entry,
                    f"candidate {k} [{text}] ends at {end} from "
                    f"{start}; expected {target} as {name} does",
                )
        checked.add((entry.action, candidate))


# --- checks -----------------------------------------------------------------------------------


def check_table(table: ReplacementTable[A, F]) -> list[TableProblem]:
    """Problems that loading does not reject: gaps and dead candidates.

    Errors: a fault-indexed candidate that uses an action its own fault set forbids (it can never
    be valid under exactly those faults). Warnings: an action of the domain with no entry, a
    fault-agnostic entry with an empty candidate list, and a candidate listed twice in one entry.

    An empty *fault-indexed* entry is no gap: it marks that the action has no replacement under
    exactly that fault set (the generator writes one for every disabled action it found none for
    within its ``max_length``, so a look-up stops there instead of merging the entries of
    subsets); :func:`no_replacement_marks` counts them.
    """
    dom = table.domain
    problems: list[TableProblem] = []
    covered = set()
    for number, entry in enumerate(table.entries):
        name = dom.format_action(entry.action)
        covered.add(entry.action)
        if not entry.candidates and entry.faults is None:
            problems.append(TableProblem("warning", "no candidates", number, name))
        seen: set[Candidate[A]] = set()
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


def no_replacement_marks(table: ReplacementTable[A, F]) -> int:
    """The fault-indexed entries with an empty candidate list: each marks "no replacement under
    exactly these faults" (see :func:`check_table`)."""
    return sum(1 for e in table.entries if e.faults is not None and not e.candidates)


# --- bundled tables ---------------------------------------------------------------------------


# --- generation options ---------------------------------------------------------------------


class Priority(StrEnum):
    """Fault-agnostic tie-break after coverage: cheapest replacements first, or first the
    candidates that fit wherever the replaced action fits."""

    COST = "cost"
    WALLS = "walls"


MAX_LENGTH_LIMIT = 12
"""The longest candidate the generator searches for (enumeration grows exponentially)."""


@dataclass(frozen=True, slots=True)
class GenerateOptions:
    """Everything that determines a generated table; recorded in its header ``parameters``.

    Strings are accepted for the enum fields and converted; an unknown value raises
    :class:`~selfrepair.errors.ProblemError` listing the allowed ones.
    """

    shape: TableShape = TableShape.FAULT_AGNOSTIC
    max_length: int = 5
    per_action: int = 5
    faults: FaultScope = FaultScope.ALL
    objective: Objective = Objective.DURATION
    priority: Priority = Priority.COST

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", choice(TableShape, self.shape, "table shape"))
        object.__setattr__(self, "faults", choice(FaultScope, self.faults, "fault scope"))
        object.__setattr__(self, "objective", choice(Objective, self.objective, "objective"))
        object.__setattr__(self, "priority", choice(Priority, self.priority, "priority"))
        if not 1 <= self.max_length <= MAX_LENGTH_LIMIT:
            raise ProblemError(
                f"max_length must be from 1 to {MAX_LENGTH_LIMIT}, got {self.max_length}"
            )
        if self.per_action < 1:
            raise ProblemError(f"per_action must be at least 1, got {self.per_action}")

    def parameters(self) -> dict[str, JSONValue]:
        """The options as the JSON header's ``parameters`` object."""
        return {
            "faults": self.faults.value,
            "max_length": self.max_length,
            "objective": self.objective.value,
            "per_action": self.per_action,
            "priority": self.priority.value,
        }
