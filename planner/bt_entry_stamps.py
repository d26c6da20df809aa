"""Write stamps for blackboard entries: BT.CPP's ``sequence_id``, which py_trees lacks.

BT.CPP counts every write to an entry (``Blackboard::set``, a script assignment, a port
copied by a SubTree), the same value written again included; ``WasEntryUpdated`` and
``SkipUnlessUpdated`` compare that count with the one they saw last. py_trees' blackboard
keeps no such count, but every write it makes, whoever makes it (a leaf's output port
through its client, ``Blackboard.set`` from a script or the runner, a subtree's remapped
key, a ``{@key}`` root key), ends in one store into ``Blackboard.storage``. This module puts
a dict there that stamps each store with the next number of one process-wide sequence: one
counter step and one dict store per write, nothing per tick, reads untouched.

The stamps only grow (never reused, not even after ``Blackboard.clear()``), so a key
removed and written again is always seen as updated; BT.CPP creates a new entry there and
starts it again at 1, which a node that had seen 1 would miss. A write into an attribute of a
stored object (py_trees' ``Blackboard.set("/a.b", v)``) changes no entry and is not counted.

The stamping storage is installed on first use (:func:`install`; the nodes call it in
``setup``) and again if something replaced ``Blackboard.storage`` with a plain dict (as
``py_trees.tests.clear_blackboard`` does): the entries found then are stamped as written.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping
from typing import Any

from py_trees.blackboard import Blackboard

__all__ = ["StampedStorage", "install", "write_stamp"]

#: The one sequence every write draws its stamp from (1, 2, ...).
_SEQUENCE = itertools.count(1)


class StampedStorage(dict[str, Any]):
    """``Blackboard.storage`` that stamps every store of a key (``stamps[key]``)."""

    def __init__(self, initial: Mapping[str, Any] | None = None) -> None:
        super().__init__()
        self.stamps: dict[str, int] = {}
        if initial:
            self.update(initial)

    def __setitem__(self, key: str, value: Any) -> None:
        super().__setitem__(key, value)
        self.stamps[key] = next(_SEQUENCE)

    def __delitem__(self, key: str) -> None:
        super().__delitem__(key)
        self.stamps.pop(key, None)

    def pop(self, key: str, *default: Any) -> Any:
        self.stamps.pop(key, None)
        return super().pop(key, *default)

    def popitem(self) -> tuple[str, Any]:
        key, value = super().popitem()
        self.stamps.pop(key, None)
        return key, value

    def clear(self) -> None:
        super().clear()
        self.stamps.clear()

    def setdefault(self, key: str, default: Any = None) -> Any:
        if key not in self:
            self[key] = default
        return self[key]

    def update(self, *args: Any, **kwargs: Any) -> None:
        items: Iterable[tuple[str, Any]]
        for source in (*args, kwargs):
            items = source.items() if isinstance(source, Mapping) else source
            for key, value in items:
                self[key] = value

    def __ior__(self, other: Any) -> StampedStorage:  # type: ignore[override,misc]
        self.update(other)
        return self


def install() -> StampedStorage:
    """Make ``Blackboard.storage`` a :class:`StampedStorage` (keeping its entries, each then
    stamped as written); return it. Cheap when it is one already."""
    storage = Blackboard.storage
    if type(storage) is StampedStorage:
        return storage
    stamped = StampedStorage(storage)
    Blackboard.storage = stamped
    return stamped


def write_stamp(key: str) -> int | None:
    """The stamp of the last write to the absolute ``key``, or None when it has no entry."""
    storage = install()
    if key not in storage:
        return None
    return storage.stamps[key]
