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

What is refused before the work it would cost: a file larger than ``max_table_bytes`` (before it is
read), JSON nested deeper than :data:`MAX_JSON_DEPTH` (before it is parsed; the format needs 5
levels), integers of more than 18 digits, ``NaN`` and infinite numbers, and more than
``max_table_candidates`` candidates (before any is re-simulated). The header's ``version`` is an
integer (``true`` is not), ``domain``, ``shape`` and ``made_by`` are strings, and ``parameters``
maps names to JSON scalars or lists of scalars. A leading UTF-8 byte-order mark is ignored.
"""

from __future__ import annotations

import json
import math
import re
from importlib import resources
from pathlib import Path
from typing import cast

import numpy as np

from selfrepair.caching import BoundedCache, CacheKind
from selfrepair.errors import InputError, TableError
from selfrepair.limits import MAX_TABLE_BYTES, MAX_TABLE_CANDIDATES, check_limit
from selfrepair.robots.domain import A, Domain, F
from selfrepair.robots.registry import domain_names, get_domain
from selfrepair.tables.generate import generate_table
from selfrepair.tables.model import (
    FORMAT_NAME,
    Candidate,
    MadeBy,
    ReplacementTable,
    SomeTable,
    TableEntry,
    TableShape,
)
from selfrepair.textio import JSONObject, JSONValue, read_text, strip_bom

__all__ = [
    "MAX_JSON_DEPTH",
    "bundled_table",
    "bundled_table_names",
    "default_table",
    "default_table_name",
    "dump_table",
    "load_table",
    "parse_table",
    "resolve_table",
]


MAX_JSON_DEPTH = 8
"""Deepest JSON nesting a table file may have: the format needs 5 (object, ``entries`` list,
entry object, ``candidates`` list, candidate list); the rest leaves room for a telling message
about a near miss. Deeper input is refused before it is parsed (100,000 ``[`` used to crash the
JSON parser with a RecursionError)."""

_MAX_INT_DIGITS = 18
_SCALARS = (str, int, float, bool, type(None))


class _BadNumber(ValueError):
    """A JSON number the format does not take: NaN, infinite, or an integer of too many digits."""

    def __init__(self, text: str, reason: str) -> None:
        super().__init__(reason)
        self.text = text
        self.reason = reason


def _json_int(text: str) -> int:
    if len(text.removeprefix("-")) > _MAX_INT_DIGITS:
        raise _BadNumber(text, f"expected an integer of at most {_MAX_INT_DIGITS} digits")
    return int(text)


def _json_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _BadNumber(text, f"expected a finite number, got {text[:40]}")
    return value


def _json_constant(text: str) -> float:
    raise _BadNumber(text, f"expected a JSON number, got {text}")


def parse_table(
    text: str,
    source: str = "<string>",
    *,
    max_table_bytes: int | None = MAX_TABLE_BYTES,
    max_table_candidates: int | None = MAX_TABLE_CANDIDATES,
) -> SomeTable:
    """Parse and validate a table in the JSON format of the module docstring.

    ``max_table_bytes`` bounds the text's length in characters (a lower bound of its size in
    bytes) and ``max_table_candidates`` the candidates counted before any is re-simulated;
    either raises :class:`~selfrepair.errors.LimitError` (``None``: no limit).
    """
    check_limit(
        len(text), max_table_bytes, name="max_table_bytes", what="characters", source=source
    )
    text = strip_bom(text)
    _check_nesting(text, source)
    data = _load_json(text, source)
    if not isinstance(data, dict):
        raise TableError("expected a JSON object at the top level", source=source)
    if data.get("format") != FORMAT_NAME:
        raise TableError(
            f'expected "format": "{FORMAT_NAME}", got {_short(data.get("format"))}', source=source
        )
    for key in ("version", "domain", "shape", "made_by", "entries"):
        if key not in data:
            raise TableError(f"expected a {key!r} key in the header", source=source)
    name, parameters = _check_header(data, source)
    dom = get_domain(name)
    raw_entries = data["entries"]
    if not isinstance(raw_entries, list):
        raise TableError('expected "entries" to be a list', source=source)
    check_limit(
        _count_candidates(raw_entries),
        max_table_candidates,
        name="max_table_candidates",
        what="candidates",
        source=source,
    )
    lines = _entry_lines(text, len(raw_entries))
    entries = tuple(
        _parse_entry(dom, raw, number, lines[number], source)
        for number, raw in enumerate(raw_entries)
    )
    return ReplacementTable(
        domain=dom,
        # strings, converted (or refused, naming the allowed values) by ReplacementTable
        shape=cast(TableShape, data["shape"]),
        made_by=cast(MadeBy, data["made_by"]),
        entries=entries,
        parameters=parameters,
        version=cast(int, data["version"]),  # an int: _check_header says so
        source=source,
    )


def _load_json(text: str, source: str) -> JSONValue:
    try:
        return cast(
            JSONValue,
            json.loads(
                text, parse_int=_json_int, parse_float=_json_float, parse_constant=_json_constant
            ),
        )
    except json.JSONDecodeError as exc:
        raise TableError(
            f"expected JSON: {exc.msg}", source=source, line=exc.lineno, column=exc.colno
        ) from None
    except _BadNumber as exc:
        line, column = _position(text, max(text.find(exc.text), 0))
        raise TableError(exc.reason, source=source, line=line, column=column) from None
    except RecursionError:  # not reached after _check_nesting; kept as a safety net
        raise TableError(
            f"expected JSON nested at most {MAX_JSON_DEPTH} deep", source=source
        ) from None


def _check_nesting(text: str, source: str) -> None:
    """Refuse JSON nested deeper than :data:`MAX_JSON_DEPTH`, before the parser recurses.

    Works on the UTF-8 bytes with numpy: escaped backslashes and quotes are blanked (keeping
    offsets), quotes toggle "inside a string", and the running count of ``[{`` minus ``]}``
    outside strings is the depth.
    """
    data = text.encode("utf-8", "surrogatepass").replace(b"\\\\", b"  ").replace(b'\\"', b"  ")
    raw = np.frombuffer(data, dtype=np.uint8)
    outside = ~np.logical_xor.accumulate(raw == ord('"')) if raw.size else raw.astype(bool)
    opens = ((raw == ord("[")) | (raw == ord("{"))) & outside
    brackets = np.flatnonzero(opens | (((raw == ord("]")) | (raw == ord("}"))) & outside))
    depth = np.cumsum(np.where(opens[brackets], 1, -1))
    too_deep = np.flatnonzero(depth > MAX_JSON_DEPTH)
    if too_deep.size:
        offset = int(brackets[too_deep[0]])
        line = data.count(b"\n", 0, offset) + 1
        start = data.rfind(b"\n", 0, offset) + 1
        column = len(data[start:offset].decode("utf-8", "replace")) + 1
        raise TableError(
            f"expected JSON nested at most {MAX_JSON_DEPTH} deep (a table needs 5)",
            source=source,
            line=line,
            column=column,
        )


def _position(text: str, index: int) -> tuple[int, int]:
    """The 1-based line and column of ``text[index]``."""
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1


def _short(value: object) -> str:
    """``value`` as JSON, cut to 60 characters, for messages."""
    text = json.dumps(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _check_header(data: JSONObject, source: str) -> tuple[str, dict[str, JSONValue]]:
    """Types of the header fields (their values are checked by :class:`ReplacementTable`);
    returns the domain's name and the parameters."""
    if type(data["version"]) is not int:  # bool is an int in Python: refuse it explicitly
        raise TableError(
            f'expected "version" to be an integer, got {_short(data["version"])}', source=source
        )
    for key in ("domain", "shape", "made_by"):
        if not isinstance(data[key], str):
            raise TableError(
                f"expected {key!r} to be a string, got {_short(data[key])}", source=source
            )
    name = data["domain"]
    if not isinstance(name, str) or name not in _domain_names():
        raise TableError(
            f"expected a domain in {', '.join(_domain_names())}, got {name!r}",
            source=source,
        )
    parameters = data.get("parameters", {})
    if not isinstance(parameters, dict):
        raise TableError('expected "parameters" to be an object', source=source)
    for key, value in parameters.items():
        items = value if isinstance(value, list) else [value]
        if not all(isinstance(item, _SCALARS) for item in items):
            raise TableError(
                f'expected "parameters" values to be strings, numbers, booleans, null or lists '
                f"of those, got {key!r}: {_short(value)}",
                source=source,
            )
    return name, parameters


