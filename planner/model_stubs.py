"""Stub nodes from a Groot2 ``TreeNodesModel``, so a tree written for another robot can be checked.

``app.py validate --nodes MODEL.xml TREE.xml`` reads the model (a file as ``app.py nodes`` or
Groot2 writes it: ``<root><TreeNodesModel><Action ID=...><input_port name=... type=...
default=.../>...``) and registers one stub per ``Action``, ``Condition``, ``Decorator`` and
``Control`` it declares. A stub has the model's ports and nothing else: an action or condition
succeeds, a decorator passes its child's status on, a control is a sequence with memory. Ports
are optional; their type is a string unless the model names one of BT.CPP's or Python's
numbers, booleans or strings (``int``, ``double``, ``bool``, ``std::string`` ...), and a default
given in the model is converted to that type. ``SubTree`` entries (a subtree's ports) declare no
node and are skipped.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

from planner.tree_problems import TreeFileError, TreeProblem
from planner.tree_reading import _parse_xml, read_tree_bytes, source_line

__all__ = ["model_stub_classes"]

#: Model type names -> Python types; any other type is carried as a string.
_TYPES: dict[str, type] = {
    **dict.fromkeys(("int", "int8_t", "int16_t", "int32_t", "int64_t", "long"), int),
    **dict.fromkeys(("uint8_t", "uint16_t", "uint32_t", "uint64_t", "unsigned", "size_t"), int),
    **dict.fromkeys(("double", "float"), float),
    **dict.fromkeys(("bool",), bool),
    **dict.fromkeys(("std::string", "string", "str"), str),
}
#: A port of no type, or of one BT.CPP does not hold to (``AnyTypeAllowed``), or of a C++
#: type Python has none for: carried as a string, and any type may share its key
#: (:func:`planner.tree_dataflow.type_problems`).
_ANY_TYPE = "BT::AnyTypeAllowed"
_PORT_TAGS = {"input_port": "in", "inout_port": "in", "output_port": "out"}


class _StubLeaf(py_trees.behaviour.Behaviour):
    def update(self) -> Status:
        self.feedback_message = "stub from a TreeNodesModel: succeeds"
        return Status.SUCCESS


class _StubDecorator(py_trees.decorators.Decorator):
    def update(self) -> Status:
        return self.decorated.status


def _convert(text: str, data_type: type) -> Any:
    if data_type is bool:
        if text.strip().lower() not in ("true", "false", "1", "0"):
            raise ValueError(f"expected true or false, got {text!r}")
        return text.strip().lower() in ("true", "1")
    return data_type(text.strip()) if data_type is not str else text


def model_stub_classes(path: str | os.PathLike[str]) -> dict[str, type]:
    """The stub classes a TreeNodesModel file declares, by ID (not registered globally).

    Raises
    ------
    TreeFileError
        Naming file and line: the file cannot be read or is not XML, it holds no
        ``<TreeNodesModel>``, a node has no ``ID``, or a port has no name or a default that
        does not convert to its type.
    """
    source = os.fspath(path)
    try:
        data = read_tree_bytes(Path(source))
    except OSError as exc:
        raise TreeFileError(
            [TreeProblem(source, None, "", f"--nodes: cannot read: {exc.strerror or exc}")]
        ) from None
    root = _parse_xml(data, source)
    models = [root] if root.tag == "TreeNodesModel" else root.findall("TreeNodesModel")
    if not models:
        raise TreeFileError(
            [TreeProblem(source, source_line(root), "", "--nodes: expected a <TreeNodesModel>")]
        )
    problems: list[TreeProblem] = []
    classes: dict[str, type] = {}
    for model in models:
        for elem in model:
            if elem.tag == "SubTree":
                continue
            where = f'<{elem.tag} ID="{elem.attrib.get("ID", "")}">'

            def problem(message: str, at: ET.Element = elem, where: str = where) -> None:
                problems.append(TreeProblem(source, source_line(at), where, message))

            if elem.tag not in ("Action", "Condition", "Decorator", "Control"):
                problem("expected Action, Condition, Decorator, Control or SubTree")
                continue
            node_id = elem.attrib.get("ID", "").strip()
            if not node_id:
                problem('expected an ID="..." attribute naming the node')
                continue
            ports: dict[str, dict[str, PortInformation]] = {"in": {}, "out": {}}
            untyped: set[str] = set()
            for port in elem:
                if port.tag not in _PORT_TAGS:
                    continue  # MetadataFields and the like
                name = port.attrib.get("name", "").strip()
                if not name:
                    problem(f'<{port.tag}>: expected a name="..." attribute', port)
                    continue
                type_text = port.attrib.get("type", "").strip()
                data_type = _TYPES.get(type_text, str)
                if type_text == _ANY_TYPE or type_text not in _TYPES:
                    untyped.add(name)
                default = None
                if "default" in port.attrib:
                    try:
                        default = _convert(port.attrib["default"], data_type)
                    except ValueError as exc:
                        problem(f"port '{name}': default: {exc}", port)
                        continue
                ports[_PORT_TAGS[port.tag]][name] = PortInformation(
                    data_type=data_type,
                    required=False,
                    description=(port.text or "").strip(),
                    default_value=default,
                )
            classes[node_id] = _stub_class(node_id, elem.tag, ports, frozenset(untyped))
    if problems:
        raise TreeFileError(problems)
    return classes


def _stub_class(
    node_id: str,
    kind: str,
    ports: dict[str, dict[str, PortInformation]],
    untyped: frozenset[str] = frozenset(),
) -> type[PortsMixin]:
    base: type = {
        "Decorator": _StubDecorator,
        "Control": py_trees.composites.Sequence,
    }.get(kind, _StubLeaf)
    namespace: dict[str, Any] = {
        "INPUT_PORTS": ports["in"],
        "OUTPUT_PORTS": {k: v for k, v in ports["out"].items() if k not in ports["in"]},
        "NODE_TYPE": "Condition" if kind == "Condition" else "Action",
        "UNTYPED_PORTS": untyped,
        "__doc__": f"Stub of the {kind} '{node_id}' from a TreeNodesModel.",
        "__module__": __name__,
    }
    if kind == "Control":

        def __init__(self: Any, name: str, children: Any = None, **kwargs: Any) -> None:
            super(cls, self).__init__(name=name, memory=True, children=children, **kwargs)

        namespace["__init__"] = __init__
    cls: type[PortsMixin] = type(f"Stub_{node_id}", (PortsMixin, base), namespace, register=False)
    return cls
