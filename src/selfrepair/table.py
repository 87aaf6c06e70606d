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
import json
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from selfrepair.domain import Domain, get_domain, run_open
from selfrepair.errors import InputError, TableError

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "MADE_BY",
    "SHAPES",
    "ReplacementTable",
    "TableEntry",
    "TableProblem",
    "bundled_table",
    "bundled_table_names",
    "check_table",
    "dump_table",
    "load_table",
    "parse_table",
    "resolve_table",
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
    e.g. :mod:`selfrepair.replacement`'s compiled flat look-ups. Not part of the value."""

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


def parse_table(text: str, source: str = "<string>") -> ReplacementTable:
    """Parse and validate a table in the JSON format of the module docstring."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise TableError(
            f"expected JSON: {exc.msg}", source=source, line=exc.lineno, column=exc.colno
        ) from None
    if not isinstance(data, dict):
        raise TableError("expected a JSON object at the top level", source=source)
    if data.get("format") != FORMAT_NAME:
        raise TableError(
            f'expected "format": "{FORMAT_NAME}", got {data.get("format")!r}', source=source
        )
    for key in ("version", "domain", "shape", "made_by", "entries"):
        if key not in data:
            raise TableError(f"expected a {key!r} key in the header", source=source)
    if data["domain"] not in _domain_names():
        raise TableError(
            f"expected a domain in {', '.join(_domain_names())}, got {data['domain']!r}",
            source=source,
        )
    dom = get_domain(data["domain"])
    raw_entries = data["entries"]
    if not isinstance(raw_entries, list):
        raise TableError('expected "entries" to be a list', source=source)
    lines = _entry_lines(text, len(raw_entries))
    parameters = data.get("parameters", {})
    if not isinstance(parameters, dict):
        raise TableError('expected "parameters" to be an object', source=source)
    entries = tuple(
        _parse_entry(dom, raw, number, lines[number], source)
        for number, raw in enumerate(raw_entries)
    )
    return ReplacementTable(
        domain=dom.name,
        shape=data["shape"],
        made_by=data["made_by"],
        entries=entries,
        parameters=parameters,
        version=data["version"],
        source=source,
    )


def _domain_names() -> list[str]:
    from selfrepair.domain import DOMAINS

    return sorted(DOMAINS)


def _entry_lines(text: str, count: int) -> list[int | None]:
    """The line of each entry's ``"action"`` key, when they can be matched one to one cheaply."""
    starts = [m.start() for m in re.finditer(r'"action"\s*:', text)]
    if len(starts) != count:
        return [None] * count
    lines: list[int | None] = []
    line, pos = 1, 0
    for start in starts:
        line += text.count("\n", pos, start)
        pos = start
        lines.append(line)
    return lines


def _parse_entry(
    dom: Domain[Any, Any], raw: Any, number: int, line: int | None, source: str
) -> TableEntry:
    def fail(what: str) -> TableError:
        return TableError(f"entry {number}: {what}", source=source, line=line)

    if not isinstance(raw, dict) or not isinstance(raw.get("action"), str):
        raise fail('expected an object with a string "action"')
    unknown = set(raw) - {"action", "faults", "candidates"}
    if unknown:
        raise fail(f"expected keys action, faults, candidates, got also {sorted(unknown)}")
    try:
        action = dom.parse_action(raw["action"])
        faults = None if "faults" not in raw else dom.parse_faults(_string(raw["faults"]))
    except InputError as exc:
        raise fail(exc.reason) from None
    candidates = raw.get("candidates")
    if not isinstance(candidates, list) or not all(isinstance(c, list) for c in candidates):
        raise fail('expected "candidates" to be a list of lists of action strings')
    parsed: list[Candidate] = []
    for k, candidate in enumerate(candidates):
        try:
            parsed.append(tuple(dom.parse_action(_string(a)) for a in candidate))
        except InputError as exc:
            raise fail(f"candidate {k}: {exc.reason}") from None
    return TableEntry(action=action, candidates=tuple(parsed), faults=faults, line=line)


def _string(value: Any) -> str:
    if not isinstance(value, str):
        raise InputError(f"expected a string, got {value!r}")
    return value


def load_table(path: str | Path) -> ReplacementTable:
    """Read and validate a table file; errors name the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise TableError(f"cannot read table file: {exc.strerror}", source=str(path)) from None
    except UnicodeDecodeError:
        raise TableError("expected a UTF-8 JSON table file", source=str(path)) from None
    return parse_table(text, source=str(path))


def _entry_sort_key(dom: Domain[Any, Any], entry: TableEntry) -> tuple[int, int, str]:
    faults = entry.faults or frozenset()
    return (dom.actions.index(entry.action), len(faults), dom.format_faults(faults))


def dump_table(table: ReplacementTable) -> str:
    """The table as deterministic JSON: sorted keys, entries in domain action order, one a line."""
    dom = get_domain(table.domain)
    rows = []
    for entry in sorted(table.entries, key=lambda e: _entry_sort_key(dom, e)):
        row: dict[str, Any] = {
            "action": dom.format_action(entry.action),
            "candidates": [[dom.format_action(a) for a in c] for c in entry.candidates],
        }
        if entry.faults is not None:
            row["faults"] = dom.format_faults(entry.faults)
        rows.append("  " + json.dumps(row, sort_keys=True))
    header = {
        "domain": table.domain,
        "format": FORMAT_NAME,
        "made_by": table.made_by,
        "parameters": dict(table.parameters),
        "shape": table.shape,
        "version": table.version,
    }
    lines = ["{", ' "domain": ' + json.dumps(header["domain"]) + ",", ' "entries": [']
    lines.append(",\n".join(rows))
    lines.append(" ],")
    rest = [
        f" {json.dumps(k)}: {json.dumps(header[k], sort_keys=True)}"
        for k in ("format", "made_by", "parameters", "shape", "version")
    ]
    lines.append(",\n".join(rest))
    lines.append("}")
    return "\n".join(line for line in lines if line) + "\n"


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


def bundled_table_names() -> tuple[str, ...]:
    """Names of the tables shipped as package data."""
    folder = resources.files("selfrepair").joinpath("data", "tables")
    return tuple(
        sorted(p.name[: -len(".json")] for p in folder.iterdir() if p.name.endswith(".json"))
    )


def bundled_table(name: str = "handwritten") -> ReplacementTable:
    """Load a table shipped with the package, e.g. ``"handwritten"`` or ``"three-action"``."""
    if name not in bundled_table_names():
        raise TableError(
            f"expected a bundled table name ({', '.join(bundled_table_names())})", source=name
        )
    resource = resources.files("selfrepair").joinpath("data", "tables", f"{name}.json")
    return parse_table(resource.read_text(encoding="utf-8"), source=f"<bundled:{name}>")


def resolve_table(spec: str | Path) -> ReplacementTable:
    """A bundled table by name, else a table file by path."""
    text = str(spec)
    if text in bundled_table_names():
        return bundled_table(text)
    return load_table(text)
