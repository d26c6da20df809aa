"""BehaviorTree.CPP v4's ``WasEntryUpdated``, ``SkipUnlessUpdated`` and ``WaitValueUpdate``:
nodes that ask whether a blackboard entry was written since they last looked.

Each remembers the write stamp (:mod:`planner.bt_entry_stamps`, BT.CPP's ``sequence_id``) it
saw last, starting from none, so an entry written before the node's first look counts as
updated then. Every write counts, the same value written again included. ``entry`` names the
key, ``{key}`` or bare ``key`` (also ``{@key}``, the root's); it is resolved as any port is,
through the subtree remappings. A missing entry is never updated.

* ``WasEntryUpdated entry``: SUCCESS if the entry was written since this node's last tick,
  else FAILURE.
* ``SkipUnlessUpdated entry``: if it was, tick the child (and keep ticking it, without looking
  again, while it is RUNNING) and return its status; otherwise SKIPPED, which Duet gives as
  :func:`planner.bt_decorators.skipped_status`. A halt stops the child; what was seen is kept.
* ``WaitValueUpdate entry``: the same, RUNNING instead of SKIPPED.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any, ClassVar

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

from planner.bt_decorators import mark_ticked, skipped_status
from planner.bt_entry_stamps import install, write_stamp

__all__ = ["BUILTIN_UPDATED", "SkipUnlessUpdated", "WaitValueUpdate", "WasEntryUpdated"]

Behaviour = py_trees.behaviour.Behaviour
_ENTRY = {
    "entry": PortInformation(data_type=object, required=True, description="entry to check"),
}


class _Watcher(PortsMixin, register=False):
    """The write stamp seen last, and the check against it."""

    #: Ports naming a key whose writes are watched, not read (the validator's dataflow).
    WATCHED_PORTS: ClassVar[frozenset[str]] = frozenset({"entry"})
    seen = 0

    def watched_key(self) -> str:
        """The absolute blackboard key ``entry`` names."""
        return self._get_blackboard_key("entry")

    def updated(self) -> bool:
        """Whether the entry was written since the last call (it exists, a new stamp)."""
        key = self.watched_key()
        stamp = write_stamp(key)
        if stamp is None:
            self.feedback_message = f"no entry {key}"
            return False
        previous, self.seen = self.seen, stamp
        self.feedback_message = f"{key} {'updated' if stamp != previous else 'not updated'}"
        return stamp != previous


class WasEntryUpdated(_Watcher, py_trees.behaviour.Behaviour, register=False):
    """SUCCESS if ``entry`` was written since this node's last tick, else FAILURE."""

    NODE_TYPE = "Condition"
    INPUT_PORTS = _ENTRY
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def setup(self, **kwargs: Any) -> None:
        """Start stamping writes (before the first tick, so the run's own writes count)."""
        install()

    def update(self) -> Status:
        """Compare the entry's stamp with the one seen last."""
        return Status.SUCCESS if self.updated() else Status.FAILURE


class SkipUnlessUpdated(_Watcher, py_trees.decorators.Decorator, register=False):
    """Tick the child only if ``entry`` was written since the last look; else SKIPPED."""

    bt_can_skip = True  # see planner.bt_decorators.propagate_skips

    INPUT_PORTS = _ENTRY
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, child: Behaviour, **kwargs: Any) -> None:
        super().__init__(name=name, child=child, **kwargs)
        self.child_running = False

    def setup(self, **kwargs: Any) -> None:
        """Start stamping writes (see :class:`WasEntryUpdated`)."""
        install()

    def not_updated(self) -> Status:
        """The status when the entry was not written: SKIPPED's stand-in."""
        return skipped_status(self)

    def tick(self) -> Iterator[Behaviour]:
        """Look, then tick the child or not; a running child goes on without a look."""
        if not self.child_running and not self.updated():
            self.status = self.not_updated()
            yield self
            return
        mark_ticked(self)
        yield from super().tick()
        self.child_running = self.decorated.status == Status.RUNNING

    def update(self) -> Status:
        """Reflect the child."""
        return self.decorated.status

    def stop(self, new_status: Status = Status.INVALID) -> None:
        """A halt or an end: the next tick looks at the entry again."""
        self.child_running = False
        super().stop(new_status)


class WaitValueUpdate(SkipUnlessUpdated, register=False):
    """Tick the child only if ``entry`` was written since the last look; else RUNNING."""

    def not_updated(self) -> Status:
        """RUNNING: wait for a write."""
        return Status.RUNNING


#: BT.CPP tag -> class.
BUILTIN_UPDATED: dict[str, type[Behaviour]] = {
    "WasEntryUpdated": WasEntryUpdated,
    "SkipUnlessUpdated": SkipUnlessUpdated,
    "WaitValueUpdate": WaitValueUpdate,
}
