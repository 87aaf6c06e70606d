"""The ``[physics]`` section of an experiment file (:class:`PhysicsConfig`), and the robot
model that validators read from the validation context (:func:`context_domain`), apart from
:mod:`selfrepair.experiment.schema` so that module stays one screenful of sections."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import ValidationInfo, field_validator, model_validator

from selfrepair.robots.domain import Domain, SomeDomain
from selfrepair.robots.fromfile import DEFAULT_DOMAIN
from selfrepair.robots.registry import get_domain
from selfrepair.tomlfile import Frozen, NonEmpty

__all__ = ["PhysicsConfig", "context_domain"]


def context_domain(info: ValidationInfo) -> SomeDomain:
    """The robot model a validator checks against: the validation context's ``domain`` (set by
    :func:`selfrepair.experiment.config.parse_config`), else the default robot."""
    context = info.context or {}
    domain = context.get("domain")
    return domain if isinstance(domain, Domain) else get_domain(DEFAULT_DOMAIN)


class PhysicsConfig(Frozen):
    """Missions in physics (:mod:`selfrepair.physics`, the ``physics`` extra): every mission runs
    on each of ``simulators``, ``lattice`` (the lattice simulator) and ``physics`` (MuJoCo, the
    robot localised on the lattice after each action; ``tracked``: under the sign-constrained
    tracker rather than open loop). The simulator is not part of a mission's situation, so both
    footings of a mission share its seed (paired)."""

    simulators: Annotated[tuple[Literal["lattice", "physics"], ...], NonEmpty] = (
        "lattice",
        "physics",
    )
    tracked: bool = True

    @field_validator("simulators")
    @classmethod
    def _distinct(cls, value: tuple[str, ...]) -> tuple[str, ...]:
        if len(set(value)) != len(value):
            raise ValueError(f"expected each simulator once, got {list(value)}")
        return value

    @model_validator(mode="after")
    def _four_wheels(self, info: ValidationInfo) -> PhysicsConfig:
        domain = context_domain(info)
        if "physics" in self.simulators and not all(
            len(getattr(a, "wheels", ())) == 4 for a in domain.actions
        ):
            raise ValueError(
                f"expected a robot whose actions command four wheels for physics, got "
                f"{domain.name!r}"
            )
        return self
