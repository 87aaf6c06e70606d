"""Domains by name: for table files, traces, experiment configs and the command line.

Library functions take :class:`~selfrepair.robots.domain.Domain` values; a name is looked up only
where text names a robot. Three sources, in this order:

1. domains registered in this process with :func:`register_domain`;
2. the built-in domains (``four-wheel``, ``three-action``), imported on first use;
3. installed plug-ins: an entry point in the group ``selfrepair.domains`` whose object is a
   ``Domain`` (e.g. ``omni = "mypackage.robots:OMNI"`` under
   ``[project.entry-points."selfrepair.domains"]``), so the command line finds a third-party robot
   without any code change here.

Built-ins and plug-ins are named here as ``"module:attribute"`` strings and imported by name, so
that the generic layers (tables, repair) that look domains up never import a concrete robot.
"""

from __future__ import annotations

import importlib
from importlib.metadata import entry_points
from typing import Any

from selfrepair.errors import InputError, ProblemError
from selfrepair.robots.domain import Domain, check_domain

__all__ = ["ENTRY_POINT_GROUP", "domain_names", "get_domain", "register_domain"]

ENTRY_POINT_GROUP = "selfrepair.domains"

_BUILTIN = {
    "four-wheel": "selfrepair.robots.four_wheel:FOUR_WHEEL",
    "three-action": "selfrepair.robots.three_action:THREE_ACTION",
}
_REGISTERED: dict[str, Domain[Any, Any]] = {}


def register_domain(domain: Domain[Any, Any], *, replace: bool = False) -> Domain[Any, Any]:
    """Make ``domain`` known by its name (after :func:`check_domain`); returns it.

    A second domain under a name already in use raises :class:`ProblemError` unless ``replace``.
    """
    check_domain(domain)
    current = _REGISTERED.get(domain.name)
    taken = domain.name in _BUILTIN or (current is not None and current is not domain)
    if taken and not replace:
        raise ProblemError(
            f"a domain named {domain.name!r} is already registered; pass replace=True to replace it"
        )
    _REGISTERED[domain.name] = domain
    return domain


def get_domain(name: str) -> Domain[Any, Any]:
    """The domain called ``name``; an unknown name raises :class:`InputError` listing the known
    ones."""
    domain = _REGISTERED.get(name)
    if domain is not None:
        return domain
    target = _BUILTIN.get(name) or _plugins().get(name)
    if target is None:
        raise InputError(
            f"expected a domain name ({', '.join(domain_names())}), got {name!r}",
            source="<domain>",
        )
    domain = _load(name, target)
    _REGISTERED[name] = domain
    return domain


def domain_names() -> tuple[str, ...]:
    """Every domain name that :func:`get_domain` accepts, sorted."""
    return tuple(sorted({*_BUILTIN, *_REGISTERED, *_plugins()}))


def _plugins() -> dict[str, str]:
    return {ep.name: ep.value for ep in entry_points(group=ENTRY_POINT_GROUP)}


def _load(name: str, target: str) -> Domain[Any, Any]:
    module_name, _, attribute = target.partition(":")
    try:
        value = getattr(importlib.import_module(module_name), attribute)
    except (ImportError, AttributeError) as exc:
        raise ProblemError(f"domain {name!r}: cannot load {target!r}: {exc}") from None
    if not isinstance(value, Domain) or value.name != name:
        raise ProblemError(f"domain {name!r}: {target!r} is not a Domain named {name!r}")
    check_domain(value)
    return value
