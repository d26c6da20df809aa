"""Check a behaviour tree file without building it: tags, ports, literals, subtrees, names.

A tree file is BehaviorTree.CPP v4 style XML. :func:`read_tree_document` reads it with the line
of every element, inlines ``<include>`` files and translates BT.CPP spellings (``Fallback``,
``RetryUntilSuccessful num_attempts=``, ``Timeout msec=`` ...) into the tags py_trees' parser
builds; :func:`check_tree_document` then finds every problem the parser (or a first tick) would
trip over, each with file, line, node and what was expected. :mod:`planner.loader` runs the
same two steps before it builds, so a tree that validates also loads.

This module is the entry point; the work is done by :mod:`planner.tree_reading` (reading and
translating), :mod:`planner.tree_ports` (the registry, ports and literals),
:mod:`planner.tree_checks` (the checks) and :mod:`planner.tree_problems` (what they report).
"""

from __future__ import annotations

import os
import sys
import xml.etree.ElementTree as ET
from collections.abc import Collection, Iterator

from planner.tree_checks import check_tree_document
from planner.tree_ports import Registry, effective_registry
from planner.tree_problems import TreeFileError, TreeProblem
from planner.tree_reading import (
    TreeDocument,
    read_tree_document,
    read_tree_document_string,
)

__all__ = [
    "TreeDocument",
    "TreeFileError",
    "TreeProblem",
    "check_tree_document",
    "effective_registry",
    "read_tree_document",
    "read_tree_document_string",
    "tree_cli_validate",
    "validate_tree",
    "validate_tree_string",
]


def validate_tree(
    path: str | os.PathLike[str],
    registry: Registry | None = None,
    *,
    main_tree_id: str | None = None,
    run_keys: Collection[str] | None = None,
) -> list[TreeProblem]:
    """Check a tree file without building it; return its problems (empty when it is fine).

    Checks: XML syntax; unknown tags (not a registered leaf, control node or ``SubTree``);
    unknown, missing required and wrongly typed ports; output ports given literals; subtree
    IDs and their remapped ports; the main tree; child counts (decorators exactly one,
    control nodes at least one, leaves none); names the parser would duplicate; subtree cycles.
    ``main_tree_id`` names the tree to check as the main one instead of ``main_tree_to_execute``
    (a file saved by Groot2 has none). ``run_keys``: for a tree Duet will run, the keys the
    run sets (:func:`planner.tree_checks.check_tree_document`).
    """
    try:
        doc = read_tree_document(path, registry, main_tree_id)
    except TreeFileError as exc:
        return list(exc.problems)
    return check_tree_document(doc, registry, run_keys=run_keys)


def validate_tree_string(
    text: str,
    source: str = "<string>",
    registry: Registry | None = None,
    *,
    run_keys: Collection[str] | None = None,
) -> list[TreeProblem]:
    """Check tree XML given as a string (see :func:`validate_tree`)."""
    try:
        doc = read_tree_document_string(text, source, registry)
    except TreeFileError as exc:
        return list(exc.problems)
    return check_tree_document(doc, registry, run_keys=run_keys)


def tree_cli_validate(
    path: str | os.PathLike[str],
    registry: Registry | None = None,
    *,
    main_tree_id: str | None = None,
    run_keys: Collection[str] | None = None,
) -> int:
    """Validate a tree file for the command line.

    Prints each problem on its own line to stderr and returns 2, or prints a one-line
    ``ok`` summary to stdout and returns 0.
    """
    problems = validate_tree(path, registry, main_tree_id=main_tree_id, run_keys=run_keys)
    if problems:
        for problem in problems:
            print(problem, file=sys.stderr)
        plural = "s" if len(problems) != 1 else ""
        print(f"{os.fspath(path)}: {len(problems)} problem{plural}", file=sys.stderr)
        return 2
    doc = read_tree_document(path, registry, main_tree_id)
    n_nodes = sum(1 for bt in doc.root.findall("BehaviorTree") for _ in _nodes(bt))
    n_trees = len(doc.behaviour_trees())
    print(
        f"{os.fspath(path)}: ok (main tree '{doc.main_tree_id}', {n_trees} tree"
        f"{'s' if n_trees != 1 else ''}, {n_nodes} nodes)"
    )
    return 0


def _nodes(bt: ET.Element) -> Iterator[ET.Element]:
    for elem in bt.iter():
        if elem is not bt:
            yield elem