def _count_candidates(raw_entries: list[JSONValue]) -> int:
    return sum(
        len(candidates)
        for raw in raw_entries
        if isinstance(raw, dict) and isinstance(candidates := raw.get("candidates"), list)
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
    dom: Domain[A, F], raw: JSONValue, number: int, line: int | None, source: str
) -> TableEntry[A, F]:
    def fail(what: str) -> TableError:
        return TableError(f"entry {number}: {what}", source=source, line=line)

    if not isinstance(raw, dict) or not isinstance(name := raw.get("action"), str):
        raise fail('expected an object with a string "action"')
    unknown = set(raw) - {"action", "faults", "candidates"}
    if unknown:
        raise fail(f"expected keys action, faults, candidates, got also {sorted(unknown)}")
    try:
        action = dom.parse_action(name)
        faults = None if "faults" not in raw else dom.parse_faults(_string(raw["faults"]))
    except InputError as exc:
        raise fail(exc.reason) from None
    candidates = raw.get("candidates")
    if not isinstance(candidates, list) or not all(isinstance(c, list) for c in candidates):
        raise fail('expected "candidates" to be a list of lists of action strings')
    parsed: list[Candidate[A]] = []
    for k, candidate in enumerate(candidates):
        try:
            parsed.append(
                tuple(dom.parse_action(_string(a)) for a in cast(list[JSONValue], candidate))
            )
        except InputError as exc:
            raise fail(f"candidate {k}: {exc.reason}") from None
    return TableEntry(action=action, candidates=tuple(parsed), faults=faults, line=line)


