"""The default tree: the shipped ``planner/trees/pick_and_place.xml``, the one source of it.

For the paper's task (one object, three moves) it is the file as shipped. A task of another
number of moves gets the same document with its main tree's ``Move`` subtree instantiated
once per move (the subtrees, compositions and guards are the file's own), so no tree is ever
built a second way in code.
"""

from __future__ import annotations

import copy
import xml.etree.ElementTree as ET
from pathlib import Path

from py_trees.behaviour import Behaviour

import planner.leaves  # noqa: F401  (registers the leaves the file uses)
from planner.loader import load_tree, load_tree_string

__all__ = ["PICK_AND_PLACE_XML", "default_tree", "pick_and_place_xml"]

#: The shipped tree of the paper's task.
PICK_AND_PLACE_XML = Path(__file__).resolve().parent / "trees" / "pick_and_place.xml"

#: The shipped file's names for its three moves; further moves are ``move_<i>``.
_MOVE_NAMES = ("move_centre", "move_right", "move_left")
_SHIPPED_MOVES = len(_MOVE_NAMES)


def pick_and_place_xml(moves: int) -> str:
    """The shipped document with ``moves`` instances of its ``Move`` subtree, as XML text.

    Raises
    ------
    ValueError
        If ``moves`` is below 1.
    """
    if moves < 1:
        raise ValueError(f"pick_and_place_xml: expected at least 1 move, got {moves}")
    root = ET.parse(PICK_AND_PLACE_XML).getroot()
    main = root.find(f"BehaviorTree[@ID='{root.get('main_tree_to_execute')}']")
    sequence = main[0] if main is not None and len(main) else None
    assert sequence is not None, f"{PICK_AND_PLACE_XML}: expected a main tree with a Sequence"
    shipped = [e for e in sequence if e.tag == "SubTree" and e.get("ID") == "Move"]
    at = list(sequence).index(shipped[0])
    for element in shipped:
        sequence.remove(element)
    for i in range(moves):
        element = copy.deepcopy(shipped[0])
        element.set("name", _MOVE_NAMES[i] if i < _SHIPPED_MOVES else f"move_{i}")
        element.set("move", str(i))
        sequence.insert(at + i, element)
    return ET.tostring(root, encoding="unicode")


def default_tree(moves: int = _SHIPPED_MOVES) -> Behaviour:
    """The tree ``app.py run`` and ``trials`` run without ``--tree``, for ``moves`` moves.

    Returns the root of ``planner/trees/pick_and_place.xml`` as loaded by
    :func:`planner.loader.load_tree` (three moves), or of :func:`pick_and_place_xml`.
    """
    if moves == _SHIPPED_MOVES:
        return load_tree(PICK_AND_PLACE_XML)
    return load_tree_string(
        pick_and_place_xml(moves), source=f"{PICK_AND_PLACE_XML} ({moves} moves)"
    )
