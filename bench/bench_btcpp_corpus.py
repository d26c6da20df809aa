"""How many of BehaviorTree.CPP's own example and test trees Duet's validator accepts.

Run from the project folder as ``python -m bench.bench_btcpp_corpus PATH [--json] [--list]``,
``PATH`` a BT.CPP 4.x checkout (without it, or ``$BTCPP_DIR``, it says so and exits 0, so
``make bench`` passes on a machine without one). It collects every tree under ``examples/``
and ``tests/``: the ``.xml`` files, and the raw string literals (``R"( ... )"``) holding a
``<root ...>...</root>`` in the C++ sources (a piece of a tree a test builds in code is left
out). For each it runs :func:`planner.validate.validate_tree` as
``app.py validate --nodes`` would for a tree of another robot, and prints the total, the
accepted, the percent and the rejection causes, each counted once per tree it blocks.

How the trees are taken as BT.CPP's tests take them:

* Leaves: a tree's node IDs that are not Duet built-ins are the test's own registrations
  (``factory.registerNodeType<...>``). Each gets a stub from a TreeNodesModel written for it
  (:mod:`planner.model_stubs`): an ``Action`` (or the ``Condition``, ``Decorator``,
  ``Control`` it is written as; else a decorator with one child, a control with more), its
  ports the attributes the tree gives it, as strings. No dataflow check: the host's keys are
  unknown, as with ``--nodes``.
* Trees registered together: a tree calling a ``<SubTree ID>`` defined in another literal of
  the same source file gets that definition added (``registerBehaviorTreeFromText`` twice,
  then ``createTree``).
* The main tree: ``main_tree_to_execute``, else the only tree, else the one no other tree
  calls (else the first), as the test's ``createTree("Main")`` names it.
* Trees BT.CPP itself rejects: a literal whose variable (or the literal itself) appears in
  an ``EXPECT_THROW``/``ASSERT_THROW``/``*_ANY_THROW`` of its file is counted apart, as
  "expected to throw", not in the total; Duet's figure on them is printed too (rejecting
  them is right). A test that throws at run time, not at load, lands there as well.

With ``--json`` the last line is the JSON of the figures; ``--list`` prints each tree's verdict.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import tempfile
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import py_trees

from planner.model_stubs import model_stub_classes
from planner.tree_checks import _BUILTIN_DECORATORS, COMPOSITES
from planner.tree_ports import effective_registry
from planner.tree_problems import TreeFileError
from planner.tree_reading import TreeDocument, lenient_xml, read_tree_document
from planner.validate import validate_tree

#: A raw string literal, ``R"delim( ... )delim"``.
_RAW = re.compile(r'R"([^()\s\\]{0,16})\((.*?)\)\1"', re.S)
#: ``name = R"(`` before a literal: ``const char* xml_text = R"(``, ``auto xml = R"(``...
_ASSIGNED = re.compile(r"(\w+)(?:\[\])?\s*(?:=|\()\s*$")
_THROW = re.compile(r"\b(?:EXPECT|ASSERT)_(?:ANY_)?THROW\s*\(")
_TEST = re.compile(r"^\s*TEST(?:_F|_P)?\s*\(", re.M)
_KINDS = ("Action", "Condition", "Decorator", "Control")


@dataclass
class Tree:
    """One tree of the corpus: where it is, its text, whether BT.CPP's test expects a throw."""

    source: str
    line: int
    text: str
    throws: bool = False
    verdict: list[str] = field(default_factory=list)


def _throw_statements(code: str) -> list[tuple[int, str]]:
    """(offset, text) of every ``*_THROW(...)`` statement of a C++ source."""
    found = []
    for match in _THROW.finditer(code):
        depth, i = 1, match.end()
        while i < len(code) and depth:
            depth += {"(": 1, ")": -1}.get(code[i], 0)
            i += 1
        found.append((match.start(), code[match.start() : i]))
    return found


def _test_bodies(code: str) -> list[tuple[int, int]]:
    """(start, end) offsets of each ``TEST(...) { ... }`` body (braces matched)."""
    bodies = []
    for match in _TEST.finditer(code):
        start = code.find("{", match.end())
        if start < 0:
            continue
        depth, i = 1, start + 1
        while i < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[i], 0)
            i += 1
        bodies.append((start, i))
    return bodies


