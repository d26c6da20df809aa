"""The tree built in code is the tree in the XML file, node for node."""

from __future__ import annotations

from pathlib import Path

import py_trees

import planner.leaves  # noqa: F401  (registers the leaves for the loader)
from planner.factories import pick_and_place
from planner.loader import load_tree

XML = Path(__file__).resolve().parents[2] / "planner" / "trees" / "pick_and_place.xml"


def outline(root: py_trees.behaviour.Behaviour) -> list[tuple[int, str, str]]:
    """(depth, class, short name) of every node, depth first."""
    out = []

    def walk(node: py_trees.behaviour.Behaviour, depth: int) -> None:
        out.append((depth, type(node).__name__, node.name.split(".")[-1]))
        for child in node.children:
            walk(child, depth + 1)

    walk(root, 0)
    return out


def test_factory_builds_the_xml_tree() -> None:
    from_xml = outline(load_tree(XML))
    py_trees.blackboard.Blackboard.clear()
    in_code = outline(pick_and_place())
    assert in_code == from_xml


def test_factory_leaves_read_the_same_ports() -> None:
    root = pick_and_place()
    transports = [n for n in root.iterate() if type(n).__name__ == "Transport"]
    assert len(transports) == 3 * 6  # 3 moves x (5 compositions + the careful fallback)
    weights = sorted({float(t.get_input("transport_weight")) for t in transports})
    assert weights == [0.1, 0.25, 1.0]
