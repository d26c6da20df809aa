"""How big a tree may grow: its nesting depth, its size once subtrees are expanded, no cycles.

A tree file is small but what it describes need not be: each ``<SubTree>`` is a copy of its
tree, so 22 levels of two subtrees each are four million nodes, and 5000 nested ``<Sequence>``
are deeper than any recursive walk (py_trees' parser, its tick, the renderer) can go. This
module measures both on the XML alone, without recursion and without expanding anything:
per ``<BehaviorTree>``, its own depth, node count and subtree references, then the expanded
figures by memoised passes over the subtree graph (a cycle is found there too, whether or
not its ``<SubTree>`` elements are named). :func:`planner.tree_checks.check_tree_document`
runs the size checks first and stops at their problems, so nothing after them meets an
unbounded tree.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field

from planner.tree_problems import TreeProblem
from planner.tree_reading import TreeDocument, describe, source_file, source_line

#: Deepest nesting a tree may have, subtrees expanded (the shipped trees are ~15 deep). Every
#: walk of a built tree recurses once per level; 200 keeps them far from Python's limit.
MAX_TREE_DEPTH = 200
#: Most nodes a tree may expand to through its subtrees (the shipped task has ~300).
MAX_TREE_NODES = 20_000


@dataclass
class _Shape:
    """One ``<BehaviorTree>`` as written: depth, own nodes, and the subtrees it uses."""

    depth: int = 0
    nodes: int = 0
    deepest: ET.Element | None = None  # first element beyond MAX_TREE_DEPTH, if any
    refs: list[tuple[str, int, ET.Element]] = field(default_factory=list)  # (ID, depth, elem)


def _shape(bt: ET.Element) -> _Shape:
    shape = _Shape()
    stack: list[tuple[ET.Element, int]] = [(child, 1) for child in bt]
    while stack:
        elem, depth = stack.pop()
        if depth > shape.depth:
            shape.depth = depth
        if depth > MAX_TREE_DEPTH and shape.deepest is None:
            shape.deepest = elem
        if elem.tag == "SubTree":
            bt_id = elem.attrib.get("ID")
            if bt_id:
                shape.refs.append((bt_id, depth, elem))
            continue
        shape.nodes += 1
        stack.extend((child, depth + 1) for child in elem)
    return shape


def _adder(doc: TreeDocument, problems: list[TreeProblem]) -> Callable[[ET.Element, str], None]:
    def add(elem: ET.Element, message: str) -> None:
        problem = TreeProblem(
            source_file(elem, doc.file), source_line(elem), describe(elem), message
        )
        if problem not in problems:
            problems.append(problem)

    return add


def tree_size_problems(doc: TreeDocument) -> list[TreeProblem]:
    """Problems of a read document's size: nested too deep, too many nodes once expanded.

    Returns
    -------
    list of TreeProblem
        Empty when the main tree, subtrees expanded, is within :data:`MAX_TREE_DEPTH` and
        :data:`MAX_TREE_NODES` (and every tree as written within the depth).
    """
    trees = doc.behaviour_trees()
    shapes = {bt_id: _shape(bt) for bt_id, bt in trees.items()}
    problems: list[TreeProblem] = []
    add = _adder(doc, problems)
    for shape in shapes.values():
        if shape.deepest is not None:
            add(
                shape.deepest,
                f"nested {shape.depth} levels deep; expected at most {MAX_TREE_DEPTH} (a deeper "
                "tree cannot be built, ticked or drawn)",
            )
    if problems:
        return problems
    sizes: dict[str, tuple[int, int]] = {}  # ID -> (expanded nodes, expanded depth)
    for bt_id in _postorder(shapes):
        shape = shapes[bt_id]
        nodes, depth = shape.nodes, shape.depth
        for ref, at, _ in shape.refs:
            if ref in sizes:  # not yet when the reference closes a cycle (reported apart)
                nodes = min(nodes + sizes[ref][0], MAX_TREE_NODES + 1)
                depth = max(depth, min(at - 1 + sizes[ref][1], MAX_TREE_DEPTH + 1))
        sizes[bt_id] = (nodes, depth)
    main = doc.main_tree_id
    if main in sizes and main in trees:
        nodes, depth = sizes[main]
        if depth > MAX_TREE_DEPTH:
            add(
                trees[main],
                f"nested more than {MAX_TREE_DEPTH} levels deep once its subtrees are expanded; "
                f"expected at most {MAX_TREE_DEPTH}",
            )
        if nodes > MAX_TREE_NODES:
            add(
                trees[main],
                f"expands to more than {MAX_TREE_NODES} nodes through its subtrees; expected "
                f"at most {MAX_TREE_NODES} (each <SubTree> is a copy of its tree)",
            )
    return problems


def subtree_cycle_problems(doc: TreeDocument) -> list[TreeProblem]:
    """One problem per ``<SubTree>`` that closes a cycle (named or not): a tree in itself."""
    shapes = {bt_id: _shape(bt) for bt_id, bt in doc.behaviour_trees().items()}
    problems: list[TreeProblem] = []
    add = _adder(doc, problems)
    for elem, cycle in _cycles(shapes):
        add(elem, f"subtree cycle {' -> '.join(cycle)}; a tree cannot contain itself")
    return problems


def _cycles(shapes: dict[str, _Shape]) -> list[tuple[ET.Element, list[str]]]:
    """Each subtree reference that closes a cycle: (the ``<SubTree>``, the cycle's IDs)."""
    found: list[tuple[ET.Element, list[str]]] = []
    done: set[str] = set()
    for start in shapes:
        if start in done:
            continue
        path: list[str] = [start]
        on_path = {start}
        iters = [iter(shapes[start].refs)]
        while iters:
            step = next(iters[-1], None)
            if step is None:
                iters.pop()
                done.add(path[-1])
                on_path.discard(path.pop())
                continue
            ref, _, elem = step
            if ref in on_path:
                found.append((elem, [*path[path.index(ref) :], ref]))
            elif ref in shapes and ref not in done:
                path.append(ref)
                on_path.add(ref)
                iters.append(iter(shapes[ref].refs))
    return found


def _postorder(shapes: dict[str, _Shape]) -> list[str]:
    """Tree IDs, each after every tree it uses (the graph has no cycles here)."""
    order: list[str] = []
    seen: set[str] = set()
    for start in shapes:
        if start in seen:
            continue
        seen.add(start)
        stack = [(start, iter(shapes[start].refs))]
        while stack:
            bt_id, refs = stack[-1]
            step = next(refs, None)
            if step is None:
                stack.pop()
                order.append(bt_id)
            elif step[0] in shapes and step[0] not in seen:
                seen.add(step[0])
                stack.append((step[0], iter(shapes[step[0]].refs)))
    return order


__all__ = ["MAX_TREE_DEPTH", "MAX_TREE_NODES", "subtree_cycle_problems", "tree_size_problems"]