def _expected_to_throw(code: str, start: int, literal: str, name: str | None) -> bool:
    """Whether BT.CPP's test expects an exception with the literal at ``start``: a literal in
    a test body whose test has a ``*_THROW``; a literal outside any test whose variable a
    ``*_THROW`` names (in a test without its own literal of that name)."""
    throws = _throw_statements(code)
    bodies = _test_bodies(code)
    body = next(((a, b) for a, b in bodies if a <= start < b), None)
    if body is not None:
        return any(body[0] <= at < body[1] for at, _ in throws)
    if any(literal in text for _, text in throws):
        return True
    if name is None:
        return False
    for at, text in throws:
        if re.search(rf"\b{name}\b", text) is None:
            continue
        inside = next(((a, b) for a, b in bodies if a <= at < b), (0, 0))
        if not re.search(rf"\b{name}\s*=\s*R\"", code[inside[0] : inside[1]]):
            return True
    return False


def collect(checkout: Path) -> list[Tree]:
    """Every tree of ``examples/`` and ``tests/``: XML files and raw literals in C++ sources."""
    trees: list[Tree] = []
    for folder in ("examples", "tests"):
        for path in sorted((checkout / folder).rglob("*")):
            rel = str(path.relative_to(checkout))
            if path.suffix == ".xml":
                text = path.read_text(encoding="utf-8", errors="replace")
                if "<root" in text:
                    trees.append(Tree(rel, 1, text))
            elif path.suffix in (".cpp", ".cc", ".h", ".hpp"):
                code = path.read_text(encoding="utf-8", errors="replace")
                for match in _RAW.finditer(code):
                    body = match.group(2)
                    if "<root" not in body or "</root>" not in body:
                        continue  # not a tree, or a piece of one the test builds in code
                    before = code[max(0, match.start() - 80) : match.start()]
                    var = _ASSIGNED.search(before)
                    throws = _expected_to_throw(
                        code, match.start(), match.group(0), var.group(1) if var else None
                    )
                    line = code.count("\n", 0, match.start()) + 1
                    trees.append(Tree(rel, line, body, throws=throws))
    return trees


def _parse(text: str) -> ET.Element | None:
    try:
        return ET.fromstring(lenient_xml(text).strip())
    except ET.ParseError:
        return None


def add_sibling_subtrees(trees: list[Tree]) -> None:
    """Give a literal the ``<BehaviorTree>`` definitions its SubTrees call from the other
    literals of its file (in place)."""
    by_file: dict[str, dict[str, ET.Element]] = {}
    for tree in trees:
        root = _parse(tree.text)
        if root is None:
            continue
        for bt in root.findall("BehaviorTree"):
            if "ID" in bt.attrib:
                by_file.setdefault(tree.source, {}).setdefault(bt.attrib["ID"], bt)
    for tree in trees:
        root = _parse(tree.text)
        known = by_file.get(tree.source, {})
        if root is None or not known:
            continue
        defined = {bt.attrib.get("ID") for bt in root.findall("BehaviorTree")}
        added = False
        todo = [s.attrib.get("ID", "") for s in root.iter("SubTree")]
        while todo:
            wanted = todo.pop()
            if wanted in defined or wanted not in known:
                continue
            defined.add(wanted)
            root.append(known[wanted])
            todo += [s.attrib.get("ID", "") for s in known[wanted].iter("SubTree")]
            added = True
        if added:
            tree.text = ET.tostring(root, encoding="unicode")


def main_tree(root: ET.Element) -> str | None:
    """``main_tree_to_execute``, the only tree, the one no other calls, or the first."""
    if "main_tree_to_execute" in root.attrib:
        return None  # the reader takes it
    ids = [bt.attrib["ID"] for bt in root.findall("BehaviorTree") if "ID" in bt.attrib]
    if len(root.findall("BehaviorTree")) <= 1:
        return None
    called = {s.attrib.get("ID") for s in root.iter("SubTree")}
    top = [i for i in ids if i not in called]
    return (top or ids)[0] if ids else None


def stub_model(doc: TreeDocument) -> str | None:
    """A TreeNodesModel of the tree's node IDs that are not Duet built-ins, or None."""
    known = set(effective_registry(None)) | set(COMPOSITES) | set(_BUILTIN_DECORATORS)
    known |= {"SubTree", "BehaviorTree", "root", "TreeNodesModel"}
    written: dict[str, str] = {}  # <Action ID="X">: the kind as written
    guessed: dict[str, str] = {}  # <X>: from its children, the most any use has
    ports: dict[str, set[str]] = {}
    rank = {"Action": 0, "Decorator": 1, "Control": 2}
    for bt in doc.root.findall("BehaviorTree"):
        for elem in bt.iter():
            if elem is bt or elem.tag in known:
                continue
            source_tag = getattr(elem, "source_tag", elem.tag)
            if source_tag in _KINDS:
                written[elem.tag] = source_tag
            kind = "Action" if len(elem) == 0 else "Decorator" if len(elem) == 1 else "Control"
            guessed[elem.tag] = max(guessed.get(elem.tag, "Action"), kind, key=rank.__getitem__)
            ports.setdefault(elem.tag, set()).update(
                k for k in elem.attrib if k not in ("name", "ID") and not k.startswith("_")
            )
    if not guessed:
        return None
    root = ET.Element("root", {"BTCPP_format": "4"})
    model = ET.SubElement(root, "TreeNodesModel")
    for tag in sorted(guessed):
        node = ET.SubElement(model, written.get(tag, guessed[tag]), {"ID": tag})
        for port in sorted(ports[tag]):
            ET.SubElement(node, "input_port", {"name": port})
    return ET.tostring(root, encoding="unicode")


