"""The Typer application object and the helpers every command module shares.

Command modules register themselves on :data:`app` (or on one of its groups) at import time;
:mod:`selfrepair.cli` imports them all. Commands return an ``int`` exit code (0 unless stated) and
raise :class:`selfrepair.errors.SelfRepairError` for bad input: :func:`selfrepair.cli.main` turns
that into one line on stderr and exit code 2.

Start-up stays fast: a command module imports only the standard library, typer and this module
at its top; numpy, rich, numba, pydantic, joblib, matplotlib and the library modules that pull
them in are imported inside the command functions (a test checks ``selfrepair --help``, every
command's ``--help`` and ``selfrepair actions``). Sub-command groups are made with
:func:`command_group`, so that their commands keep these conventions. Typer reads the
signature of every command on each start, so the command modules do not use ``from __future__
import annotations`` (string annotations would be compiled again on every start; names imported
only for type checking are quoted instead). Help is plain text (``rich_markup_mode=None``): no
type labels such as ``<bool>``, and the same text on a terminal and in a pipe.
"""

from __future__ import annotations

import functools
import inspect
import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import MISSING, fields
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer
from typer.core import TyperArgument, TyperCommand, TyperGroup

if TYPE_CHECKING:
    from rich.console import Console

_F = TypeVar("_F", bound=Callable[..., object])


def _no_type_label(ctx: Any) -> None:
    return None


def _quick(param: Any) -> None:
    """Let an option that was not given (value ``None``) skip Typer's value coercion.

    Typer 0.29 coerces parameter values through pydantic and imports it to do so, even for a
    value that was not given and stays ``None`` (the ``--help`` flag, the global ``--plugin``
    option); a value that was given is coerced as before. A required parameter without a value
    still goes through Typer, which reports it missing."""
    if getattr(param, "_selfrepair_quick", False):
        return
    process = param.process_value
    multiple = bool(param.multiple or param.nargs == -1)

    def process_value(ctx: Any, value: Any) -> Any:
        if value is not None or param.required:
            return process(ctx, value)
        empty = () if multiple else None
        return empty if param.callback is None else param.callback(ctx, param, empty)

    param.process_value = process_value
    param._selfrepair_quick = True


DOMAINS = "{domains}"
"""In an option's help: replaced, when help is shown, by the registered robot domains (with
the files given to ``--plugin``, which are loaded before a command's help is made)."""
FAULT_EXAMPLES = "{fault_examples}"
"""In an option's help: replaced, when help is shown, by an example fault set of each robot."""


def robot_help(text: str) -> str:
    """``text`` with :data:`DOMAINS` and :data:`FAULT_EXAMPLES` filled in from the domain
    registry (only when the text holds one: the registry is not imported otherwise)."""
    if DOMAINS not in text and FAULT_EXAMPLES not in text:
        return text
    from selfrepair.errors import SelfRepairError
    from selfrepair.robots.registry import domain_names, get_domain

    names = domain_names()
    examples = []
    for name in names:
        try:
            domain = get_domain(name)
        except SelfRepairError:  # a broken installed plug-in: its own error comes on use
            continue
        if domain.faults:
            first, last = domain.faults[0], domain.faults[-1]
            example = domain.format_faults([first, last] if last != first else [first])
            examples.append(f"{example} ({name})")
    return text.replace(DOMAINS, ", ".join(names)).replace(FAULT_EXAMPLES, "; ".join(examples))


class _QuickHelp:
    """Three small changes to Typer's commands: options that were not given cost no import,
    help has no type labels, and help names the robots this process knows (:func:`robot_help`).

    See :func:`_quick` for the first (so ``selfrepair --help`` and ``selfrepair actions`` import
    no pydantic). For the second, the help of an argument shows its metavar alone (``MAZE``),
    not followed by a type label (``MAZE <str>``); options show their metavar
    (``--start X,Y,H``) and flags nothing. Parsing is unchanged."""

    def get_params(self, ctx: Any) -> Any:
        params = super().get_params(ctx)  # type: ignore[misc]
        for param in params:
            _quick(param)
            if isinstance(param, TyperArgument):
                param.display_type_rich = _no_type_label  # type: ignore[method-assign]
        return params

    def format_help(self, ctx: Any, formatter: Any) -> None:
        for param in self.get_params(ctx):
            template = getattr(param, "_selfrepair_help", None) or getattr(param, "help", None)
            if template and (DOMAINS in template or FAULT_EXAMPLES in template):
                param._selfrepair_help = template
                param.help = robot_help(template)
        super().format_help(ctx, formatter)  # type: ignore[misc]