def _string(value: object) -> str:
    if not isinstance(value, str):
        raise InputError(f"expected a string, got {value!r}")
    return value


def load_table(
    path: str | Path,
    *,
    max_table_bytes: int | None = MAX_TABLE_BYTES,
    max_table_candidates: int | None = MAX_TABLE_CANDIDATES,
) -> SomeTable:
    """Read and validate a table file; errors name the file.

    A file larger than ``max_table_bytes`` is refused before it is read (a 2.9 GB file used to
    take 18 GB of memory); see :func:`parse_table` for ``max_table_candidates``.
    """
    text = read_text(
        path,
        what="table file",
        error=TableError,
        max_bytes=max_table_bytes,
        limit="max_table_bytes",
    )
    return parse_table(
        text,
        source=str(path),
        max_table_bytes=None,
        max_table_candidates=max_table_candidates,
    )


def _entry_sort_key(dom: Domain[A, F], entry: TableEntry[A, F]) -> tuple[int, int, str]:
    faults = entry.faults or frozenset()
    return (dom.actions.index(entry.action), len(faults), dom.format_faults(faults))


def dump_table(table: ReplacementTable[A, F]) -> str:
    """The table as deterministic JSON: sorted keys, entries in domain action order, one a line."""
    dom = table.domain
    rows = []
    for entry in sorted(table.entries, key=lambda e: _entry_sort_key(dom, e)):
        row: JSONObject = {
            "action": dom.format_action(entry.action),
            "candidates": [[dom.format_action(a) for a in c] for c in entry.candidates],
        }
        if entry.faults is not None:
            row["faults"] = dom.format_faults(entry.faults)
        rows.append("  " + json.dumps(row, sort_keys=True))
    header: JSONObject = {
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
        f" {json.dumps(k)}: {json.dumps(header[k], sort_keys=True, allow_nan=False)}"
        for k in ("format", "made_by", "parameters", "shape", "version")
    ]
    lines.append(",\n".join(rest))
    lines.append("}")
    return "\n".join(line for line in lines if line) + "\n"


