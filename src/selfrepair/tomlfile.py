"""TOML input files read into validated pydantic models, every problem naming file, line, key.

Experiment files (:mod:`selfrepair.experiment.config`, :mod:`selfrepair.experiment.teams`) and
team scenarios (:mod:`selfrepair.team.scenario`) are read the same way, here:

1. :func:`read_toml` parses the text (a leading byte-order mark dropped); a syntax error, a file
   nested too deep or an integer of thousands of digits is a :class:`~selfrepair.errors.ConfigError`
   with its line.
2. :func:`validate` checks the data against a frozen pydantic model (:class:`Frozen`: unknown keys
   refused, integers strict through :data:`Int`, floats refusing booleans through :data:`Float`);
   the most telling validation problem becomes one ``ConfigError`` (:func:`validation_error`) that
   names the key as a dotted path (``strategies[1].tables``), its line and what was expected.
3. :func:`find_line` finds the line of a key path in the text, following ``[[array]]`` headers by
   index and ``[table]`` headers by name; checks made after validation use it to point at the
   line they complain about.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Collection, Mapping
from typing import Annotated, Any, TypeVar

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError

from selfrepair.errors import ConfigError
from selfrepair.textio import strip_bom, text_lines

__all__ = [
    "Float",
    "Frozen",
    "Int",
    "NonEmpty",
    "find_line",
    "read_toml",
    "validate",
    "validation_error",
]

# Strict numbers: TOML has real booleans and floats, and ``true`` or ``1.0`` where an integer is
# expected is a mistake to report, not a 1 to guess (pydantic's lax mode would take both).
Int = Annotated[int, Field(strict=True)]
"""An integer that refuses booleans and floats."""
Float = Annotated[float, Field(strict=True)]
"""A number that refuses booleans (strict floats still take integers)."""


class Frozen(BaseModel):
    """The base of every file model: frozen, unknown keys refused."""

    model_config = ConfigDict(frozen=True, extra="forbid", strict=False)


def _non_empty(value: tuple[T, ...]) -> tuple[T, ...]:
    if not value:
        raise ValueError("expected a non-empty list")
    return value


NonEmpty = AfterValidator(_non_empty)
"""Marks a list option that must hold at least one item: ``Annotated[tuple[X, ...], NonEmpty]``
(an empty list in a file is an error naming the key, not an empty sweep)."""

Model = TypeVar("Model", bound=BaseModel)
T = TypeVar("T")


def read_toml(text: str, *, source: str = "<string>") -> dict[str, Any]:
    """TOML ``text`` (a byte-order mark dropped) as a dict; every syntax problem is a
    :class:`ConfigError` with its line and column where known."""
    text = strip_bom(text)
    try:
        return tomllib.loads(text)
    except RecursionError:
        raise ConfigError(
            "invalid TOML: arrays or inline tables nested too deep (a selfrepair file needs 3 "
            "levels)",
            source=source,
        ) from None
    except tomllib.TOMLDecodeError as exc:
        where = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        reason = re.sub(r"\s*\(at (line \d+, column \d+|end of document)\)", "", str(exc))
        line, column = (int(where.group(1)), int(where.group(2))) if where else (None, None)
        raise ConfigError(
            f"invalid TOML: {reason}", source=source, line=line, column=column
        ) from None
    except ValueError:  # an integer beyond Python's 4300-digit conversion limit
        long = re.search(r"[0-9_]{4300,}", text)
        line = None if long is None else text.count("\n", 0, long.start()) + 1
        raise ConfigError(
            "invalid TOML: expected an integer of at most 4300 digits", source=source, line=line
        ) from None


def validate(
    model: type[Model],
    data: Mapping[str, Any],
    *,
    text: str,
    source: str,
    context: Mapping[str, Any] | None = None,
    tags: Collection[str] = (),
    tag_name: str = "name",
) -> Model:
    """``data`` (read from ``text``) as a ``model``; a validation problem is one
    :class:`ConfigError` (see :func:`validation_error`; ``tags`` are the discriminator values of
    the model's tagged unions, dropped from key paths; a wrong tag is "expected a ``tag_name``").
    ``context`` reaches the validators."""
    try:
        return model.model_validate(dict(data), context=dict(context or {}))
    except ValidationError as exc:
        raise validation_error(exc, text, source, tags=tags, tag_name=tag_name) from None


_TYPE_MISMATCH = ("literal_error", "int_type", "int_parsing", "string_type", "float_type")


def _most_telling(errors: list[Any]) -> Any:
    """For a value that may take several forms (``routes`` is "bundled", a count or a list),
    pydantic reports one error per form. The telling one went deepest into the value, and among
    those, one whose form matched the value's type; otherwise the first error."""

    def rank(error: Any) -> tuple[int, bool]:
        mismatch = error["type"] in _TYPE_MISMATCH or error["type"].endswith("_type")
        return len(error["loc"]), not mismatch

    return max(errors, key=rank)


def validation_error(
    exc: ValidationError,
    text: str,
    source: str,
    *,
    tags: Collection[str] = (),
    tag_name: str = "name",
) -> ConfigError:
    """The most telling problem of ``exc`` as a ConfigError naming key, line and expectation."""
    error = _most_telling(exc.errors())
    loc = _clean_loc(error["loc"], tags)
    key = dotted(loc) or "<top level>"
    message = error["msg"].removeprefix("Value error, ")
    if error["type"] == "extra_forbidden":
        message = "unknown key"
    elif error["type"] == "missing":
        message = "missing required key"
    elif error["type"] == "union_tag_invalid":
        loc = (*loc, "name")
        key = dotted(loc)
        # the tags as written in the file (pydantic writes enum tags as their reprs)
        expected = ", ".join(repr(str(tag)) for tag in tags) or error.get("ctx", {}).get(
            "expected_tags", ""
        )
        message = f"expected a {tag_name}, one of {expected}"
        got = error.get("input", {}).get("name") if isinstance(error.get("input"), dict) else None
        return ConfigError(
            f"key {key!r}: {message} (got {got!r})", source=source, line=find_line(text, loc)
        )
    elif error["type"] in ("tuple_type", "list_type"):
        message = "expected a list"
    elif error["type"] == "too_short":
        message = f"expected a list of at least {error['ctx']['min_length']} item(s), got none"
    elif error["type"] in ("model_type", "model_attributes_type", "dict_type"):
        message = "expected a table"
    else:
        message = message.replace("Input should be", "expected")
    got = error.get("input")
    if (
        error["type"] not in ("missing", "extra_forbidden")
        and not isinstance(got, dict | list)
        and "got " not in message
    ):
        message += f" (got {got!r})"
    return ConfigError(f"key {key!r}: {message}", source=source, line=find_line(text, loc))


_UNION_MEMBERS = ("int", "str", "tuple", "float", "bool", "constrained-int", "function-after")


def _clean_loc(loc: tuple[Any, ...], tags: Collection[str]) -> tuple[str | int, ...]:
    """Drop pydantic's union-member labels (a tag such as ``'replacement'``, a type such as
    ``'int'`` or ``'tuple[...]'``) from a location, leaving the keys and indices of the file."""
    out: list[str | int] = []
    for part in loc:
        if isinstance(part, str) and (part in tags or "[" in part or part in _UNION_MEMBERS):
            continue
        out.append(part)
    return tuple(out)


def dotted(loc: tuple[str | int, ...]) -> str:
    """A key path as text: ``("strategies", 1, "tables")`` -> ``strategies[1].tables``."""
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text


_HEADER = re.compile(r"^\s*\[\[?\s*([A-Za-z0-9_.\-\"']+)\s*\]\]?")


def find_line(text: str, loc: tuple[str | int, ...]) -> int | None:
    """Best-effort 1-based line of the key at ``loc`` in TOML ``text`` (None when not found).

    Follows ``[[array]]`` headers by index and ``[table]`` headers by name, then looks for
    ``key =`` inside the section found so far (the section's header line when the key is not
    written there, e.g. a missing key).
    """
    lines = text_lines(strip_bom(text))
    start, end = 0, len(lines)
    found: int | None = None
    section = ""
    i = 0
    while i < len(loc):
        part = loc[i]
        nxt = loc[i + 1] if i + 1 < len(loc) else None
        if isinstance(part, int):
            i += 1
            continue
        name = f"{section}.{part}" if section else part
        if isinstance(nxt, int):
            hit = _nth_header(lines, name, nxt, start, end)
            if hit is not None:
                start, end, section, found = hit[0] + 1, hit[1], name, hit[0] + 1
                i += 2
                continue
        hit = _nth_header(lines, name, 0, start, end)
        if hit is not None:
            start, end, section, found = hit[0] + 1, hit[1], name, hit[0] + 1
            i += 1
            continue
        key_line = _key_line(lines, part, start, end)
        if key_line is None:
            return found
        return key_line + 1
    return found


def _nth_header(
    lines: list[str], name: str, index: int, start: int, end: int
) -> tuple[int, int] | None:
    """The (header line, section end) of the ``index``-th ``[name]``/``[[name]]`` header."""
    count = -1
    for n in range(start, end):
        match = _HEADER.match(lines[n])
        if match and match.group(1).strip("\"'") == name:
            count += 1
            if count == index:
                stop = next(
                    (m for m in range(n + 1, len(lines)) if _HEADER.match(lines[m])), len(lines)
                )
                return n, stop
    return None


def _key_line(lines: list[str], key: str, start: int, end: int) -> int | None:
    pattern = re.compile(rf"^\s*[\"']?{re.escape(key)}[\"']?\s*=|[{{,]\s*{re.escape(key)}\s*=")
    for n in range(start, end):
        if _HEADER.match(lines[n]) and n > start:
            break
        if pattern.search(lines[n]):
            return n
    return None
