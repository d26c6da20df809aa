"""Load behaviour trees from BehaviorTree.CPP v4 style XML: the one wrapper around py_trees' parser.

py_trees' XML parser (:mod:`py_trees.parsers.behaviour_tree_xml`) is experimental, so nothing
else in the project calls it. This module:

1. reads the file with line numbers, inlines ``<include path=...>`` and translates BT.CPP
   spellings (``Fallback``, ``ReactiveSequence``, ``RetryUntilSuccessful num_attempts=``,
   ``Timeout msec=``, ``ForceSuccess``, ``Parallel success_count=``, ``<Action ID=...>``),
2. checks it (:mod:`planner.validate`) so that mistakes come back as :class:`TreeFileError`
   naming file, line, node and expectation,
3. hands the translated XML to py_trees' parser with ``Timeout`` bound to
   :class:`~planner.decorators.SimTimeout` (simulated time).

Example::

    root = load_tree("trees/pick_place.xml")
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(world=world, clock=lambda: world.time)
"""

from __future__ import annotations

import functools
import os
import re
import tempfile
import weakref
import xml.etree.ElementTree as ET
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

import py_trees
import py_trees.ports_utils
from py_trees.parsers.behaviour_tree_xml import parse_behaviour_tree_xml

from planner.bt_decorators import propagate_skips
from planner.bt_scripting import attach_conditions
from planner.tree_checks import check_tree_document
from planner.tree_ports import Registry, effective_registry
from planner.tree_problems import TreeFileError, TreeProblem
from planner.tree_reading import (
    TreeDocument,
    describe,
    read_tree_document,
    read_tree_document_string,
)

__all__ = [
    "TreeFileError",
    "load_document",
    "load_tree",
    "load_tree_string",
    "main_tree_id",
    "subtree_ids",
]

#: For each root the loader built: the ``<BehaviorTree ID>`` of each named ``<SubTree>`` instance
#: (by its name), where one name has one ID. Weak keys: a tree dropped is forgotten.
_SUBTREE_IDS: weakref.WeakKeyDictionary[py_trees.behaviour.Behaviour, dict[str, str]] = (
    weakref.WeakKeyDictionary()
)
#: For each root the loader built: the ``<BehaviorTree ID>`` it is the root of.
_MAIN_TREE_IDS: weakref.WeakKeyDictionary[py_trees.behaviour.Behaviour, str] = (
    weakref.WeakKeyDictionary()
)


def _once_per_class(
    collect: Callable[[Callable[..., Any]], dict[str, Any]],
) -> Callable[[Callable[..., Any]], dict[str, Any]]:
    """``collect`` (py_trees' ``collect_type_hints``) computed once per class.

    The parser asks for a class's constructor hints once per node, and each time walks the
    class's MRO with ``inspect.signature``: half of building the default tree. A class's
    hints do not change, so each class's are kept (weakly: a class dropped is forgotten) and
    a copy handed out; anything but a class (a ``functools.partial``) is asked every time.
    """
    if getattr(collect, "_once_per_class", False):  # this module imported again
        return collect
    found: weakref.WeakKeyDictionary[type, dict[str, Any]] = weakref.WeakKeyDictionary()

    @functools.wraps(collect)
    def hints(constructor: Callable[..., Any]) -> dict[str, Any]:
        if not isinstance(constructor, type):
            return collect(constructor)
        if constructor not in found:
            found[constructor] = collect(constructor)
        return dict(found[constructor])

    hints._once_per_class = True  # type: ignore[attr-defined]
    return hints


py_trees.ports_utils.collect_type_hints = _once_per_class(  # type: ignore[assignment]
    py_trees.ports_utils.collect_type_hints
)


def main_tree_id(root: py_trees.behaviour.Behaviour) -> str | None:
    """The ``<BehaviorTree ID>`` a tree this module loaded was built from (its main tree), or
    None for a tree built otherwise."""
    return _MAIN_TREE_IDS.get(root)


def subtree_ids(root: py_trees.behaviour.Behaviour) -> dict[str, str] | None:
    """``{instance name: subtree ID}`` of the SubTrees of a tree this module loaded (they are
    inlined: no node stands for them), or None for a tree built otherwise."""
    return _SUBTREE_IDS.get(root)


