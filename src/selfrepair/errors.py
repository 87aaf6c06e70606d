"""The one error hierarchy of selfrepair.

Outcomes (no plan, no replacement, mission failed) are data on result values; these exceptions are
for misuse and bad input only. The CLI turns every :class:`SelfRepairError` into a single line on
stderr and exit code 2, so each message must stand on its own: it names the file, the line and
column where known, and what was expected.
"""

from __future__ import annotations

from enum import StrEnum
from typing import TypedDict, TypeVar, Unpack

__all__ = [
    "ConfigError",
    "InputError",
    "LimitError",
    "ProblemError",
    "SelfRepairError",
    "TableError",
    "TraceError",
    "Where",
    "choice",
]

_E = TypeVar("_E", bound=StrEnum)


class SelfRepairError(Exception):
    """Root of every error that selfrepair raises on purpose."""


class Where(TypedDict, total=False):
    """Where in an input an :class:`InputError` is (the keywords of every input error):
    ``source``, a file path or a short label such as ``"<string>"`` or ``"--faults"``, and the
    1-based ``line`` and ``column`` (``None`` when they do not apply)."""

    source: str
    line: int | None
    column: int | None


class InputError(SelfRepairError, ValueError):
    """Text that does not parse: a maze, scenario, action, fault, route, table or trace.

    ``source``, ``line`` and ``column`` say where (:class:`Where`).
    """

    def __init__(
        self,
        message: str,
        *,
        source: str = "<input>",
        line: int | None = None,
        column: int | None = None,
    ) -> None:
        self.source = source
        self.line = line
        self.column = column
        self.reason = message
        super().__init__(self._render())

    def _render(self) -> str:
        where = self.source
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        return f"{where}: {self.reason}"


class LimitError(InputError):
    """Input that would take more than a documented size limit (:mod:`selfrepair.limits`).

    Raised before the work the limit guards starts. ``limit`` is the limit's name, which is also
    the keyword argument that sets it (``max_cells``); the message names it and the command-line
    flag that raises it (``--max-cells``), unless ``note`` says something else.
    """

    def __init__(
        self,
        message: str,
        *,
        limit: str,
        note: str | None = None,
        **where: Unpack[Where],
    ) -> None:
        self.limit = limit
        self.message = message
        """The message without the note on the limit."""
        flag = "--" + limit.replace("_", "-")
        note = f"raise it with {flag}" if note is None else note
        super().__init__(f"{message} (limit {limit}; {note})", **where)


class TableError(InputError):
    """A replacement table that is malformed or contains an entry that does not re-simulate."""


class TraceError(InputError):
    """A trace file that is malformed (a trace that parses but does not replay is a result)."""


class ConfigError(InputError):
    """An experiment configuration with a missing, unknown or ill-typed key."""


class ProblemError(SelfRepairError, ValueError):
    """A request that cannot be posed: a start inside a wall, a goal outside the grid, an unknown
    strategy or heuristic name, a negative budget."""


def choice(kind: type[_E], value: object, what: str, *, source: str | None = None) -> _E:
    """``value`` as a member of the string enum ``kind``; anything else raises
    :class:`ProblemError` naming ``what`` and the allowed values, or, for a value read from input
    ``source``, an :class:`InputError` naming it."""
    try:
        return kind(value)  # type: ignore[arg-type]  # any value may be tried
    except ValueError:
        allowed = ", ".join(member.value for member in kind)
        message = f"unknown {what} {value!r}; expected one of {allowed}"
        if source is None:
            raise ProblemError(message) from None
        raise InputError(message, source=source) from None
