"""A world seen through some of the port's roles only, to hold leaves to the roles they name."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from planner.port import role_methods


class RoleView:
    """Forwards the methods of ``roles`` to ``world``; any other raises AttributeError.

    Parameters
    ----------
    world : object
        A world satisfying :class:`planner.port.WorldPort`.
    roles : iterable of type
        Role Protocols of :mod:`planner.port`.
    """

    def __init__(self, world: Any, roles: Iterable[type]) -> None:
        self._world = world
        self._roles = tuple(roles)
        self._allowed = frozenset().union(*(role_methods(r) for r in self._roles))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_") or name not in self._allowed:
            offered = ", ".join(r.__name__ for r in self._roles)
            raise AttributeError(f"{name}: not a method of the roles {offered}")
        return getattr(self._world, name)