class _Command(_QuickHelp, TyperCommand):
    pass


class _Group(_QuickHelp, TyperGroup):
    pass


class _Typer(typer.Typer):
    """A Typer whose commands are :class:`_Command` and whose groups are :class:`_Group`."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(cls=_Group, rich_markup_mode=None, **kwargs)

    def command(self, *args: Any, **kwargs: Any) -> Callable[[_F], _F]:
        kwargs.setdefault("cls", _Command)
        decorator: Callable[[_F], _F] = super().command(*args, **kwargs)
        return decorator


def command_group(*, help: str) -> typer.Typer:
    """A sub-command group with this CLI's conventions (quick options, help without type
    labels); a command module adds it with ``app.add_typer(group, name=...)``."""
    return _Typer(help=help, no_args_is_help=True)


def option(name: str, metavar: str, help: str, **more: Any) -> Any:
    """The option ``name METAVAR`` with ``help`` (every option that takes a value names both), for
    ``param: Annotated[type, option(...)] = default``; ``more`` goes to :func:`typer.Option`
    (``min``, ``max``, ``show_default``). A parameter typed ``list[...] | None`` makes it
    repeatable. An option with a short name too (``-o``) uses :func:`typer.Option` itself."""
    return typer.Option(name, metavar=metavar, help=help, **more)


def flag(name: str, help: str) -> Any:
    """The on/off option ``name`` (``--json``, or a pair ``--warm-up/--no-warm-up``) with
    ``help``, for ``param: Annotated[bool, flag(...)] = default``."""
    return typer.Option(name, help=help)


def option_group(group: type, parameter: str) -> Callable[[Callable[..., int]], Callable[..., int]]:
    """A decorator that gives a command every field of the dataclass ``group`` as a parameter of
    its own (Typer reads them from the signature), in place of its parameter ``parameter``, which
    it is then called with: the fields' values gathered in one ``group``.

    Each field is typed with an option alias (or an argument) and has the option's default; the
    dataclass's module does not use ``from __future__ import annotations`` (Typer needs the field
    types as objects). Use it below ``@app.command()``; the command's other parameters keep their
    place around the group's."""
    names = tuple(f.name for f in fields(group))
    shared = [
        inspect.Parameter(
            f.name,
            inspect.Parameter.KEYWORD_ONLY,
            annotation=f.type,
            default=inspect.Parameter.empty if f.default is MISSING else f.default,
        )
        for f in fields(group)
    ]

    def decorate(command: Callable[..., int]) -> Callable[..., int]:
        own = inspect.signature(command).parameters
        if parameter not in own or set(names) & set(own):
            from selfrepair.errors import ProblemError

            raise ProblemError(
                f"{command.__name__}: expected a parameter {parameter!r} and none named as a "
                f"field of {group.__name__}"
            )
        params: list[inspect.Parameter] = []
        for param in own.values():
            keyword = param.replace(kind=inspect.Parameter.KEYWORD_ONLY)
            params.extend(shared if param.name == parameter else [keyword])

        @functools.wraps(command)
        def with_group(**values: Any) -> int:
            gathered = group(**{name: values.pop(name) for name in names})
            return command(**{parameter: gathered}, **values)

        with_group.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
            params, return_annotation=int
        )
        with_group.__annotations__ = {p.name: p.annotation for p in params}
        with_group.__annotations__["return"] = int
        return with_group

    return decorate


app = _Typer(
    name="selfrepair",
    help="Self-repairing robot plans: replacement tables versus replanning from scratch.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"max_content_width": 100},
)
maze_app = command_group(help="Show, list and generate mazes; draw routes for them.")
table_app = command_group(help="Replacement tables: show, check, generate, coverage.")
app.add_typer(maze_app, name="maze")
app.add_typer(table_app, name="table")

FLOAT_DIGITS = 6
"""Decimal places of the floats the commands print as JSON (exact values go as strings)."""


