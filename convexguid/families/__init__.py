"""The registry of problem families: the one list of what ``family:`` in a problem file may name.

Each family is a package ``convexguid/families/<name>/`` exporting ``FAMILY``
(a :class:`~convexguid.families.base.Family`); adding one is a new package and one line in
:data:`FAMILIES`. Importing the registry imports only the families' spec models.
"""

from __future__ import annotations

from convexguid.errors import SpecError
from convexguid.families import flat_attitude, lpmpc, potential_function, quaternion_attitude, rendezvous
from convexguid.families.base import Family

FAMILIES: dict[str, Family] = {family.name: family for family in (
    flat_attitude.FAMILY,
    rendezvous.FAMILY,
    quaternion_attitude.FAMILY,
    potential_function.FAMILY,
    lpmpc.FAMILY,
)}
"""Every family, by the value of the problem file's ``family`` key."""


def family_names() -> tuple[str, ...]:
    """Names of the known families, in registry order."""
    return tuple(FAMILIES)


def get_family(name: str) -> Family:
    """The family called ``name``.

    Raises
    ------
    SpecError
        If there is none; the message lists the known families.
    """
    family = FAMILIES.get(name) if isinstance(name, str) else None
    if family is None:
        raise SpecError(f"unknown family {name!r}; known families: {', '.join(FAMILIES)}")
    return family


__all__ = ["FAMILIES", "Family", "family_names", "get_family"]
