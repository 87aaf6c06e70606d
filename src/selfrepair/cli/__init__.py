"""Command-line interface: ``selfrepair COMMAND ...``.

:func:`main` runs the CLI in-process and returns the exit code, which is how the tests drive it;
:func:`run` is the console-script entry point.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import typer
from typer._click.exceptions import ClickException, NoArgsIsHelpError

# Importing the command modules registers their commands on ``app``; they import the heavy
# libraries inside the commands, so that ``selfrepair --help`` starts fast.
from selfrepair.cli import (  # noqa: F401
    basics,
    domains,
    execution,
    experiments,
    gym,
    pddl,
    physics,
    planning,
    tables,
    team,
    tolerance,
    view,
)
from selfrepair.cli._app import app
from selfrepair.errors import SelfRepairError

__all__ = ["app", "main", "run"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI with ``argv`` (default: ``sys.argv[1:]``) and return the exit code.

    Bad input (any :class:`~selfrepair.errors.SelfRepairError`, a usage error, or an
    :class:`OSError` such as an output path in a missing directory) becomes one line on stderr
    and exit code 2, never a traceback.
    """
    command = typer.main.get_command(app)
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        result = command.main(args=args, prog_name="selfrepair", standalone_mode=False)
    except SelfRepairError as exc:
        sys.stderr.write(f"selfrepair: error: {_one_line(str(exc))}\n")
        return 2
    except OSError as exc:  # an output path that cannot be written, a full disk, ...
        where = f"{exc.filename}: " if exc.filename is not None else ""
        sys.stderr.write(f"selfrepair: error: {where}{_one_line(exc.strerror or str(exc))}\n")
        return 2
    except NoArgsIsHelpError as exc:
        sys.stdout.write(exc.ctx.get_help() + "\n" if exc.ctx is not None else "")
        return 0
    except typer.Exit as exc:
        return int(exc.exit_code)
    except typer.Abort:
        sys.stderr.write("selfrepair: aborted\n")
        return 130
    except ClickException as exc:
        sys.stderr.write(f"selfrepair: error: {_one_line(exc.format_message())}\n")
        return 2
    return result if isinstance(result, int) else 0


def _one_line(text: str) -> str:
    return " ".join(text.split())


def run() -> None:
    """Console-script entry point."""
    sys.exit(main())