def load_tree(
    path: str | os.PathLike[str],
    registry: Registry | None = None,
    *,
    main_tree_id: str | None = None,
    run_keys: Collection[str] | None = None,
) -> py_trees.behaviour.Behaviour:
    """Build the main tree of an XML file and return its root behaviour.

    ``run_keys``: for a tree Duet will run, the blackboard keys the run sets before the first
    tick; a port reading a key nothing writes is then refused
    (:func:`planner.tree_checks.check_tree_document`).

    Parameters
    ----------
    path : path-like
        BehaviorTree.CPP v4 style XML (``<root BTCPP_format="4" main_tree_to_execute=...>``).
    registry : mapping tag -> class or functools.partial, optional
        Leaf classes by tag. Default: every imported ports-enabled behaviour (py_trees' global
        ports registry). ``Timeout`` is :class:`~planner.decorators.SimTimeout` unless given.
    main_tree_id : str, optional
        The ``<BehaviorTree ID>`` to build instead of ``main_tree_to_execute``.

    Returns
    -------
    py_trees.behaviour.Behaviour
        The root; ports are wired, ``setup()`` has not been called.

    Raises
    ------
    TreeFileError
        For anything wrong with the file; ``str()`` lists ``file:line: <Tag name="..">: what
        was expected`` one per line (XML syntax errors give ``file:line:col``).
    """
    return load_document(read_tree_document(path, registry, main_tree_id), registry, run_keys)


def load_tree_string(
    text: str,
    source: str = "<string>",
    registry: Registry | None = None,
    *,
    main_tree_id: str | None = None,
    run_keys: Collection[str] | None = None,
) -> py_trees.behaviour.Behaviour:
    """Build a tree from XML text; ``source`` labels it in messages (see :func:`load_tree`)."""
    doc = read_tree_document_string(text, source, registry, main_tree_id)
    return load_document(doc, registry, run_keys)


def _name_subtrees(doc: TreeDocument) -> None:
    """Name each ``<SubTree>`` the file leaves unnamed ``ID::k`` (the k-th of that ID, as
    BehaviorTree.CPP's paths name an instance by its ID): py_trees would name it by a fresh
    uuid4, which reached ``run.btlog``'s subtree IDs and ``run.jsonl``'s clients, another in
    every run. Each is still its own instance, with a blackboard of its own."""
    count: dict[str, int] = {}
    for bt in doc.root.findall("BehaviorTree"):
        for elem in bt.iter("SubTree"):
            tree_id = elem.attrib.get("ID")
            if tree_id is not None and not elem.attrib.get("name"):
                count[tree_id] = count.get(tree_id, 0) + 1
                elem.attrib["name"] = f"{tree_id}::{count[tree_id]}"


def load_document(
    doc: TreeDocument, registry: Registry | None = None, run_keys: Collection[str] | None = None
) -> py_trees.behaviour.Behaviour:
    """Build the main tree of a document already read (:func:`planner.tree_reading.
    read_tree_document`), as :func:`load_tree` does: for a caller that needs the document too
    (the files it was read from)."""
    problems = check_tree_document(doc, registry, run_keys=run_keys)
    if problems:
        raise TreeFileError(problems)
    assert doc.main_tree_id is not None  # a document without one has a problem above
    _name_subtrees(doc)
    text = ET.tostring(doc.root, encoding="unicode")
    # The parser reads files only; the translated document is self-contained (includes inlined).
    handle, tmp = tempfile.mkstemp(suffix=".xml", prefix="duet_tree_")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            out.write(text)
        root = parse_behaviour_tree_xml(
            tmp, main_tree_id=doc.main_tree_id, node_registry=effective_registry(registry)
        )
    except Exception as exc:  # the parser and leaf constructors may raise anything
        raise TreeFileError([_build_problem(doc, exc)]) from exc
    finally:
        Path(tmp).unlink(missing_ok=True)
    ids: dict[str, set[str]] = {}
    for bt in doc.root.findall("BehaviorTree"):
        for elem in bt.iter("SubTree"):
            if "name" in elem.attrib and "ID" in elem.attrib:
                ids.setdefault(elem.attrib["name"], set()).add(elem.attrib["ID"])
    _SUBTREE_IDS[root] = {name: next(iter(i)) for name, i in ids.items() if len(i) == 1}
    _MAIN_TREE_IDS[root] = doc.main_tree_id
    trees = doc.behaviour_trees()
    attach_conditions(trees[doc.main_tree_id], root, trees, "/")
    propagate_skips(root)
    return root


def _build_problem(doc: TreeDocument, exc: Exception) -> TreeProblem:
    """Attribute a build failure to the element it names, when exactly one fits."""
    message = str(exc).replace("\n", " ") or type(exc).__name__
    quoted = set(re.findall(r"'([^']+)'", message))
    candidates = [
        elem
        for bt in doc.root.findall("BehaviorTree")
        for elem in bt.iter()
        if elem.tag in quoted or elem.attrib.get("name") in quoted
    ]
    if len(candidates) == 1:
        elem = candidates[0]
        return TreeProblem(
            getattr(elem, "sourcefile", doc.file),
            getattr(elem, "sourceline", None),
            describe(elem),
            f"cannot build: {message}",
        )
    return TreeProblem(doc.file, None, "", f"cannot build tree '{doc.main_tree_id}': {message}")
