"""Checking a read tree document: every problem the py_trees parser (or a first tick) would
trip over, each with file, line, node and what was expected."""

from __future__ import annotations

import difflib
import xml.etree.ElementTree as ET
from collections.abc import Collection
from typing import Any

import py_trees
from py_trees.parsers.behaviour_tree_xml import DECORATOR_NODES
from py_trees.ports import PortInformation, PortsMixin

from planner.bt_controls import CHILD_COUNTS
from planner.bt_switch import SWITCH_CHILD_COUNTS
from planner.tree_dataflow import dataflow_problems, port_uses, type_problems
from planner.tree_limits import subtree_cycle_problems, tree_size_problems
from planner.tree_ports import (
    Registry,
    constructor_params,
    effective_registry,
    key_problem,
    literal_problem,
    one_of,
    registry_class,
    type_name,
)
from planner.tree_problems import TreeProblem
from planner.tree_reading import TreeDocument, describe, source_file, source_line
from planner.tree_syntax import script_keys

COMPOSITES = ("Sequence", "Selector", "Parallel")
#: Per translated tag, py_trees' parameter -> the BT.CPP attribute the file wrote
#: (:mod:`planner.tree_reading` renames them): what a problem names.
BT_SPELLINGS: dict[str, dict[str, str]] = {
    "Retry": {"num_failures": "num_attempts"},
    "Repeat": {"num_success": "num_cycles"},
    "Timeout": {"duration": "msec"},
}
#: Parallel policies the py_trees parser can build (``success_on_selected`` needs a child list).
PARALLEL_POLICIES = ("success_on_all", "success_on_one")
_BUILTIN_DECORATORS: dict[str, type[py_trees.decorators.Decorator]] = {
    cls.__name__: cls for cls in DECORATOR_NODES.values()
}


