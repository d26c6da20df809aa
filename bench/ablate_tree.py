"""Write a copy of a tree file without some of its nodes, for ablation campaigns.

Every element whose ``name`` attribute is one of ``--without`` is removed with its subtree,
wherever it occurs (a Fallback's recovery branch, a check). The copy is loaded once, so a
removal that leaves a control node without children, or the tree unreadable, is refused
(exit 2) rather than written. Example, Hard mode without the recovery re-grasp (the Move
subtree's ``regrasp`` branch; re-grasps that a turn needs stay)::

    python bench/ablate_tree.py planner/trees/pick_and_place.xml --without regrasp \
        --out /tmp/no_regrasp.xml
    # a copy of the world whose ``tree:`` is /tmp/no_regrasp.xml (and another name)
    python app.py trials /tmp/no_regrasp_world.yaml --hard --n 100 --seed 0

The copy goes in a world's ``tree`` field, not ``--tree``: a world's tree is made into each
trial's task (a turned goal the grip cannot make in one move is several moves), while a tree
given with ``--tree`` runs as written, with the shipped file's three moves; on trials with
turned goals a trial with more moves than the file names fails at once, saying so.
"""

from __future__ import annotations

import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import planner.leaves  # noqa: F401  (registers the leaves the tree uses)
from planner.loader import TreeFileError, load_tree
from planner.tree_dataflow import RUN_WRITES


def without(root: ET.Element, names: set[str]) -> list[str]:
    """Remove from ``root`` every element named in ``names``; the names removed, in order."""
    removed = []
    for parent in list(root.iter()):
        for child in list(parent):
            if child.get("name") in names:
                parent.remove(child)
                removed.append(str(child.get("name")))
    return removed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tree", type=Path, help="tree file (BehaviorTree.CPP v4 XML)")
    parser.add_argument("--without", nargs="+", required=True, help="node names to remove")
    parser.add_argument("--out", type=Path, required=True, help="where to write the copy")
    args = parser.parse_args()
    document = ET.parse(args.tree)
    removed = without(document.getroot(), set(args.without))
    missing = sorted(set(args.without) - set(removed))
    if missing:
        print(f"{args.tree}: no node named {', '.join(missing)}", file=sys.stderr)
        return 2
    document.write(args.out, encoding="unicode", xml_declaration=True)
    try:
        load_tree(args.out, run_keys=RUN_WRITES)
    except TreeFileError as err:
        args.out.unlink()
        print(f"{args.out}: the copy does not load: {err}", file=sys.stderr)
        return 2
    print(f"wrote {args.out} without {len(removed)} node(s): {', '.join(removed)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