_NAMES: BoundedCache[str, tuple[str, ...]] = BoundedCache(
    "bundled table names", 1, kind=CacheKind.INPUT
)


def bundled_table_names() -> tuple[str, ...]:
    """Names of the tables shipped as package data (listed once per process)."""

    def listing() -> tuple[str, ...]:
        folder = resources.files("selfrepair").joinpath("data", "tables")
        names = (p.name[: -len(".json")] for p in folder.iterdir() if p.name.endswith(".json"))
        return tuple(sorted(names))

    return _NAMES.get("tables", listing)


def bundled_table(name: str = "handwritten") -> SomeTable:
    """A table shipped with the package, e.g. ``"handwritten"`` or ``"three-action"`` (parsed
    once per process; a few are kept)."""
    if name not in bundled_table_names():
        raise TableError(
            f"expected a bundled table name ({', '.join(bundled_table_names())})", source=name
        )
    return _BUNDLED.get(name, lambda: _read_bundled(name))


def _read_bundled(name: str) -> SomeTable:
    resource = resources.files("selfrepair").joinpath("data", "tables", f"{name}.json")
    return parse_table(resource.read_text(encoding="utf-8"), source=f"<bundled:{name}>")


_BUNDLED: BoundedCache[str, SomeTable] = BoundedCache("bundled tables", 8, kind=CacheKind.INPUT)
_FILES: BoundedCache[tuple[str, int, int, int | None, int | None], SomeTable] = BoundedCache(
    "table files", 8, kind=CacheKind.INPUT
)


def resolve_table(
    spec: str | Path,
    *,
    max_table_bytes: int | None = MAX_TABLE_BYTES,
    max_table_candidates: int | None = MAX_TABLE_CANDIDATES,
) -> SomeTable:
    """A bundled table by name, else a table file by path, checked against the limits (see
    :func:`load_table`). A file is read again when its size or modification time changed since it
    was last read in this process, or when it is asked for with other limits."""
    text = str(spec)
    if text in bundled_table_names():
        return bundled_table(text)
    path = Path(text)

    def load() -> SomeTable:
        return load_table(
            path, max_table_bytes=max_table_bytes, max_table_candidates=max_table_candidates
        )

    try:
        info = path.stat()
    except OSError:
        return load()  # raises the TableError that names the problem
    key = (
        str(path.resolve()),
        info.st_mtime_ns,
        info.st_size,
        max_table_bytes,
        max_table_candidates,
    )
    return _FILES.get(key, load)


GENERATED_DEFAULT = "generated"
"""What :func:`default_table_name` calls a table generated for a robot that ships none."""


def default_table_name(domain: Domain[A, F]) -> str:
    """Which table :func:`default_table` gives ``domain``: ``"handwritten"`` (the paper's, for
    the four-wheel robot), the name of a bundled table named after the domain
    (``"three-action"``), else :data:`GENERATED_DEFAULT`."""
    if domain.name == "four-wheel":
        return "handwritten"
    if domain.name in bundled_table_names() and bundled_table(domain.name).domain is domain:
        return domain.name
    return GENERATED_DEFAULT


def default_table(domain: Domain[A, F]) -> ReplacementTable[A, F]:
    """The table a robot gets when none is named (the command line, the Gymnasium environment):
    the bundled table :func:`default_table_name` names, else one generated for the domain with
    the default options (fault-agnostic; made once per process for a few domains)."""
    name = default_table_name(domain)
    if name != GENERATED_DEFAULT:
        return bundled_table(name)
    # keyed by the domain itself, so the table is of that domain
    return cast("ReplacementTable[A, F]", _GENERATED.get(domain, lambda: generate_table(domain)))


_GENERATED: BoundedCache[object, object] = BoundedCache(
    "generated default tables", 4, kind=CacheKind.INPUT
)