class _Checker:
    """Walks a translated document and collects problems."""

    def __init__(self, doc: TreeDocument, registry: Registry | None) -> None:
        self.doc = doc
        self.registry = effective_registry(registry)
        self.trees = doc.behaviour_trees()
        self.problems: list[TreeProblem] = []
        self._subtree_ports: dict[str, set[str]] = {}

    def add(self, elem: ET.Element, message: str) -> None:
        problem = TreeProblem(
            source_file(elem, self.doc.file), source_line(elem), describe(elem), message
        )
        if problem not in self.problems:
            self.problems.append(problem)

    def where(self, elem: ET.Element, seen_from: ET.Element) -> str:
        """``line N``, or ``file:N`` when ``elem`` is in another file than ``seen_from``."""
        file = source_file(elem, self.doc.file)
        if file == source_file(seen_from, self.doc.file):
            return f"line {source_line(elem)}"
        return f"{file}:{source_line(elem)}"

    # -- definitions --------------------------------------------------------------------
    def run(self) -> list[TreeProblem]:
        seen: dict[str, ET.Element] = {}
        for bt in self.doc.root.findall("BehaviorTree"):
            bt_id = bt.attrib.get("ID")
            if not bt_id:
                self.add(bt, 'expected an ID="..." attribute')
            elif bt_id in seen:
                self.add(
                    bt,
                    f"duplicate BehaviorTree ID '{bt_id}' (first at {self.where(seen[bt_id], bt)})",
                )
            else:
                seen[bt_id] = bt
            if len(bt) != 1:
                self.add(bt, f"expected exactly one child (the tree's root node), found {len(bt)}")
            for child in bt:
                self.check(child)
        for other in self.doc.root:
            if other.tag not in ("BehaviorTree", "TreeNodesModel"):
                self.add(other, "unexpected element under <root>; expected <BehaviorTree ID=...>")
        if self.doc.main_tree_id in self.trees:
            names: dict[str, ET.Element] = {}
            self.instantiate(
                self.trees[self.doc.main_tree_id], "", [self.doc.main_tree_id], names, None
            )
        return self.problems

    def check(self, elem: ET.Element) -> None:
        tag = elem.tag
        if tag in self.registry:
            self.check_ports_node(elem, self.registry[tag])
        elif tag in COMPOSITES:
            self.check_composite(elem)
        elif tag in _BUILTIN_DECORATORS:
            self.check_params(elem, _BUILTIN_DECORATORS[tag], allow_keys=True)
            self.check_children(elem, 1, 1, "decorator")
        elif tag == "SubTree":
            self.check_subtree(elem)
        else:
            self.unknown_tag(elem)
            return
        self.check_name(elem)
        for child in elem:
            self.check(child)

    def unknown_tag(self, elem: ET.Element) -> None:
        leaves = sorted(
            t for t, e in self.registry.items() if (c := registry_class(e)) and not _is_parent(c)
        )
        known = leaves + list(COMPOSITES) + ["Fallback", "SubTree"] + sorted(_BUILTIN_DECORATORS)
        guesses = difflib.get_close_matches(elem.tag, known, n=3)
        hint = f"did you mean {' or '.join(repr(g) for g in guesses)}? " if guesses else ""
        self.add(
            elem,
            f"unknown node type '{elem.tag}': {hint}register it with --leaves my_leaves.py "
            f"(a module defining a planner.leaves.WorldLeaf subclass named {elem.tag}), or an "
            "installed package's duet.leaves entry point; expected a registered leaf "
            f"({one_of(leaves)}), a control node (Sequence, Fallback/Selector, Parallel, "
            "a decorator) or <SubTree ID=...>",
        )

    def check_name(self, elem: ET.Element) -> None:
        name = elem.attrib.get("name")
        if name is not None and "." in name:
            self.add(elem, f"name '{name}': expected no '.' (py_trees joins parent names with '.')")

    def check_children(self, elem: ET.Element, low: int, high: int | None, what: str) -> None:
        n = len(elem)
        if high is not None and low == high and n != low:
            self.add(elem, f"a {what} takes exactly {low} child, found {n}")
        elif n < low:
            self.add(elem, f"a {what} needs at least {low} child, found {n}")
        elif high is not None and n > high:
            self.add(elem, f"a {what} takes at most {high} children, found {n}")

    def check_composite(self, elem: ET.Element) -> None:
        allowed = {"name", "memory"} if elem.tag != "Parallel" else {"name", "policy"}
        for key, value in elem.attrib.items():
            if key not in allowed:
                self.add(elem, f"unknown attribute '{key}'; expected one of {one_of(allowed)}")
            elif key == "memory" and value.strip().lower() not in ("true", "false"):
                self.add(elem, f"attribute 'memory': expected true or false, got '{value}'")
            elif key == "policy" and value not in PARALLEL_POLICIES:
                self.add(
                    elem,
                    f"attribute 'policy': expected one of {', '.join(PARALLEL_POLICIES)}, "
                    f"got '{value}'",
                )
        self.check_children(elem, 1, None, "control node")

    def check_params(self, elem: ET.Element, entry: Any, allow_keys: bool) -> set[str]:
        """Check constructor-argument attributes; return the names accepted."""
        params = constructor_params(entry)
        # The reader gave BT.CPP's spellings py_trees' names: say them as the file has them.
        spelt = BT_SPELLINGS.get(elem.tag, {})
        for pname, param in params.items():
            if param.required and pname not in elem.attrib:
                self.add(elem, f"missing required attribute '{spelt.get(pname, pname)}'")
        for key, value in elem.attrib.items():
            if key not in params:
                continue
            is_key, bad = key_problem(value)
            if bad:
                self.add(elem, f"attribute '{spelt.get(key, key)}': {bad}")
            elif is_key and not allow_keys:
                self.add(
                    elem,
                    f"attribute '{key}' is a constructor argument; expected a literal, got the "
                    f"blackboard key '{value}'",
                )
            elif not is_key:
                bad = literal_problem(value, params[key].annotation, key)
                if bad:
                    self.add(elem, f"attribute '{spelt.get(key, key)}': {bad}")
        unknown = [k for k in elem.attrib if k not in params and k != "name"]
        if registry_class(entry) in _BUILTIN_DECORATORS.values():
            names = {spelt.get(p, p) for p in params}
            for key in unknown:
                self.add(elem, f"unknown attribute '{key}'; expected one of {one_of(names)}")
        return set(params)

    def check_ports_node(self, elem: ET.Element, entry: Any) -> None:
        cls = registry_class(entry)
        if cls is None or not issubclass(cls, PortsMixin):
            self.add(elem, f"registry entry for '{elem.tag}' is not a ports-enabled class")
            return
        inputs: dict[str, PortInformation] = cls.input_ports()
        outputs: dict[str, PortInformation] = cls.output_ports()
        params = self.check_params(elem, entry, allow_keys=False)
        accepted = set(inputs) | set(outputs) | params
        for key, value in elem.attrib.items():
            if key == "name" or key in params:
                continue
            if key not in inputs and key not in outputs:
                spelt = BT_SPELLINGS.get(elem.tag, {})
                names = {spelt.get(a, a) for a in accepted}
                self.add(elem, f"unknown port '{key}'; expected one of {one_of(names)}")
                continue
            is_key, bad = key_problem(value)
            if bad:
                self.add(elem, f"port '{key}': {bad}")
            elif key in outputs and not is_key:
                self.add(
                    elem,
                    f"output port '{key}': expected a blackboard key such as {{{key}}}, got the "
                    f"literal '{value}'",
                )
            elif key in inputs and not is_key:
                bad = literal_problem(value, inputs[key].data_type, key)
                own = getattr(cls, "port_literal_problem", None)
                if not bad and callable(own):  # a leaf's own check of what a literal says
                    bad = own(key, value)
                if bad:
                    self.add(elem, f"port '{key}': {bad}")
        for port, info in inputs.items():
            if info.required and not info.has_default and port not in elem.attrib:
                self.add(
                    elem,
                    f"missing required input port '{port}' ({type_name(info.data_type)}); "
                    f"give a literal or a blackboard key such as {{{port}}}",
                )
        for port in getattr(cls, "REQUIRED_OUTPUTS", ()):
            if port not in elem.attrib:
                # An output port is required only where the node says so (BT.CPP's
                # SetBlackboard throws at its first tick without its output_key).
                self.add(
                    elem,
                    f"missing required output port '{port}'; give the blackboard key it "
                    f"writes, such as {{{port}}}",
                )
        if issubclass(cls, py_trees.decorators.Decorator):
            self.check_children(elem, 1, 1, "decorator")
        elif issubclass(cls, py_trees.composites.Composite):
            low, high = {**CHILD_COUNTS, **SWITCH_CHILD_COUNTS}.get(elem.tag, (1, None))
            self.check_children(elem, low, high, f"{elem.tag} node")
        elif len(elem):
            self.add(elem, f"a leaf takes no children, found {len(elem)}")

    def subtree_ports(self, bt_id: str) -> set[str]:
        """Names a ``<SubTree>`` may remap: the tree's own attributes, the ports its
        ``<TreeNodesModel>`` entry declares, and the keys its nodes and scripts use."""
        if bt_id in self._subtree_ports:
            return self._subtree_ports[bt_id]
        bt = self.trees[bt_id]
        ports = {k for k in bt.attrib if k not in ("ID", "name")}
        ports |= getattr(bt, "model_ports", set())
        self._subtree_ports[bt_id] = ports  # guards recursion through cycles
        for elem in bt.iter():
            if elem is bt:
                continue
            for value in elem.attrib.values():
                is_key, bad = key_problem(value)
                if is_key and not bad:
                    ports.add(value[1:-1])
            ports |= script_keys(elem)
        return ports

    def check_subtree(self, elem: ET.Element) -> None:
        bt_id = elem.attrib.get("ID")
        if not bt_id:
            self.add(elem, 'expected an ID="..." attribute naming a <BehaviorTree>')
            return
        if bt_id not in self.trees:
            guess = difflib.get_close_matches(bt_id, list(self.trees), n=1)
            hint = f"did you mean '{guess[0]}'? " if guess else ""
            self.add(
                elem,
                f"unknown subtree '{bt_id}'; {hint}expected one of the <BehaviorTree> IDs: "
                f"{one_of(set(self.trees))}",
            )
            return
        ports = self.subtree_ports(bt_id)
        for key, value in elem.attrib.items():
            if key in ("ID", "name"):
                continue
            if key not in ports:
                self.add(
                    elem,
                    f"unknown port '{key}' of subtree '{bt_id}'; expected one of {one_of(ports)}",
                )
                continue
            is_key, bad = key_problem(value)
            if bad:
                self.add(elem, f"port '{key}': {bad}")
            elif not is_key:
                self.check_subtree_literal(elem, bt_id, key, value)
        if len(elem):
            self.add(elem, f"a <SubTree> takes no children, found {len(elem)}")

    def check_subtree_literal(self, elem: ET.Element, bt_id: str, port: str, value: str) -> None:
        """Check a literal given to a subtree port against the leaf input ports using it."""
        for inner in self.trees[bt_id].iter():
            cls = registry_class(self.registry.get(inner.tag))
            if cls is None or not issubclass(cls, PortsMixin):
                continue
            for name, info in cls.input_ports().items():
                if inner.attrib.get(name) != f"{{{port}}}":
                    continue
                bad = literal_problem(value, info.data_type, name)
                if bad:
                    self.add(
                        elem,
                        f"port '{port}' feeds {describe(inner)} port '{name}' (line "
                        f"{source_line(inner)}): {bad}",
                    )

    # -- instantiation: names as the parser makes them, subtree cycles ------------------
    def instantiate(
        self,
        elem: ET.Element,
        prefix: str,
        stack: list[str],
        names: dict[str, ET.Element],
        via: ET.Element | None,
    ) -> None:
        tag = elem.tag
        if tag == "BehaviorTree":
            for child in elem:
                self.instantiate(child, prefix, stack, names, via)
            return
        if tag == "SubTree":
            bt_id = elem.attrib.get("ID", "")
            if bt_id not in self.trees:
                return
            if bt_id in stack:
                return  # a cycle: planner.tree_limits reports it, named or not
            name = elem.attrib.get("name")
            if name is None:
                return  # the parser names it with a fresh uuid: nothing inside can clash
            inner = f"{prefix}.{name}" if prefix else name
            self.instantiate(self.trees[bt_id], inner, [*stack, bt_id], names, elem)
            return
        explicit = elem.attrib.get("name")
        if explicit:
            full = f"{prefix}.{explicit}" if prefix else explicit
            if full in names:
                first = names[full]
                culprit = via if via is not None else elem
                self.add(
                    culprit,
                    f"duplicate node name '{full}' (also at {self.where(first, culprit)}); "
                    "py_trees needs unique names: rename one or name its parent",
                )
            names.setdefault(full, elem)
            child_prefix = full
        else:
            child_prefix = prefix
        for child in elem:
            self.instantiate(child, child_prefix, stack, names, via)


