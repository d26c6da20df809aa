"""A JSON-lines log of a tree run: every status change and every blackboard write.

One JSON object per line, stamped with the simulated time::

    {"t": 0.5, "tick": 3, "event": "status", "node": "grip", "kind": "Action",
     "type": "Grasp", "from": "RUNNING", "to": "SUCCESS", "feedback": "holding at 15.0 N"}
    {"t": 0.5, "tick": 3, "event": "write", "key": "/held", "client": "grip",
     "activity": "INITIALISED", "value": true}

After every tick the log compares the status of the nodes that may have changed, and only
those: the nodes ticked (a visitor records their order) and the nodes stopped (each node's
``stop`` is wrapped while the log is attached; py_trees changes a status only in ``tick`` and
``stop``), stopped ones not ticked following in tree order. Labels and tree order are worked
out once at attach, and again only when a node not seen before turns up. ``node`` names one
node of the tree (:func:`node_labels`): its name, which for a tree loaded from XML is already
its dotted path from the root, or, where several nodes share a name (a tree built in code), its
path from the root. Writes come from py_trees' blackboard activity stream, which is drained
after every tick. The file is flushed after every tick, so an interrupted run keeps everything
up to its last tick.
"""

from __future__ import annotations

import enum
import json
import math
import os
import time
import uuid
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np
import py_trees
from py_trees.blackboard import ActivityType, Blackboard
from py_trees.common import Status

from duet_robot.closing import Closing
from planner.atomic_file import commit, temporary_beside
from planner.render import node_kind, node_type, shown_name
from planner.runner import readable

__all__ = ["RunLog", "StatusListener", "json_safe", "node_labels"]

#: Called with (node, status before, status after) for every status change a log records.
StatusListener = Callable[[py_trees.behaviour.Behaviour, Status, Status], None]

#: Blackboard activities that change a value.
_WRITES = (ActivityType.WRITE.value, ActivityType.INITIALISED.value, ActivityType.UNSET.value)


def json_safe(value: Any, decimals: int = 6, max_items: int = 64, max_chars: int = 200) -> Any:
    """Summarise a value for a JSON log line.

    Numbers, strings, booleans and None are kept (non-finite floats become "nan"/"inf"
    strings); numpy arrays and scalars become lists/numbers rounded to ``decimals``; lists,
    tuples and dicts are summarised item by item; enums by name; anything else by its
    ``repr`` cut to ``max_chars``. Arrays and sequences longer than ``max_items`` are
    summarised by shape, dtype, min and max instead.
    """
    if value is None or isinstance(value, bool | str):
        return value if not isinstance(value, str) else _cut(value, max_chars)
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        number = float(value)
        if not math.isfinite(number):
            return str(number)
        return round(number, decimals)
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.ndarray):
        if value.size > max_items:
            summary: dict[str, Any] = {"shape": list(value.shape), "dtype": str(value.dtype)}
            if np.issubdtype(value.dtype, np.number) and value.size:
                summary["min"] = json_safe(value.min(), decimals)
                summary["max"] = json_safe(value.max(), decimals)
            return summary
        if np.issubdtype(value.dtype, np.floating):
            return json_safe(np.round(value, decimals).tolist(), decimals, max_items, max_chars)
        return json_safe(value.tolist(), decimals, max_items, max_chars)
    if isinstance(value, list | tuple):
        if len(value) > max_items:
            return {"len": len(value), "head": _cut(repr(value[:4]), max_chars)}
        return [json_safe(v, decimals, max_items, max_chars) for v in value]
    if isinstance(value, dict) and len(value) <= max_items:
        return {str(k): json_safe(v, decimals, max_items, max_chars) for k, v in value.items()}
    return _cut(repr(value), max_chars)


def node_labels(root: py_trees.behaviour.Behaviour) -> dict[uuid.UUID, str]:
    """One label per node of the tree under ``root``, no two alike.

    A node's label is its name (an unnamed node's, BehaviorTree.CPP's way, its type:
    :func:`planner.runner.readable`) where no other node of the tree has that name; otherwise
    its path from the root: the names from the root down joined by ``/``, each followed by
    ``[i]`` (its index among same-named siblings, from 0) where siblings share it.
    """
    names = {node.id: shown_name(node) for node in root.iterate()}
    counts = Counter(names.values())
    labels: dict[uuid.UUID, str] = {}

    def walk(node: py_trees.behaviour.Behaviour, path: str) -> None:
        labels[node.id] = names[node.id] if counts[names[node.id]] == 1 else path
        shared = Counter(names[child.id] for child in node.children)
        seen: Counter[str] = Counter()
        for child in node.children:
            step = names[child.id]
            if shared[step] > 1:
                seen[step] += 1
                step = f"{step}[{seen[step] - 1}]"
            walk(child, f"{path}/{step}")

    walk(root, names[root.id])
    return labels


