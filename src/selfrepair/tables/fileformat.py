"""The JSON file format of replacement tables: parse, dump, load, and the bundled tables.

File format (JSON, written by :func:`dump_table` with sorted keys and one entry per line)::

    {"format": "selfrepair-table", "version": 1, "domain": "four-wheel",
     "shape": "fault-agnostic", "made_by": "hand", "parameters": {},
     "entries": [{"action": "FFFF", "candidates": [["FFSS"], ["FBFB", "FBFB", "BBBB", ...]]}]}

Fault-indexed entries also carry ``"faults": "FL:F,RR:B"`` (the domain's canonical fault text).
The ``domain`` key names a domain known to :func:`selfrepair.robots.registry.get_domain`. Every
table is re-simulated when it is built (:class:`~selfrepair.tables.model.ReplacementTable`); a wrong
entry raises :class:`~selfrepair.errors.TableError` naming the file, the entry's line (when known),
its index and action, and what was expected.
"""

from __future__ import annotations

import json
import re
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

from selfrepair.caching import BoundedCache
from selfrepair.errors import InputError, TableError
from selfrepair.robots.domain import Domain
from selfrepair.robots.registry import domain_names, get_domain
from selfrepair.tables.model import FORMAT_NAME, Candidate, ReplacementTable, TableEntry

__all__ = [
    "bundled_table",
    "bundled_table_names",
    "dump_table",
    "load_table",
    "parse_table",
    "resolve_table",
]


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
    if not isinstance(data["domain"], str) or data["domain"] not in _domain_names():
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
        domain=dom,
        shape=data["shape"],
        made_by=data["made_by"],
        entries=entries,
        parameters=parameters,
        version=data["version"],
        source=source,
    )


def _domain_names() -> list[str]:
    return list(domain_names())


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
    dom = table.domain
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
        "domain": dom.name,
        "format": FORMAT_NAME,
        "made_by": table.made_by.value,
        "parameters": dict(table.parameters),
        "shape": table.shape.value,
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


@cache
def bundled_table_names() -> tuple[str, ...]:
    """Names of the tables shipped as package data."""
    folder = resources.files("selfrepair").joinpath("data", "tables")
    return tuple(
        sorted(p.name[: -len(".json")] for p in folder.iterdir() if p.name.endswith(".json"))
    )


def bundled_table(name: str = "handwritten") -> ReplacementTable:
    """A table shipped with the package, e.g. ``"handwritten"`` or ``"three-action"`` (parsed
    once per process; a few are kept)."""
    if name not in bundled_table_names():
        raise TableError(
            f"expected a bundled table name ({', '.join(bundled_table_names())})", source=name
        )
    return _BUNDLED.get(name, lambda: _read_bundled(name))


def _read_bundled(name: str) -> ReplacementTable:
    resource = resources.files("selfrepair").joinpath("data", "tables", f"{name}.json")
    return parse_table(resource.read_text(encoding="utf-8"), source=f"<bundled:{name}>")


_BUNDLED: BoundedCache[str, ReplacementTable] = BoundedCache("bundled tables", 8)
_FILES: BoundedCache[tuple[str, int, int], ReplacementTable] = BoundedCache("table files", 8)


def resolve_table(spec: str | Path) -> ReplacementTable:
    """A bundled table by name, else a table file by path. A file is read again when its size or
    modification time changed since it was last read in this process."""
    text = str(spec)
    if text in bundled_table_names():
        return bundled_table(text)
    path = Path(text)
    try:
        info = path.stat()
    except OSError:
        return load_table(path)  # raises the TableError that names the problem
    key = (str(path.resolve()), info.st_mtime_ns, info.st_size)
    return _FILES.get(key, lambda: load_table(path))
