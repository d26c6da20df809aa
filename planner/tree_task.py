"""Does a tree's task match a world's? The move indices a tree names, against the moves the
world's task has; and the grasps its leaves make.

A tree names moves by index (``move="2"`` on a ``SubTree`` or a leaf, counted from 0 per
object); the object is a literal name (``object="box_b"``) or a blackboard key
(``object="{object}"``), which the episode binds to ``bound_object``. Only literal indices can
be checked; a ``{key}`` is resolved by the subtree instance that remaps it, whose literal is
checked where it is written. Two mismatches are reported: a move the world's task does not have
(the tree would fail at that node after the moves before it were simulated), and a move of the
world that no node names (the tree would leave it undone).
"""

from __future__ import annotations

from collections.abc import Mapping

from planner.leaves.select import SelectSkills
from planner.tree_ports import Registry, effective_registry, registry_class
from planner.tree_problems import TreeProblem
from planner.tree_reading import TreeDocument, describe, source_file, source_line
from skills.vocabulary import GraspType

#: The port that names a move, on subtrees and leaves alike.
MOVE_PORT = "move"
OBJECT_PORT = "object"


def _literal(value: str | None) -> str | None:
    """The value if it is a literal (not a ``{key}`` reference), else None."""
    if value is None or (value.startswith("{") and value.endswith("}")):
        return None
    return value


def _port_default(reg: Registry, tag: str) -> object:
    """The default of node ``tag``'s ``move`` port, where it is a registered node with one."""
    cls = registry_class(reg[tag]) if tag in reg else None
    port = getattr(cls, "INPUT_PORTS", {}).get(MOVE_PORT) if cls is not None else None
    return None if port is None else port.default_value


def _moves_phrase(name: str, count: int) -> str:
    plural = "move" if count == 1 else "moves"
    span = f" (indices 0..{count - 1})" if count else ""
    return f"the world's task has {count} {plural} for {name}{span}"


def check_tree_moves(
    doc: TreeDocument,
    moves: Mapping[str, int],
    bound_object: str | None,
    notes: Mapping[str, str] | None = None,
) -> list[TreeProblem]:
    """Problems of a tree's move indices against a world's task.

    Parameters
    ----------
    doc : TreeDocument
        The tree, read (:func:`planner.tree_reading.read_tree_document`).
    moves : mapping of str to int
        Number of moves per object of the world's task.
    bound_object : str or None
        The object a ``{...}`` object port is bound to when the tree runs; None if unknown
        (then indices on such nodes are not checked).
    notes : mapping of str to str, optional
        Per object, why its count differs from its world file's (a turn made in steps),
        added where the count is given.

    Returns
    -------
    list of TreeProblem
        Empty when every literal index exists and every move of the checked objects is named.
    """
    problems: list[TreeProblem] = []
    named: dict[str, set[int]] = {}
    notes = notes or {}
    reg = effective_registry(None)

    def phrase(name: str) -> str:
        note = notes.get(name)
        return _moves_phrase(name, moves[name]) + (f" ({note})" if note else "")

    for elem in doc.root.iter():
        raw = _literal(elem.attrib.get(MOVE_PORT))
        if raw is None:
            continue
        where = (source_file(elem, doc.file), source_line(elem), describe(elem))
        name = _literal(elem.attrib.get(OBJECT_PORT)) or bound_object
        if name is None:
            continue
        try:
            index = int(raw)
        except ValueError:
            continue  # not a whole number: the port checks report it
        if index < 0 and (elem.tag == "SubTree" or index == _port_default(reg, elem.tag)):
            # The node's own "no move" (Approach's -1), as Groot2 writes defaults out, or a
            # value a subtree passes on to such nodes (they say so if theirs is not -1).
            continue
        if name not in moves:
            known = ", ".join(sorted(moves)) or "none"
            problems.append(
                TreeProblem(
                    *where, f"object {name!r} is not in the world's task (objects: {known})"
                )
            )
            continue
        if not 0 <= index < moves[name]:
            problems.append(TreeProblem(*where, f"move {index}, but {phrase(name)}"))
            continue
        named.setdefault(name, set()).add(index)
    for name, indices in named.items():
        missing = [i for i in range(moves[name]) if i not in indices]
        if missing:
            listed = ", ".join(str(i) for i in sorted(indices))
            left = ", ".join(str(i) for i in missing)
            problems.append(
                TreeProblem(
                    doc.file,
                    None,
                    "",
                    f"names moves {listed} of {name}, but {phrase(name)}: "
                    f"move{'s' if len(missing) > 1 else ''} {left} would be left undone",
                )
            )
    return problems


def tree_grasps(doc: TreeDocument, registry: Registry | None = None) -> frozenset[GraspType] | None:
    """The grasps the tree's :class:`~planner.leaves.select.SelectSkills` nodes ask the
    reasoner for (their ``grasp`` port, or its default): the only grasps its leaves make.

    Returns None when that is not known: no such node, or a ``grasp`` given by a ``{key}``.
    """
    reg = effective_registry(registry)
    default = str(SelectSkills.INPUT_PORTS["grasp"].default_value)
    grasps: set[GraspType] = set()
    for elem in doc.root.iter():
        cls = registry_class(reg[elem.tag]) if elem.tag in reg else None
        if cls is None or not issubclass(cls, SelectSkills):
            continue
        value = elem.attrib.get("grasp", default)
        if _literal(value) is None or value not in {g.value for g in GraspType}:
            return None  # a blackboard key, or a bad literal the port checks report
        grasps.add(GraspType(value))
    return frozenset(grasps) or None


__all__ = ["check_tree_moves", "tree_grasps"]
