"""Does a tree name objects the world has? Every ``object`` port, literals traced through
subtree remapping, against the world's objects.

``object="ghost"`` validates on its own (any text is a name) and then fails the run at its
first tick, after everything before it was simulated. Where the world is known (``run``,
``trials``, ``validate WORLD --tree T``), :func:`check_tree_objects` finds it first: the
literal on a leaf, or on a ``<SubTree>`` whose port feeds a leaf's ``object``. A node with
a literal ``move`` is left to :func:`planner.tree_task.check_tree_moves`, which reports its
object against the world's task.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Collection

from planner.tree_dataflow import port_uses
from planner.tree_ports import Registry
from planner.tree_problems import TreeProblem
from planner.tree_reading import TreeDocument, describe, source_file, source_line
from planner.tree_task import MOVE_PORT, OBJECT_PORT


def check_tree_objects(
    doc: TreeDocument,
    objects: Collection[str],
    registry: Registry | None = None,
) -> list[TreeProblem]:
    """One problem per place a tree names an object the world does not have.

    A ``{object}`` the run writes (:data:`planner.tree_dataflow.TASK_OBJECT_KEY`) is the
    task's object, which the world file already holds to its objects.

    Parameters
    ----------
    doc : TreeDocument
        The tree, read and within bounds (it has passed :func:`planner.validate`'s checks).
    objects : collection of str
        The world's object names.
    """
    known = ", ".join(sorted(objects)) or "none"
    found: dict[tuple[int, str], tuple[ET.Element, list[ET.Element]]] = {}
    for use in port_uses(doc, registry):
        if use.port != OBJECT_PORT or use.direction != "read":
            continue
        name = use.binding.literal
        where = use.binding.origin if use.binding.origin is not None else use.elem
        if name is None or name in objects:
            continue
        move = where.attrib.get(MOVE_PORT)
        if move is not None and not move.startswith("{") and OBJECT_PORT in where.attrib:
            continue  # check_tree_moves reports it, with the moves
        readers = found.setdefault((id(where), name), (where, []))[1]
        if use.elem is not where and use.elem not in readers:
            readers.append(use.elem)
    problems = []
    for (_, name), (where, readers) in found.items():
        via = ""
        if readers:
            first = f"{describe(readers[0])} at line {source_line(readers[0])}"
            more = len(readers) - 1
            via = f" (read by {first}" + (f" and {more} other nodes)" if more else ")")
        problems.append(
            TreeProblem(
                source_file(where, doc.file),
                source_line(where),
                describe(where),
                f"object {name!r}{via}: expected one of the world's objects ({known})",
            )
        )
    return problems


__all__ = ["check_tree_objects"]
