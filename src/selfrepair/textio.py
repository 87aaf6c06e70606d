"""Reading text files the same way in every reader: size first, UTF-8, rows split at ``\\n``.

Every reader of a text format (mazes, MovingAI maps and scenarios, tables, experiment files) reads
its file with :func:`read_text`, so a file that is too big, unreadable or not UTF-8 gets the same
kind of one-line error, naming the file, the line and the column of the first bad byte. Line-based
readers split with :func:`text_lines`: only ``\\n`` and ``\\r\\n`` end a line, so a form feed or a
Unicode line separator stays in its line, where the reader refuses it as a character with its
column (``str.splitlines`` would silently split there). A leading byte-order mark is the reader's
business: every reader of selfrepair accepts and ignores one (:func:`strip_bom`). Paths a file
names are relative to the file's directory (:func:`source_dir`). The writers of Markdown reports
lay their tables out with :func:`markdown_table`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TypeAlias

from selfrepair.errors import InputError, LimitError

__all__ = [
    "BOM",
    "JSONObject",
    "JSONValue",
    "markdown_table",
    "read_text",
    "source_dir",
    "strip_bom",
    "text_lines",
]

JSONValue: TypeAlias = "str | int | float | bool | list[JSONValue] | dict[str, JSONValue] | None"
"""A value as :func:`json.loads` returns it (or :func:`json.dumps` takes it): what a JSON file
holds, to be taken apart with ``isinstance`` checks rather than trusted."""

JSONObject: TypeAlias = "dict[str, JSONValue]"
"""A JSON object: the header of a table file, one row of a trace, one mission row."""

BOM = "\ufeff"
"""The UTF-8 byte-order mark as a character; some editors write it at the start of a file."""


def read_text(
    path: str | Path,
    *,
    what: str,
    error: type[InputError] = InputError,
    max_bytes: int | None = None,
    limit: str = "",
) -> str:
    """The text of the UTF-8 file ``path``; ``what`` names the kind of file in messages.

    With ``max_bytes``, a larger file is refused before it is read (and a device or pipe that
    goes on is refused once it has given more) with a :class:`LimitError` naming ``limit``.
    Other problems raise ``error`` (an :class:`InputError` subclass).
    """
    source = str(path)
    try:
        with open(path, "rb") as stream:
            if max_bytes is not None:
                size = Path(path).stat().st_size
                _check_size(size, max_bytes, what, limit, source, f"{size:,}")
                data = stream.read(max_bytes + 1)
                _check_size(len(data), max_bytes, what, limit, source, "more")
            else:
                data = stream.read()
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror or exc}", source=source) from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        column = len(data[line_start : exc.start].decode("utf-8", "replace")) + 1
        raise error(
            f"expected a UTF-8 text {what}, got the byte 0x{data[exc.start]:02x}",
            source=source,
            line=line,
            column=column,
        ) from None


def _check_size(size: int, max_bytes: int, what: str, limit: str, source: str, got: str) -> None:
    if size > max_bytes:
        raise LimitError(
            f"expected a {what} of at most {max_bytes:,} bytes, got {got}",
            limit=limit,
            source=source,
        )


def strip_bom(text: str) -> str:
    """``text`` without a leading byte-order mark."""
    return text.removeprefix(BOM)


def text_lines(text: str) -> list[str]:
    """The lines of ``text``, split at ``\\n`` only, without their ``\\r\\n`` or ``\\n`` ends.

    Like ``str.splitlines`` for ordinary text (a final line end does not start another line),
    but a lone ``\\r``, a form feed, U+2028 and the other separators ``splitlines`` knows stay
    inside their line.
    """
    lines = text.split("\n")
    if lines[-1] == "":
        lines.pop()
    return [line[:-1] if line.endswith("\r") else line for line in lines]


def source_dir(source: str) -> Path:
    """The directory that relative paths in the file ``source`` resolve against: the file's own,
    or the working directory for text that came from no file (a source such as ``<string>``)."""
    return Path(source).parent if not source.startswith("<") else Path.cwd()


def markdown_table(headers: Sequence[str], body: Sequence[Sequence[str]]) -> str:
    """A GitHub-flavoured Markdown table (first column left-aligned, the rest right-aligned)."""
    lines = ["| " + " | ".join(headers) + " |"]
    lines.append("|" + "|".join([":---"] + ["---:"] * (len(headers) - 1)) + "|")
    lines += ["| " + " | ".join(cells) + " |" for cells in body]
    return "\n".join(lines)