def _is_parent(cls: type) -> bool:
    return issubclass(cls, (py_trees.decorators.Decorator, py_trees.composites.Composite))


def check_tree_document(
    doc: TreeDocument,
    registry: Registry | None = None,
    *,
    run_keys: Collection[str] | None = None,
) -> list[TreeProblem]:
    """Return every problem in a read document (reading problems first).

    Parameters
    ----------
    doc : TreeDocument
        From :func:`read_tree_document`.
    registry : mapping tag -> class, optional
        As for :func:`effective_registry`.
    run_keys : collection of str, optional
        For a tree Duet will run: the blackboard keys the run sets before the first tick
        (:data:`planner.tree_dataflow.RUN_WRITES`); a port reading a key that neither they nor
        any node writes is then a problem. Without it (a BT.CPP tree whose host may set any
        key, a conformance test that sets them) reads are not checked.
    """
    # The size limits first, and alone when they fail: the checks below walk the tree (and
    # expand its subtrees) recursively, which only a bounded tree allows.
    limits = tree_size_problems(doc)
    if limits:
        return [*doc.problems, *limits]
    uses = port_uses(doc, registry)  # walked once for both checks of the blackboard
    return [
        *doc.problems,
        *_Checker(doc, registry).run(),
        *subtree_cycle_problems(doc),
        *type_problems(doc, registry, uses),
        *(dataflow_problems(doc, registry, run_keys, uses) if run_keys is not None else ()),
    ]