def _cut(text: str, max_chars: int) -> str:
    return text if len(text) <= max_chars else text[: max_chars - 3] + "..."


class _VisitOrder(py_trees.visitors.VisitorBase):
    """Records the ids of the nodes ticked this tick, in tick order."""

    def __init__(self) -> None:
        super().__init__(full=False)
        self.order: list[uuid.UUID] = []

    def initialise(self) -> None:
        self.order = []

    def run(self, behaviour: py_trees.behaviour.Behaviour) -> None:
        self.order.append(behaviour.id)


class RunLog(Closing):
    """Log every status change and blackboard write of a tree to a JSON-lines file.

    Parameters
    ----------
    path : path-like
        Output file (overwritten). Parent directories are created.
    clock : callable, optional
        Returns the simulated time in s for the ``t`` stamp; default ``time.monotonic``.
    decimals : int
        Rounding of logged floats and arrays.

    Examples
    --------
    >>> with RunLog("out/run.jsonl", clock=lambda: world.time) as log:  # doctest: +SKIP
    ...     log.attach(tree)
    ...     for _ in range(100):
    ...         tree.tick()

    Notes
    -----
    ``attach`` enables py_trees' global blackboard activity stream (and ``close`` disables it
    again if this log enabled it); the stream is cleared after each tick, so other readers of
    the stream only see the current tick.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        clock: Callable[[], float] | None = None,
        decimals: int = 6,
    ) -> None:
        self.path = os.fspath(path)
        self.clock: Callable[[], float] = clock if clock is not None else time.monotonic
        self.decimals = decimals
        self.tick_count = 0
        self._statuses: dict[uuid.UUID, Status] = {}
        self._tree: py_trees.trees.BehaviourTree | None = None
        self._visitor = _VisitOrder()
        # The tree as last indexed: id -> node, label, position in tree order.
        self._root: py_trees.behaviour.Behaviour | None = None
        self._nodes: dict[uuid.UUID, py_trees.behaviour.Behaviour] = {}
        self._labels: dict[uuid.UUID, str] = {}
        self._rank: dict[uuid.UUID, int] = {}
        self._stopped: set[uuid.UUID] = set()
        self._status_listeners: list[StatusListener] = []
        self._enabled_stream = False
        parent = os.path.dirname(self.path)
        if parent:
            os.makedirs(parent, exist_ok=True)
        #: Why the log could not be written (a full disk), or None; the run goes on without it.
        self.error: str | None = None
        # Written beside the final name and renamed over it on close: a run killed midway,
        # or a disk that fills up, never leaves half a log named run.jsonl.
        self._temporary = temporary_beside(Path(self.path))
        self._file: IO[str] | None = open(self._temporary, "w", encoding="utf-8", buffering=1)

    @property
    def writing_path(self) -> Path:
        """Where the log is being written until :meth:`close` renames it to ``path`` (each
        tick is flushed there, to follow a run live)."""
        return Path(self._temporary)

    # -- wiring -----------------------------------------------------------------------
    def attach(self, tree: py_trees.trees.BehaviourTree) -> RunLog:
        """Log ``tree``'s ticks from now on; returns self.

        Raises
        ------
        RuntimeError
            If this log is already attached to a tree or closed.
        """
        if self._file is None:
            raise RuntimeError(f"RunLog {self.path}: closed; expected an open log")
        if self._tree is not None:
            raise RuntimeError(f"RunLog {self.path}: already attached to a tree")
        self._tree = tree
        self._index(tree.root)
        self._statuses = {node_id: node.status for node_id, node in self._nodes.items()}
        if Blackboard.activity_stream is None:
            Blackboard.enable_activity_stream(maximum_size=100_000)
            self._enabled_stream = True
        else:
            Blackboard.activity_stream.clear()
        tree.add_visitor(self._visitor)
        tree.add_post_tick_handler(self._on_post_tick)
        return self

    def _on_post_tick(self, tree: py_trees.trees.BehaviourTree) -> None:
        self.record_tick(tree.root)

    # -- records ----------------------------------------------------------------------
    def write(self, record: dict[str, Any]) -> None:
        """Write one record (a JSON-safe dict) as a line; ``t`` and ``tick`` are added first."""
        if self._file is None:
            raise RuntimeError(f"RunLog {self.path}: closed; expected an open log")
        if self.error is not None:
            return  # the disk refused an earlier line: the log is abandoned
        line = {"t": json_safe(float(self.clock()), self.decimals), "tick": self.tick_count}
        line.update(record)
        try:
            self._file.write(json.dumps(line, allow_nan=False) + "\n")
        except OSError as err:
            self._abandon(err)

    def record_tick(self, root: py_trees.behaviour.Behaviour) -> None:
        """Log the status changes and blackboard writes since the last tick, then flush.

        Called by the post-tick handler :meth:`attach` installs; call it yourself after
        ``root.tick_once()`` when ticking a bare root without a ``BehaviourTree``.
        """
        self.tick_count += 1
        ticked = list(dict.fromkeys(self._visitor.order))
        self._visitor.order = []
        if root is not self._root or any(i not in self._nodes for i in ticked):
            # A new root, or a node added since: index the tree again and compare every node
            # this once, as a node changed before it was indexed is in no record.
            self._index(root)
            self._stopped.update(self._nodes)
        stopped = self._stopped.difference(ticked)
        self._stopped.clear()  # the same set the wrapped stops add to
        order = [i for i in ticked if i in self._nodes]
        order += sorted((i for i in stopped if i in self._nodes), key=self._rank.__getitem__)
        for node_id in order:
            node = self._nodes[node_id]
            before = self._statuses.get(node_id, Status.INVALID)
            if node.status != before:
                self.write(
                    {
                        "event": "status",
                        "node": self._labels[node_id],
                        "kind": node_kind(node),
                        "type": node_type(node),
                        "from": before.value,
                        "to": node.status.value,
                        "feedback": node.feedback_message,
                    }
                )
                for listener in self._status_listeners:
                    listener(node, before, node.status)
            self._statuses[node_id] = node.status
        self._drain_blackboard()
        if self._file is not None and self.error is None:
            try:
                self._file.flush()
            except OSError as err:
                self._abandon(err)

    def _abandon(self, err: OSError) -> None:
        """Stop logging after a write failed: the partial log is removed, never committed."""
        self.error = f"{self.path}: {err.strerror or err}"
        if self._file is not None:
            try:
                self._file.close()
            except OSError:
                pass  # the buffered rest cannot be written either
        Path(self._temporary).unlink(missing_ok=True)

    def add_status_listener(self, listener: StatusListener) -> None:
        """Call ``listener(node, before, after)`` for every status change logged, in log order
        (e.g. :class:`planner.btlog.BtLog`, which writes the same changes for Groot2)."""
        self._status_listeners.append(listener)

    def _index(self, root: py_trees.behaviour.Behaviour) -> None:
        """Index the tree under ``root``: nodes, labels, tree order; wrap each node's ``stop``."""
        self._unwrap_stops()
        self._root = root
        self._nodes = {}
        self._rank = {}
        for rank, node in enumerate(root.iterate()):
            self._nodes[node.id] = node
            self._rank[node.id] = rank
            self._wrap_stop(node)
        self._labels = node_labels(root)

    def _wrap_stop(self, node: py_trees.behaviour.Behaviour) -> None:
        original = node.stop  # bound: the class's own stop, with its overrides
        stopped = self._stopped
        node_id = node.id

        def stop(new_status: Status = Status.INVALID) -> None:
            stopped.add(node_id)
            original(new_status)

        # An instance attribute: composites call ``child.stop(...)``, which finds it first.
        node.stop = stop  # type: ignore[method-assign]

    def _unwrap_stops(self) -> None:
        for node in self._nodes.values():
            if "stop" in vars(node):
                del node.stop
        self._nodes = {}
        self._root = None

    def _drain_blackboard(self) -> None:
        stream = Blackboard.activity_stream
        if stream is None:
            return
        for item in stream.data:
            if item.activity_type not in _WRITES:
                continue
            record: dict[str, Any] = {
                "event": "write",
                "key": item.key,
                "client": readable(item.client_name),
                "activity": item.activity_type,
            }
            if item.activity_type != ActivityType.UNSET.value:
                record["value"] = json_safe(item.current_value, self.decimals)
            self.write(record)
        stream.clear()

    # -- lifetime ---------------------------------------------------------------------
    def close(self) -> None:
        """Detach from the tree, flush and close the file (idempotent)."""
        self._unwrap_stops()
        if self._tree is not None:
            if self._on_post_tick in self._tree.post_tick_handlers:
                self._tree.post_tick_handlers.remove(self._on_post_tick)
            if self._visitor in self._tree.visitors:
                self._tree.visitors.remove(self._visitor)
            self._tree = None
        if self._enabled_stream:
            Blackboard.disable_activity_stream()
            self._enabled_stream = False
        if self._file is not None:
            if self.error is None:
                try:
                    self._file.close()
                    commit(self._temporary, Path(self.path))
                except OSError as err:
                    self._abandon(err)
            self._file = None
