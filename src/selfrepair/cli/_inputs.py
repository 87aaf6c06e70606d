"""What several commands take: the maze argument, the shared options, and finding input files.

Argument and option names are the same in every command (``MAZE``, ``--start X,Y,H``,
``--goal X,Y``, ``--faults FAULTS``, ``--backend NAME``, ``--json``), and every option has help.

:func:`find_input` lets a command run from anywhere inside a source checkout with the paths the
README shows (``tests/data/movingai/maze512-1-0.map``): a relative path that does not exist in the
working directory is looked up relative to the checkout the package was installed from (an
editable install; an installed wheel has no checkout and the path is taken as given).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from selfrepair.cli._app import flag, option
from selfrepair.errors import InputError

if TYPE_CHECKING:
    from selfrepair.robots.domain import A, Domain, F, SomeDomain
    pass

__all__ = [
    "Backend",
    "Braid",
    "ClearanceWeight",
    "Corridor",
    "DomainOpt",
    "Faults",
    "GoalPose",
    "Heuristic",
    "Json",
    "MaxExpansions",
    "MazeArg",
    "Start",
    "TableArg",
    "TimeLimit",
    "TraceArg",
    "TraceOut",
    "checkout_root",
    "domain_named",
    "find_input",
    "parse_faults",
    "parse_weight",
]

MazeArg = Annotated[
    str,
    typer.Argument(
        metavar="MAZE",
        help="A bundled maze name (see `maze list`), a .maze text file or a MovingAI .map file.",
        show_default=False,
    ),
]
Start = Annotated[str, option("--start", "X,Y,H", "Start pose (heading H: N, E, S or W).")]
GoalPose = Annotated[str, option("--goal", "X,Y[,H]", "Goal cell, or goal pose X,Y,H.")]
TableArg = Annotated[
    str, typer.Argument(metavar="TABLE", help="Table file or bundled name (e.g. handwritten).")
]
TraceArg = Annotated[
    Path, typer.Argument(metavar="TRACE", help="A JSON Lines trace written by run --trace.")
]
TraceOut = Annotated[Path | None, option("--trace", "FILE", "Write the JSON Lines trace here.")]
Corridor = Annotated[int, option("--corridor", "N", "Corridor width in cells.")]
Braid = Annotated[float, option("--braid", "P", "Share of dead ends to open (0 = perfect maze).")]
Faults = Annotated[
    str,
    option(
        "--faults",
        "FAULTS",
        "The robot's faults, comma-separated (none: ''), e.g. {fault_examples}.",
    ),
]
DomainOpt = Annotated[
    str, option("--domain", "NAME", "The robot: a registered domain name ({domains}).")
]
ClearanceWeight = Annotated[
    str,
    option(
        "--clearance-weight",
        "W",
        "Exact weight of the wall-clearance cost term, e.g. 1, 1/2 or 0.25.",
    ),
]
Heuristic = Annotated[
    str, option("--heuristic", "NAME", "A* heuristic: grid-distance, manhattan or zero.")
]
Backend = Annotated[
    str,
    option("--backend", "NAME", "Search backend: auto (numba when installed), numba or python."),
]
Json = Annotated[bool, flag("--json", "Print JSON instead of text.")]
MaxExpansions = Annotated[
    int | None, option("--max-expansions", "N", "Node budget of the search (expansions).")
]
TimeLimit = Annotated[float | None, option("--time-limit", "SECONDS", "Time budget of the search.")]


def checkout_root() -> Path | None:
    """The source checkout this package runs from (``src/selfrepair`` under a folder with
    ``pyproject.toml``), or ``None`` for an installed package."""
    import selfrepair

    package = Path(selfrepair.__file__).resolve().parent
    root = package.parent.parent
    if package.parent.name == "src" and (root / "pyproject.toml").is_file():
        return root
    return None


def find_input(spec: str) -> str:
    """``spec`` itself when it exists here (or is not a path at all), else the same relative
    path inside the source checkout when it exists there."""
    path = Path(spec)
    if path.exists() or path.is_absolute():
        return spec
    root = checkout_root()
    if root is not None and (root / path).exists():
        return str(root / path)
    if root is not None and path.suffix in (".map", ".scen"):
        hits = sorted(root.glob(f"tests/data/*/{path.name}"))
        if hits:
            raise InputError(
                f"no such file; the source checkout has it as {hits[0].relative_to(root)}",
                source=spec,
            )
    return spec


def parse_weight(text: str, option: str = "--clearance-weight") -> Fraction:
    """Parse an exact weight such as ``2``, ``1/3`` or ``0.25``, from 0 to
    :data:`~selfrepair.limits.MAX_CLEARANCE_WEIGHT`."""
    from selfrepair.limits import MAX_CLEARANCE_WEIGHT

    try:
        weight = Fraction(text.strip())
    except (ValueError, ZeroDivisionError) as exc:
        raise InputError(
            f"expected a number such as 2, 1/3 or 0.25, got {text[:40]!r}", source=option
        ) from exc
    if not 0 <= weight <= MAX_CLEARANCE_WEIGHT:
        raise InputError(
            f"expected a weight from 0 to {MAX_CLEARANCE_WEIGHT:,}, got {text[:40]!r}",
            source=option,
        )
    return weight


def domain_named(name: str) -> SomeDomain:
    """The registered domain ``name`` (bad names are an error on ``--domain``)."""
    from selfrepair.robots.registry import get_domain

    try:
        return get_domain(name)
    except InputError as exc:
        raise InputError(exc.reason, source="--domain") from None


def parse_faults(domain: Domain[A, F], text: str) -> frozenset[F]:
    """The fault set ``text`` names for ``domain`` (bad text is an error on ``--faults``)."""
    try:
        return domain.parse_faults(text)
    except InputError as exc:
        raise InputError(exc.reason, source="--faults") from None
