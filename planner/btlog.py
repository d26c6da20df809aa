"""A Groot2 replay log (``.btlog``): BehaviorTree.CPP v4's FileLogger2 layout, for any tree.

The layout, all integers little-endian, as BT.CPP's ``FileLogger2`` writes it:

- the 18 ASCII bytes ``BTCPP4-FileLogger2`` and one byte, the protocol (1);
- a uint32, the size N of the tree's XML, then those N bytes: ``<root BTCPP_format="4">`` with
  a ``<BehaviorTree>`` per tree instance (the main tree, then each SubTree instance's, see
  :func:`groot_tree_xml`) whose nodes carry ``name`` and ``_uid`` (1, 2, ... in depth-first
  order, as BT.CPP numbers nodes as it creates them), then a ``<TreeNodesModel>`` of the
  leaves and of any node that is not one of BT.CPP's built-ins;
- a uint64, the first timestamp in microseconds;
- then 9 bytes for every status change: the time since the first timestamp in microseconds
  (6 bytes), the node's uid (uint16) and its new status (uint8: 0 IDLE, 1 RUNNING, 2 SUCCESS,
  3 FAILURE; py_trees' INVALID is BT.CPP's IDLE).

Times are the clock's (the simulated time in a run), not the wall clock. Node names are the
names as written, without the parent path. A py_trees tree holds no SubTree nodes (the loader
inlines subtrees): the log adds them back, each taking the status of its subtree's root node
at the same time, as BT.CPP's SubTree node takes its child's.
"""

from __future__ import annotations

import os
import struct
import uuid
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from typing import IO

import py_trees
from py_trees.common import Status
from py_trees.ports import PortsMixin

from duet_robot.closing import Closing
from planner.decorators import SimTimeout
from planner.nodes_model import add_node_model
from planner.render import BT_DECORATORS, bt_type, node_kind, short_name

__all__ = ["MAGIC", "PROTOCOL", "STATUS_CODES", "BtLog", "GrootTree", "groot_tree_xml"]

#: The file's first bytes, then the protocol byte.
MAGIC = b"BTCPP4-FileLogger2"
PROTOCOL = 1
#: BT.CPP's NodeStatus values.
STATUS_CODES = {Status.INVALID: 0, Status.RUNNING: 1, Status.SUCCESS: 2, Status.FAILURE: 3}
#: Largest uid a transition holds (2 bytes).
MAX_UID = 0xFFFF


def _bt_cpp_element(node: py_trees.behaviour.Behaviour) -> tuple[str, dict[str, str], bool]:
    """The BT.CPP spelling of a node: tag, attributes besides name and uid, and whether the tag
    is one of BT.CPP's built-ins (which Groot2 knows without a model)."""
    tag = bt_type(node)
    if isinstance(node, py_trees.composites.Parallel):
        on_one = isinstance(node.policy, py_trees.common.ParallelPolicy.SuccessOnOne)
        return tag, {"success_count": "1" if on_one else "-1", "failure_count": "1"}, True
    if isinstance(node, py_trees.decorators.Retry):
        return tag, {"num_attempts": str(node.num_failures)}, True
    if isinstance(node, py_trees.decorators.Repeat):
        return tag, {"num_cycles": str(node.num_success)}, True
    if isinstance(node, SimTimeout):
        return tag, {"msec": str(round(node.duration * 1000))}, True
    composite = isinstance(node, py_trees.composites.Sequence | py_trees.composites.Selector)
    return tag, {}, composite or type(node) in BT_DECORATORS


def _model_kind(node: py_trees.behaviour.Behaviour) -> str:
    if isinstance(node, py_trees.decorators.Decorator):
        return "Decorator"
    if isinstance(node, py_trees.composites.Composite):
        return "Control"
    return node_kind(node)


@dataclass(frozen=True)
class GrootTree:
    """A tree as BT.CPP's ``WriteTreeToXML`` with uids writes it.

    Attributes
    ----------
    xml : str
        ``<root BTCPP_format="4">``: a ``<BehaviorTree>`` per tree instance, then a
        ``<TreeNodesModel>``.
    uids : dict
        py_trees node id -> uid (1, 2, ... depth first, SubTree nodes included).
    subtree_uids : dict
        py_trees node id of the first node of a subtree instance -> the uids of the SubTree
        nodes it stands for (innermost first): they take its status, as BT.CPP's SubTree
        node takes its child's.
    """

    xml: str
    uids: dict[uuid.UUID, int]
    subtree_uids: dict[uuid.UUID, tuple[int, ...]]


def _subtree_segments(
    node: py_trees.behaviour.Behaviour, parent_name: str, ids: dict[str, str] | None
) -> list[str]:
    """The SubTree instances between a node and its parent (outermost first), from the
    loader's names: a node's name is its parent's, then each SubTree instance's name, then its
    own, joined by dots (``a.first_object.b``: ``first_object`` is a SubTree). Only for trees
    the loader built (``ids`` is not None); a tree built in code has no SubTrees."""
    if ids is None:
        return []
    prefix = f"{parent_name}." if parent_name else ""
    if not node.name.startswith(prefix):
        return []
    return node.name[len(prefix) :].split(".")[:-1]


