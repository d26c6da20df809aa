"""Where a tree's blackboard keys are written and read, resolved as the parser resolves them.

py_trees' XML parser gives each ``<SubTree>`` instance a namespace (``/first_object/...``)
and a remapping table: a port of the subtree given ``{parent_key}`` reads the parent's key, a
port given a literal reads that constant, and any other ``{key}`` inside is the instance's
own ``<namespace>/key``. :func:`port_uses` follows the same rules over the XML (no tree is
built), so every ``{key}`` a leaf reads resolves to one absolute key, or to the literal a
subtree was given. :func:`dataflow_problems` then reports a read of a key that nothing
writes: such a tree validates and builds, then its leaf fails at its first tick with
``NoDataAvailable``.

Writes are: a leaf's output port given a ``{key}``; ``SetBlackboard output_key``; an
assignment (``key := ...``, ``key = ...``, ``key += ...``) in a BT.CPP script (a ``code``
attribute, or a ``_post``/``_onSuccess``/``_onFailure``/``_onHalted`` post-condition); and the
keys the run sets before the first tick (:data:`RUN_WRITES`). Scripts are read with a simple
regular expression, not parsed: enough to find what they assign.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Collection
from dataclasses import dataclass
from typing import Any, Literal

from py_trees.parsers.behaviour_tree_xml import DECORATOR_NODES
from py_trees.ports import PortsMixin

from planner.tree_bindings import Binding, resolve, subtree_bindings
from planner.tree_ports import (
    Registry,
    effective_registry,
    key_problem,
    registry_class,
    type_name,
)
from planner.tree_problems import TreeProblem
from planner.tree_reading import TreeDocument, describe, source_file, source_line
from planner.tree_syntax import ROOT_PREFIX

#: The blackboard key a run writes before the first tick: the task's object, which
#: :func:`experiment.episode.run_episode` seeds (a tree's ``{object}`` at its top level).
TASK_OBJECT_KEY = "/object"
#: Every key written before the first tick.
RUN_WRITES: frozenset[str] = frozenset({TASK_OBJECT_KEY})
#: Attributes holding BT.CPP script code that may assign keys.
SCRIPT_ATTRIBUTES = ("code", "_post", "_onSuccess", "_onFailure", "_onHalted")
#: ``name :=``, ``name =``, ``name +=`` ... but not ``==``, ``<=``, ``>=`` or ``!=``.
_DECORATORS = frozenset(cls.__name__ for cls in DECORATOR_NODES.values())
_ASSIGNMENT = re.compile(r"(@?[A-Za-z_]\w*)\s*(?::=|[-+*/]?=)(?!=)")


@dataclass(frozen=True)
class PortUse:
    """One attribute of one node instance that reads or writes the blackboard (or a literal).

    ``binding`` is the resolved key, or the literal (written on ``elem`` itself or on the
    ``<SubTree>`` that remapped it).
    """

    elem: ET.Element
    port: str
    direction: Literal["read", "write"]
    name: str  # the key as written, without braces (or the literal)
    binding: Binding


def _key_name(value: str) -> str | None:
    is_key, bad = key_problem(value)
    return value[1:-1] if is_key and not bad else None


def port_uses(doc: TreeDocument, registry: Registry | None = None) -> list[PortUse]:
    """Every blackboard read and write of the main tree, subtrees expanded (document order).

    Literal values of leaf input ports are listed too, as reads of a constant. The tree must
    be within :mod:`planner.tree_limits`' bounds (the expansion visits every instance).
    """
    reg = effective_registry(registry)
    trees = doc.behaviour_trees()
    if doc.main_tree_id not in trees:
        return []
    uses: list[PortUse] = []
    unnamed = 0
    Frame = tuple[ET.Element, str, dict[str, Binding], tuple[str, ...]]
    main = trees[doc.main_tree_id]
    # The main tree's own attributes are its defaults, as a subtree's are (the parser's
    # rule): ``{@key}``'s ``ROOT__key="{key}"`` among them binds the root's ``/key``.
    top = subtree_bindings(ET.Element("SubTree"), main, "/", {})
    stack: list[Frame] = [(main, "/", top, (doc.main_tree_id,))]
    while stack:
        elem, ns, remap, chain = stack.pop()
        children = list(elem)
        if elem.tag == "SubTree":
            bt_id = elem.attrib.get("ID", "")
            if bt_id not in trees or bt_id in chain:
                continue  # reported by the other checks
            bt = trees[bt_id]
            inner = subtree_bindings(elem, bt, ns, remap)
            label = elem.attrib.get("name")
            if label is None:
                unnamed += 1
                label = f"<unnamed {unnamed}>"  # the parser uses a fresh uuid
            stack.append((bt, ns.rstrip("/") + "/" + label, inner, (*chain, bt_id)))
            continue
        uses.extend(_node_uses(elem, ns, remap, reg))
        stack.extend((child, ns, remap, chain) for child in reversed(children))
    return uses


def _node_uses(
    elem: ET.Element, ns: str, remap: dict[str, Binding], reg: Registry
) -> list[PortUse]:
    uses: list[PortUse] = []
    if elem.tag == "BehaviorTree":
        return uses
    cls = registry_class(reg.get(elem.tag)) if elem.tag in reg else None
    ports = cls is not None and issubclass(cls, PortsMixin)
    inputs: set[str] = set()
    outputs: set[str] = set()
    if cls is not None and issubclass(cls, PortsMixin):
        inputs, outputs = set(cls.input_ports()), set(cls.output_ports())
    # A port that watches whether a key is written (WasEntryUpdated) reads no value: a key
    # nothing writes is its answer, not a crash.
    watched = set(getattr(cls, "WATCHED_PORTS", ()))
    # A node of no known type reads nothing we can tell (its tag is reported apart); a
    # py_trees decorator reads the keys given to its parameters.
    reads = ports or elem.tag in _DECORATORS
    # Pre/post-condition scripts parsed by the reader (planner.tree_reading) left the attributes.
    conditions = getattr(elem, "conditions", {})
    for attr, script in conditions.items():
        if attr in SCRIPT_ATTRIBUTES:
            for name in sorted(script.keys_written()):
                uses.append(PortUse(elem, attr, "write", name, resolve(name, ns, remap)))
    for attr, value in elem.attrib.items():
        if attr == "name":
            continue
        if attr in SCRIPT_ATTRIBUTES and attr not in conditions:
            for name in _ASSIGNMENT.findall(value):
                uses.append(PortUse(elem, attr, "write", name, resolve(name, ns, remap)))
            continue
        if elem.tag == "SetBlackboard" and attr == "output_key":
            name = _key_name(value) or value
            uses.append(PortUse(elem, attr, "write", name, resolve(name, ns, remap)))
            continue
        name = _key_name(value)
        if name is None:
            if attr in inputs:
                uses.append(PortUse(elem, attr, "read", value, Binding(None, value, elem)))
            continue
        direction: Literal["read", "write"] = "write" if attr in outputs else "read"
        if direction == "read" and (not reads or attr in watched):
            continue
        uses.append(PortUse(elem, attr, direction, name, resolve(name, ns, remap)))
    return uses


def dataflow_problems(
    doc: TreeDocument,
    registry: Registry | None = None,
    run_keys: Collection[str] = RUN_WRITES,
    uses: list[PortUse] | None = None,
) -> list[TreeProblem]:
    """One problem per node port reading a ``{key}`` that nothing writes.

    A key counts as written if any node instance of the tree writes it (an output port,
    ``SetBlackboard``, a script assignment), wherever in the tree, or the run sets it before
    the first tick (``run_keys``, by default :data:`RUN_WRITES`). ``uses``: the document's
    :func:`port_uses`, where the caller has them already.
    """
    uses = port_uses(doc, registry) if uses is None else uses
    written = set(run_keys) | {
        u.binding.key for u in uses if u.direction == "write" and u.binding.key
    }
    problems: list[TreeProblem] = []
    for use in uses:
        key = use.binding.key
        if use.direction != "read" or key is None or key in written:
            continue
        seeded = ", ".join("{" + k.lstrip("/") + "}" for k in sorted(run_keys)) or "none"
        name = _as_written(use.name)
        problem = TreeProblem(
            source_file(use.elem, doc.file),
            source_line(use.elem),
            describe(use.elem),
            f"port '{use.port}' reads {{{name}}} (blackboard key {key}), which nothing "
            "writes: expected a node's output port, a SetBlackboard or a script to write it, "
            f"or a key the run sets before the first tick ({seeded} at the top level)",
        )
        if problem not in problems:
            problems.append(problem)
    return problems


def _as_written(name: str) -> str:
    """A key's name as the file writes it: a ``{@key}`` is passed down under another name
    (:mod:`planner.tree_syntax`)."""
    return "@" + name[len(ROOT_PREFIX) :] if name.startswith(ROOT_PREFIX) else name


def _port_type(use: PortUse, reg: Registry) -> Any:
    """The declared type of the leaf port ``use`` is, or None: a node without typed ports
    (``SetBlackboard``, a script, a decorator's parameter) or one typed ``Any``/``object``."""
    cls = registry_class(reg.get(use.elem.tag)) if use.elem.tag in reg else None
    if cls is None or not issubclass(cls, PortsMixin):
        return None
    if use.port in getattr(cls, "UNTYPED_PORTS", ()):
        return None  # a model's port of no type (planner.model_stubs)
    table = cls.output_ports() if use.direction == "write" else cls.input_ports()
    info = table.get(use.port)
    data_type = getattr(info, "data_type", None)
    return None if data_type in (None, Any, object) else data_type


def type_problems(
    doc: TreeDocument, registry: Registry | None = None, uses: list[PortUse] | None = None
) -> list[TreeProblem]:
    """One problem per leaf port given a ``{key}`` whose entry a port of another declared
    type made first, as BehaviorTree.CPP refuses the tree when it builds it ("the port [key]
    was initially created with type [double] and, later type [std::string]"): the entry's
    type is that of the first port that uses it, in document order; an entry a ``str`` port
    or a port of no declared type made takes any (BT.CPP converts from strings, and checks
    no type on an entry an untyped port made). Such a tree had validated, then
    failed at the reader's first tick. ``uses``: as for :func:`dataflow_problems`."""
    reg = effective_registry(registry)
    # Per key, the type of the port that used it first: None, a port of no declared type
    # (SetBlackboard's output_key, a script), after which BT.CPP checks no type on it.
    made: dict[str, tuple[Any, PortUse]] = {}
    problems: list[TreeProblem] = []
    for use in port_uses(doc, registry) if uses is None else uses:
        key = use.binding.key
        if key is None:
            continue
        data_type = _port_type(use, reg)
        kind, maker = made.setdefault(key, (data_type, use))
        if data_type is None or kind is None or kind == data_type or kind is str:
            continue
        problem = TreeProblem(
            source_file(use.elem, doc.file),
            source_line(use.elem),
            describe(use.elem),
            f"port '{use.port}' ({type_name(data_type)}) uses {{{_as_written(use.name)}}} "
            f"(blackboard key {key}), which {describe(maker.elem)} port '{maker.port}' made "
            f"{type_name(kind)}: expected ports of one type on a key",
        )
        if problem not in problems:
            problems.append(problem)
    return problems


__all__ = [
    "RUN_WRITES",
    "TASK_OBJECT_KEY",
    "Binding",
    "PortUse",
    "dataflow_problems",
    "port_uses",
    "type_problems",
]
