"""Write a copy of a tree file without some of its nodes, or with some ports set, for
ablation campaigns.

Every element whose ``name`` attribute is one of ``--without`` is removed with its subtree,
wherever it occurs (a Fallback's recovery branch, a check). ``--set NAME PORT=VALUE`` sets a
port of every element named ``NAME``. The copy is loaded once, so a removal that leaves a
control node without children, a port the node does not have, or the tree unreadable, is
refused (exit 2) rather than written. Example, Hard mode without the recovery re-grasp (the
Move subtree's ``regrasp`` branch; re-grasps that a turn needs stay)::

    python bench/ablate_tree.py planner/trees/pick_and_place.xml --without regrasp \
        --out /tmp/no_regrasp.xml
    # a copy of the world whose ``tree:`` is /tmp/no_regrasp.xml (and another name)
    python app.py trials /tmp/no_regrasp_world.yaml --hard --n 100 --seed 0

and without grasp maintenance in the carries (their hold terms composed at weight 0; the
grasp still closes with them; the world that runs it is
``bench/worlds/parcel_pick_place_no_hold.yaml``)::

    python bench/ablate_tree.py planner/trees/pick_and_place.xml \
        --set path_clear hold_gain=0 --set transport hold_gain=0 \
        --set careful_transport hold_gain=0 --set careful_path_clear hold_gain=0 \
        --out bench/worlds/pick_and_place_no_hold.xml

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
    removed: list[str] = []
    for parent in list(root.iter()):
        for child in list(parent):
            if child.get("name") in names:
                parent.remove(child)
                removed.append(str(child.get("name")))
    return removed


def with_ports(root: ET.Element, settings: list[tuple[str, str, str]]) -> list[str]:
    """Set, per ``(name, port, value)``, the port of every element named ``name``; the names
    of the settings that matched no element."""
    unmatched = []
    for name, port, value in settings:
        found = [e for e in root.iter() if e.get("name") == name]
        for element in found:
            element.set(port, value)
        if not found:
            unmatched.append(name)
    return unmatched


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tree", type=Path, help="tree file (BehaviorTree.CPP v4 XML)")
    parser.add_argument("--without", nargs="+", default=[], help="node names to remove")
    parser.add_argument(
        "--set",
        nargs=2,
        action="append",
        default=[],
        metavar=("NAME", "PORT=VALUE"),
        help="set a port of the nodes named NAME (repeatable)",
    )
    parser.add_argument("--out", type=Path, required=True, help="where to write the copy")
    args = parser.parse_args()
    if not args.without and not args.set:
        print("ablate_tree: give --without, --set or both", file=sys.stderr)
        return 2
    settings = []
    for name, assignment in args.set:
        port, sep, value = assignment.partition("=")
        if not sep or not port:
            print(f"--set {name} {assignment}: expected PORT=VALUE", file=sys.stderr)
            return 2
        settings.append((name, port, value))
    document = ET.parse(args.tree)
    removed = without(document.getroot(), set(args.without))
    missing = sorted(set(args.without) - set(removed))
    missing += with_ports(document.getroot(), settings)
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
    changes = [f"without {len(removed)} node(s): {', '.join(removed)}"] if removed else []
    changes += [f"{name}.{port}={value}" for name, port, value in settings]
    print(f"wrote {args.out} {'; '.join(changes)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