def groot_tree_xml(root: py_trees.behaviour.Behaviour, tree_id: str | None = None) -> GrootTree:
    """The tree under ``root`` as BT.CPP's ``WriteTreeToXML`` with uids writes it.

    A tree the loader built has its SubTrees expanded as Groot2 expects: in the parent tree a
    ``<SubTree ID=... _fullpath=... _uid=...>`` node, and for each instance its own
    ``<BehaviorTree ID=... _fullpath=...>`` (``_fullpath``: the instance names from the main
    tree down, joined by ``/``; ``ID``: the subtree's, or the instance name where the loader
    could not tell). The main tree is ``tree_id``, by default the ID the loader built it from
    (``MainTree`` for a tree built in code).

    Raises
    ------
    ValueError
        If the tree has more nodes than a uid can number (65535).
    """
    from planner.loader import main_tree_id, subtree_ids

    ids = subtree_ids(root)
    # The main tree by its own ID, as BT.CPP writes it (a tree built in code: MainTree).
    tree_id = tree_id or main_tree_id(root) or "MainTree"
    document = ET.Element("root", {"BTCPP_format": "4"})
    model = ET.Element("TreeNodesModel")
    modelled: set[str] = set()
    uids: dict[uuid.UUID, int] = {}
    subtree_uids: dict[uuid.UUID, tuple[int, ...]] = {}
    count = [0]

    def next_uid() -> int:
        count[0] += 1
        if count[0] > MAX_UID:
            raise ValueError(f"tree '{root.name}': expected at most {MAX_UID} nodes, got more")
        return count[0]

    def add(
        node: py_trees.behaviour.Behaviour, parent: ET.Element, parent_name: str, path: str
    ) -> None:
        standing_for: list[int] = []
        for segment in _subtree_segments(node, parent_name, ids):
            path = f"{path}/{segment}" if path else segment
            sub_id = (ids or {}).get(segment, segment)
            uid = next_uid()
            ET.SubElement(parent, "SubTree", {"ID": sub_id, "_fullpath": path, "_uid": str(uid)})
            standing_for.insert(0, uid)
            parent = ET.SubElement(document, "BehaviorTree", {"ID": sub_id, "_fullpath": path})
        if standing_for:
            subtree_uids[node.id] = tuple(standing_for)
        uid = next_uid()
        uids[node.id] = uid
        tag, attrib, builtin = _bt_cpp_element(node)
        elem = ET.SubElement(parent, tag, {"name": short_name(node), "_uid": str(uid), **attrib})
        if not builtin and tag not in modelled:
            modelled.add(tag)
            if isinstance(node, PortsMixin):
                add_node_model(model, tag, type(node))
            else:
                ET.SubElement(model, _model_kind(node), {"ID": tag})
        for child in node.children:
            add(child, elem, node.name, path)

    main = ET.SubElement(document, "BehaviorTree", {"ID": tree_id, "_fullpath": ""})
    add(root, main, "", "")
    model[:] = sorted(model, key=lambda e: e.attrib["ID"])
    document.append(model)
    ET.indent(document)
    return GrootTree(ET.tostring(document, encoding="unicode"), uids, subtree_uids)


class BtLog(Closing):
    """Write a tree's status changes as a Groot2 replay log (see the module's layout).

    Parameters
    ----------
    path : path-like
        Output file, ``.btlog`` (Groot2 opens only that suffix); overwritten.
    root : Behaviour
        The tree; its XML and uids are fixed now (nodes added later are not logged).
    clock : callable
        Returns the time in s (the simulated time in a run); its value now is the first
        timestamp.

    Examples
    --------
    >>> with RunLog("out/run.jsonl", clock=world.time) as log:  # doctest: +SKIP
    ...     btlog = BtLog("out/run.btlog", root, clock=world.time)
    ...     log.add_status_listener(btlog.record)
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        root: py_trees.behaviour.Behaviour,
        clock: Callable[[], float],
    ) -> None:
        self.path = os.fspath(path)
        if not self.path.endswith(".btlog"):
            raise ValueError(f"BtLog {self.path}: expected a file name ending in .btlog")
        self.clock = clock
        self.tree = groot_tree_xml(root)
        self.uids = self.tree.uids
        data = self.tree.xml.encode("utf-8")
        self.first_time_s = float(clock())
        self.transitions = 0
        # Unbuffered: every transition is on disk at once, so an interrupted run keeps it.
        self._file: IO[bytes] | None = open(self.path, "wb", buffering=0)
        first_us = round(self.first_time_s * 1e6)
        self._file.write(
            MAGIC + bytes([PROTOCOL]) + struct.pack("<I", len(data)) + data
            + struct.pack("<q", first_us)
        )  # fmt: skip

    def record(self, node: py_trees.behaviour.Behaviour, before: Status, after: Status) -> None:
        """Write one transition of ``node`` to ``after``, stamped with the clock now (a
        :data:`planner.runlog.StatusListener`); nodes not in the tree at the start are skipped."""
        uid = self.uids.get(node.id)
        if self._file is None or uid is None:
            return
        delta_us = max(0, round((float(self.clock()) - self.first_time_s) * 1e6))
        stamp, code = struct.pack("<Q", delta_us)[:6], STATUS_CODES[after]
        # The node, then the SubTree nodes it stands for, which take its status.
        for each in (uid, *self.tree.subtree_uids.get(node.id, ())):
            self._file.write(stamp + struct.pack("<HB", each, code))
            self.transitions += 1

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._file is not None:
            self._file.close()
            self._file = None