_QUOTED = re.compile(r"'[^']*'|\"[^\"]*\"|\{[^{}]*\}")


def cause(message: str) -> str:
    """A problem's message with its names left out: one cause for many trees."""
    text = _QUOTED.sub("'…'", message)
    text = re.sub(r"\d+", "N", text)
    for cut in ("; expected", ": expected", ": did you mean", "; give"):
        if cut in text and not text.startswith("unknown node type"):
            text = text.split(cut)[0]
    if text.startswith("unknown node type"):
        tag = re.search(r"unknown node type '([^']*)'", message)
        return f"unknown node type '{tag.group(1) if tag else '?'}'"
    return text[:110]


def judge(tree: Tree, workdir: Path) -> list[str]:
    """The tree's rejection causes (empty: accepted)."""
    if tree.source.endswith(".xml"):
        # Validated where it is, so that its <include path> resolve.
        path = Path(tree.source)
    else:
        path = workdir / "tree.xml"
        path.write_text(tree.text, encoding="utf-8")
    try:
        doc = read_tree_document(path)
    except TreeFileError as exc:
        return sorted({cause(p.message) for p in exc.problems})
    registry = None
    model = stub_model(doc)
    if model is not None:
        model_file = workdir / "model.xml"
        model_file.write_text(model, encoding="utf-8")
        try:
            registry = {**py_trees.ports.get_ports_registry(), **model_stub_classes(model_file)}
        except TreeFileError as exc:
            return sorted({f"stub model: {cause(p.message)}" for p in exc.problems})
    problems = validate_tree(path, registry, main_tree_id=main_tree(doc.root), run_keys=None)
    return sorted({cause(p.message) for p in problems})


def measure(checkout: Path, listing: bool = False) -> dict[str, object]:
    """Validate the corpus; the figures."""
    trees = collect(checkout)
    add_sibling_subtrees(trees)
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="btcpp_corpus_") as tmp:
        os.chdir(checkout)
        try:
            for tree in trees:
                tree.verdict = judge(tree, Path(tmp))
        finally:
            os.chdir(cwd)
    loaded = [t for t in trees if not t.throws]
    throwing = [t for t in trees if t.throws]
    accepted = [t for t in loaded if not t.verdict]
    causes: Counter[str] = Counter(c for t in loaded for c in t.verdict)
    if listing:
        for t in trees:
            mark = "throws " if t.throws else ""
            print(f"{t.source}:{t.line}: {mark}{'ok' if not t.verdict else '; '.join(t.verdict)}")
    return {
        "trees": len(loaded),
        "accepted": len(accepted),
        "percent": round(100.0 * len(accepted) / max(len(loaded), 1), 1),
        "expected_to_throw": len(throwing),
        "expected_to_throw_rejected": sum(1 for t in throwing if t.verdict),
        "causes": dict(causes.most_common()),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("checkout", nargs="?", default=os.environ.get("BTCPP_DIR"))
    parser.add_argument("--json", action="store_true", help="end with the figures as JSON")
    parser.add_argument("--list", action="store_true", help="print each tree's verdict")
    args = parser.parse_args(argv)
    if not args.checkout:
        print("skipped: give a BehaviorTree.CPP 4.x checkout (PATH or $BTCPP_DIR)")
        if args.json:
            print(json.dumps({"skipped": True}))
        return 0
    checkout = Path(args.checkout).resolve()
    if not (checkout / "tests").is_dir() or not (checkout / "examples").is_dir():
        print(f"{args.checkout}: expected a BT.CPP checkout with examples/ and tests/")
        return 2
    figures = measure(checkout, listing=args.list)
    print(
        f"BT.CPP trees (examples/ and tests/, loaded by BT.CPP): {figures['trees']}, "
        f"accepted by Duet's validator: {figures['accepted']} ({figures['percent']} %)"
    )
    print(
        f"expected to throw in BT.CPP's tests (not counted): {figures['expected_to_throw']}, "
        f"rejected by Duet too: {figures['expected_to_throw_rejected']}"
    )
    causes = figures["causes"]
    assert isinstance(causes, dict)
    for text, count in causes.items():
        print(f"{count:4d}  {text}")
    if args.json:
        print(json.dumps(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
