"""The ``[planner]`` section and the ``[[strategies]]`` entries of an experiment file: one frozen
pydantic model per strategy, told apart by ``name`` (:data:`StrategyConfig`), apart from
:mod:`selfrepair.experiment.schema` (which holds the rest of the file's sections and
re-exports these) so that each module holds one job.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Annotated, Literal

from pydantic import Field, ValidationInfo, field_validator, model_validator

from selfrepair.errors import ProblemError
from selfrepair.experiment.schema_physics import context_domain as _domain
from selfrepair.limits import (
    DEFAULT_CONFIDENCE,
    DEFAULT_FAULT_PRIOR,
    DEFAULT_MAX_FAULTS,
    MAX_CLEARANCE_WEIGHT,
)
from selfrepair.repair.replacement import DEFERRING, RecursionMode
from selfrepair.repair.strategies import MissionKind, StrategyName
from selfrepair.repair.tolerance import OPTIMAL, parse_objective
from selfrepair.tomlfile import Float, Frozen, Int, NonEmpty

__all__ = [
    "STRATEGY_TAGS",
    "DStarLiteStrategy",
    "DiagnosisStrategy",
    "LookaheadStrategy",
    "LpgAdaptStrategy",
    "MazeNames",
    "PlannerConfig",
    "ReplacementStrategy",
    "ReplanStrategy",
    "StrategyConfig",
]

MazeNames = Annotated[tuple[str, ...], Field(min_length=1)] | None
"""A strategy's ``mazes``: the labels of the experiment's mazes it runs on (all when absent)."""


class PlannerConfig(Frozen):
    """Planner options shared by every strategy unless a strategy overrides the weights."""

    clearance_weights: tuple[str, ...] = ("0",)
    clearance_radius: Annotated[Int, Field(ge=0, le=64)] = 2

    @field_validator("clearance_weights", mode="before")
    @classmethod
    def _weights(cls, value: object) -> object:
        return _weights(value)


class _StrategyEntry(Frozen):
    """What every strategy entry has: its own clearance weights (else the planner's) and the
    labels of the mazes it runs on (else all)."""

    clearance_weights: tuple[str, ...] | None = None
    mazes: MazeNames = None

    @field_validator("clearance_weights", mode="before")
    @classmethod
    def _weights(cls, value: object) -> object:
        return _weights(value)


class ReplanStrategy(_StrategyEntry):
    """The baseline: replan from scratch at every faulty encounter, with the planner ``backend``
    (``auto``: the compiled kernels when numba is installed; ``python``: the pure-Python search,
    to compare with pure-Python strategies such as D* Lite)."""

    name: Literal[StrategyName.REPLAN]
    backend: Literal["auto", "numba", "python"] = "auto"


class ReplacementStrategy(_StrategyEntry):
    """Replacement tables with recursion mode; one variant per table, mode and ``rewrite``
    value (``true``: whole-plan rewriting, ``[false, true]``: both; default per encounter)."""

    name: Literal[StrategyName.REPLACEMENT]
    tables: Annotated[tuple[str, ...], NonEmpty] = ("handwritten",)
    recursion: Annotated[tuple[RecursionMode, ...], NonEmpty] = (RecursionMode.GUARDED,)
    rewrite: tuple[bool, ...] = (False,)
    objectives: Annotated[tuple[str, ...], NonEmpty] = (OPTIMAL,)
    """How the plan made before any fault is known is chosen: ``optimal`` (the plain cost, with
    the clearance weight), ``tolerant k=K`` (the cheapest plan tolerant of every set of 1 to K
    faults, else the optimum) or ``tolerant soft L k=K`` (L ticks per (step, fault set) pair
    that needs a replan); see :mod:`selfrepair.repair.tolerance_masks`."""

    @field_validator("objectives")
    @classmethod
    def _objectives(cls, value: tuple[str, ...]) -> tuple[str, ...]:
        out = []
        for text in value:
            try:
                objective = parse_objective(text)
            except ProblemError as exc:
                raise ValueError(str(exc)) from None
            out.append(OPTIMAL if objective is None else objective.label)
        if len(set(out)) != len(out):
            raise ValueError("an objective is listed twice")
        return tuple(out)

    @model_validator(mode="after")
    def _tolerant_modes(self) -> ReplacementStrategy:
        deferring = [str(m) for m in self.recursion if m in DEFERRING]
        if any(o != OPTIMAL for o in self.objectives) and deferring:
            raise ValueError(
                f"tolerant objectives need a non-deferring recursion mode, not "
                f"{', '.join(deferring)}"
            )
        return self

    @field_validator("rewrite", mode="before")
    @classmethod
    def _rewrite(cls, value: object) -> object:
        if isinstance(value, bool):
            return (value,)
        if isinstance(value, list | tuple) and not value:
            raise ValueError("expected true, false or a non-empty list of them")
        if isinstance(value, list | tuple) and not all(isinstance(v, bool) for v in value):
            raise ValueError(f"expected true, false or a list of them, got {value!r}")
        return value

    @model_validator(mode="after")
    def _rewrite_modes(self) -> ReplacementStrategy:
        deferring = [str(m) for m in self.recursion if m in DEFERRING]
        if any(self.rewrite) and deferring:
            raise ValueError(
                f"rewrite is not available with {', '.join(deferring)} recursion (its "
                "replacements may keep faulty actions for later); list those modes in a "
                "strategy without rewrite"
            )
        return self


class LookaheadStrategy(ReplacementStrategy):
    """Replace a window of ``window`` actions after the faulty one and, when the fault is known
    ahead, ``before`` actions before it; one variant per (window, before) pair."""

    name: Literal[StrategyName.LOOKAHEAD]  # type: ignore[assignment]
    window: tuple[Annotated[Int, Field(ge=0, le=64)], ...] = (3,)
    before: tuple[Annotated[Int, Field(ge=0, le=64)], ...] = (0,)

    @field_validator("rewrite")
    @classmethod
    def _no_rewrite(cls, value: tuple[bool, ...]) -> tuple[bool, ...]:
        if any(value):
            raise ValueError("rewrite applies to the replacement strategy only")
        return value


class DStarLiteStrategy(_StrategyEntry):
    """D* Lite, incremental replanning, keeping its search between repairs, with the planner
    ``backend`` (``auto``: the compiled kernels when numba is installed; ``python``: the
    pure-Python reference, the same plans)."""

    name: Literal[StrategyName.DSTAR_LITE]
    backend: Literal["auto", "numba", "python"] = "auto"


class LpgAdaptStrategy(_StrategyEntry):
    """Plan repair with LPG-adapt (``pddl`` extra, four-wheel robot): ``time_limit`` seconds per
    call, LPG's ``seed``; LPG's failures and time-outs fall back to replanning. Where it cannot
    run (extra, robot) the experiment is refused before any mission runs, unless ``optional``:
    then the entry has no missions and :attr:`refusal` says why (the command prints it)."""

    optional: bool = False  # before ``name``, whose validator reads it
    name: Literal[StrategyName.LPG_ADAPT]
    time_limit: Annotated[Float, Field(gt=0, le=3600)] = 5.0
    seed: Annotated[Int, Field(ge=0, lt=2**31)] = 0
    refusal: str | None = None
    """Why the strategy cannot run here (set by validation, for an ``optional`` entry)."""

    @field_validator("name")
    @classmethod
    def _runnable(cls, value: str, info: ValidationInfo) -> str:
        """Refuse the strategy before any mission runs where it cannot run (extra, robot),
        unless the entry is optional."""
        refusal = _lpg_refusal(info)
        if refusal is not None and not info.data.get("optional"):
            raise ValueError(refusal)
        return value

    @model_validator(mode="after")
    def _left_out(self, info: ValidationInfo) -> LpgAdaptStrategy:
        """Record why an optional entry cannot run (never what the file says)."""
        object.__setattr__(self, "refusal", _lpg_refusal(info) if self.optional else None)
        return self


def _lpg_refusal(info: ValidationInfo) -> str | None:
    """Why LPG-adapt cannot run here for the experiment's robot, or ``None``."""
    from selfrepair.baselines.adapt import check_lpg_adapt

    try:
        check_lpg_adapt(_domain(info).name)
    except ProblemError as exc:
        return str(exc)
    return None


class DiagnosisStrategy(_StrategyEntry):
    """A strategy for faults the robot is not told (docs/diagnosis.md): the ``oracle``, told
    them, and ``diagnose``, ``conformant``, ``active-diagnosis`` and ``trial-and-error``, with a
    table (one variant per table and recursion mode) and the diagnosis options: hypotheses of up
    to ``max_faults`` faults, the per-fault prior ``fault_prior``, the posterior mass ``1 -
    confidence`` that isolates a class."""

    name: Literal[
        StrategyName.ORACLE,
        StrategyName.DIAGNOSE,
        StrategyName.CONFORMANT,
        StrategyName.ACTIVE_DIAGNOSIS,
        StrategyName.TRIAL_AND_ERROR,
    ]
    tables: Annotated[tuple[str, ...], NonEmpty] = ("handwritten",)
    recursion: Annotated[tuple[RecursionMode, ...], NonEmpty] = (RecursionMode.FLAT,)
    max_faults: Annotated[Int, Field(ge=0, le=4)] = DEFAULT_MAX_FAULTS
    fault_prior: Annotated[Float, Field(gt=0.0, lt=1.0)] = DEFAULT_FAULT_PRIOR
    confidence: Annotated[Float, Field(ge=0.0, lt=1.0)] = DEFAULT_CONFIDENCE


STRATEGY_TAGS: tuple[StrategyName, ...] = StrategyName.of_kind(MissionKind.ROBOT)
"""The ``name`` values that select a strategy entry's model (the discriminator of
:data:`StrategyConfig`)."""

StrategyConfig = Annotated[
    ReplanStrategy
    | ReplacementStrategy
    | LookaheadStrategy
    | DStarLiteStrategy
    | LpgAdaptStrategy
    | DiagnosisStrategy,
    Field(discriminator="name"),
]


def _weights(value: object) -> object:
    """Clearance weights as canonical exact strings (``0.5`` -> ``"1/2"``), each from 0 to
    :data:`~selfrepair.limits.MAX_CLEARANCE_WEIGHT`."""
    if value is None:
        return None
    if not isinstance(value, list | tuple):
        raise ValueError("expected a list of non-negative numbers such as [0, 1, 2.5]")
    if not value:
        raise ValueError("expected a non-empty list")
    out = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, int | float | str):
            raise ValueError(f"expected a non-negative number, got {item!r}")
        try:
            weight = Fraction(str(item))
        except (ValueError, ZeroDivisionError):
            raise ValueError(f"expected a non-negative number, got {item!r}") from None
        if weight < 0:
            raise ValueError(f"expected a non-negative number, got {item!r}")
        if weight > MAX_CLEARANCE_WEIGHT:
            raise ValueError(f"expected a weight of at most {MAX_CLEARANCE_WEIGHT:,}, got {item!r}")
        out.append(str(weight))
    return tuple(out)