@app.callback()
def _global_options(
    plugin: Annotated[
        list[Path] | None,
        option(
            "--plugin",
            "FILE",
            "A Python file that registers a robot domain (repeatable); see docs/extending.md.",
        ),
    ] = None,
) -> None:
    """Self-repairing robot plans: replacement tables versus replanning from scratch."""
    if plugin:
        from selfrepair.robots.registry import load_plugin

        for path in plugin:
            load_plugin(path)


def console() -> Console:
    """A rich console on the current stdout (looked up per call so tests can capture it).

    When stdout is not a terminal the console is wide (tables are never cut in logs and pipes)."""
    from rich.console import Console

    if sys.stdout.isatty():
        return Console(file=sys.stdout, soft_wrap=True, highlight=False)
    return Console(file=sys.stdout, width=1000, soft_wrap=True, highlight=False)


def echo(text: str = "") -> None:
    """Print plain text to stdout."""
    sys.stdout.write(text + "\n")


def echo_json(data: object) -> None:
    """Print ``data`` as indented, valid JSON to stdout (never ``NaN`` or ``Infinity``: a
    non-finite number is a bug and raises ``ValueError`` instead of printing invalid JSON)."""
    sys.stdout.write(json.dumps(data, indent=2, allow_nan=False) + "\n")


# --- limits: one flag per limit of selfrepair.limits, the same on every command ----------------
# A command declares ``max_cells: MaxCells = MAX_CELLS`` and so on; --help shows the default.

def limit_option(flag: str, help: str, *, least: int = 1) -> Any:
    """The option of one limit of :mod:`selfrepair.limits`: ``flag N``, a whole number of at least
    ``least``, with ``help`` (what is refused past it)."""
    return option(flag, "N", help, min=least)


MaxCells = Annotated[
    int,
    limit_option("--max-cells", "Refuse a maze (file, map or generated) of more cells than this."),
]
MaxMissions = Annotated[
    int, limit_option("--max-missions", "Refuse an experiment of more missions than this.")
]
MaxTableBytes = Annotated[
    int, limit_option("--max-table-bytes", "Refuse a table file larger than this, unread.")
]
MaxLookupPatterns = Annotated[
    int,
    limit_option(
        "--max-lookup-patterns",
        "Occupancy patterns one compiled table look-up stores at most (past it, answers are "
        "computed each time).",
        least=0,
    ),
]
MaxTableCandidates = Annotated[
    int,
    limit_option(
        "--max-table-candidates",
        "Refuse a table of more candidates than this, before re-simulating any.",
    ),
]
MaxFileBytes = Annotated[
    int,
    limit_option(
        "--max-file-bytes",
        "Refuse a scenario, route, experiment or team file larger than this, unread.",
    ),
]
MaxTraceBytes = Annotated[
    int, limit_option("--max-trace-bytes", "Refuse a trace file larger than this, unread.")
]
MaxRobots = Annotated[
    int, limit_option("--max-robots", "Refuse a scenario of more robots than this.")
]
MaxTasks = Annotated[
    int, limit_option("--max-tasks", "Refuse a scenario of more tasks than this.", least=0)
]


def number_json(value: Fraction | float | int | None) -> int | float | None:
    """A JSON number: integers stay exact, anything else is rounded to :data:`FLOAT_DIGITS`
    decimals (``None`` and NaN become ``null``)."""
    if value is None:
        return None
    if isinstance(value, Fraction):
        return value.numerator if value.denominator == 1 else round(float(value), FLOAT_DIGITS)
    if isinstance(value, int):
        return value
    return None if math.isnan(value) else round(value, FLOAT_DIGITS)


def exact_json(value: Fraction | None) -> str | None:
    """An exact number as a JSON string, always (``"262"``, ``"31/3"``)."""
    return None if value is None else str(value)


def text_table(headers: Sequence[str], rows: Sequence[Sequence[str]], right: set[int]) -> str:
    """A plain aligned table (no rich): a header, a rule, the rows; columns in ``right`` are
    right-aligned. For commands that must start fast."""
    widths = [max([len(h), *(len(r[i]) for r in rows)]) for i, h in enumerate(headers)]

    def line(cells: Sequence[str]) -> str:
        parts = [c.rjust(w) if i in right else c.ljust(w) for i, (c, w) in enumerate(
            zip(cells, widths, strict=True))]
        return "  ".join(parts).rstrip()

    rule = "  ".join("-" * w for w in widths)
    return "\n".join([line(headers), rule, *(line(r) for r in rows)]) + "\n"
