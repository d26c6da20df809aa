"""Describe our leaves as a Groot2 ``TreeNodesModel`` so trees can be authored in Groot2.

The document lists, for every registered ports-enabled leaf, its kind (``Action`` or
``Condition``, from the class attribute ``NODE_TYPE``), its ports with type, default and
description, and the first line of its docstring::

    <root BTCPP_format="4">
      <TreeNodesModel>
        <Action ID="Grasp">
          <input_port name="force_n" type="float" default="15.0">squeeze per palm, N</input_port>
          <output_port name="holding" type="bool"/>
          <MetadataFields>
            <Metadata description="Squeeze the object between the palms."/>
          </MetadataFields>
        </Action>
      </TreeNodesModel>
    </root>
"""

from __future__ import annotations

import enum
import inspect
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from typing import Any

import py_trees
from py_trees.ports import PortInformation, PortsMixin, get_ports_registry

from planner.tree_ports import Registry, builtin_nodes, registry_class, type_name
from planner.tree_problems import TreeFileError, TreeProblem
from planner.tree_reading import TRANSLATED_TAGS, read_tree_document

__all__ = ["add_node_model", "embed_nodes_model", "leaf_kind", "nodes_model_xml", "summary_line"]

NODE_KINDS = ("Action", "Condition")


def leaf_kind(cls: type) -> str:
    """Return the Groot2 element for a ports-enabled class.

    ``Decorator`` and ``Control`` for py_trees decorators and composites, otherwise the class's
    ``NODE_TYPE`` (``Action`` or ``Condition``; ``Action`` when absent).

    Raises
    ------
    ValueError
        If ``NODE_TYPE`` is something other than ``Action`` or ``Condition``.
    """
    if issubclass(cls, py_trees.decorators.Decorator):
        return "Decorator"
    if issubclass(cls, py_trees.composites.Composite):
        return "Control"
    kind = getattr(cls, "NODE_TYPE", "Action")
    if kind not in NODE_KINDS:
        raise ValueError(
            f"{cls.__module__}.{cls.__qualname__}.NODE_TYPE: expected one of "
            f"{', '.join(NODE_KINDS)}, got {kind!r}"
        )
    return str(kind)


#: A reST role such as :attr:`~planner.move_result.MoveResult.rested_z`, its target kept.
_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")
#: Where a docstring's first sentence ends: a full stop before a space and a capital.
_SENTENCE_END = re.compile(r"(?<=[.!?])\s+(?=[A-Z])")


def summary_line(cls: type) -> str:
    """The first sentence of the class's own docstring, its wrapped lines joined and its
    reST markup dropped (``:attr:`~a.b.c``` reads ``c``, a literal is quoted); '' when it has
    none."""
    doc = inspect.getdoc(cls) if "__doc__" in vars(cls) and cls.__doc__ else ""
    paragraph = doc.strip().split("\n\n", 1)[0] if doc else ""
    text = " ".join(line.strip() for line in paragraph.splitlines() if line.strip())
    text = _ROLE.sub(lambda m: m.group(1).rsplit(".", 1)[-1], text).replace("``", "'")
    return _SENTENCE_END.split(text, 1)[0]


def _format_default(value: Any) -> str:
    """A default as an XML attribute the parser converts back (lists ``;``-separated)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, list | tuple):
        return ";".join(_format_default(v) for v in value)
    return str(value)


def _port_element(parent: ET.Element, tag: str, name: str, info: PortInformation) -> None:
    attrib = {"name": name, "type": type_name(info.data_type)}
    if info.has_default:
        attrib["default"] = _format_default(info.default_value)
    port = ET.SubElement(parent, tag, attrib)
    if info.description:
        port.text = info.description


def _selected(
    registry: Registry, include_all: bool, packages: Iterable[str]
) -> list[tuple[str, type[PortsMixin]]]:
    prefixes = tuple(packages)
    chosen: list[tuple[str, type[PortsMixin]]] = []
    for tag, entry in registry.items():
        cls = registry_class(entry)
        if cls is None or not issubclass(cls, PortsMixin):
            continue
        module = cls.__module__
        if include_all or any(module == p or module.startswith(p + ".") for p in prefixes):
            chosen.append((tag, cls))
    return sorted(chosen, key=lambda item: item[0])


def add_node_model(model: ET.Element, tag: str, cls: type[PortsMixin]) -> ET.Element:
    """Append the model of one ports-enabled class, registered as ``tag``, to a
    ``<TreeNodesModel>`` element: its kind, ports and description; the new element."""
    node = ET.SubElement(model, leaf_kind(cls), {"ID": tag})
    for name, info in cls.input_ports().items():
        _port_element(node, "input_port", name, info)
    for name, info in cls.output_ports().items():
        _port_element(node, "output_port", name, info)
    description = summary_line(cls)
    if description:
        fields = ET.SubElement(node, "MetadataFields")
        ET.SubElement(fields, "Metadata", {"description": description})
    return node


def nodes_model_xml(
    registry: Registry | None = None,
    *,
    include_all: bool = False,
    packages: Iterable[str] = ("planner",),
) -> str:
    """Return a Groot2-compatible ``TreeNodesModel`` document, sorted by tag.

    Parameters
    ----------
    registry : mapping tag -> class or functools.partial, optional
        Default: py_trees' global ports registry (every imported ports-enabled behaviour).
    include_all : bool
        List every registered class, not only those defined in ``packages``.
    packages : iterable of str
        Module prefixes of the classes to list (default: this project's ``planner``).

    Returns
    -------
    str
        Indented XML text ending in a newline.
    """
    reg = get_ports_registry() if registry is None else registry
    root = ET.Element("root", {"BTCPP_format": "4"})
    model = ET.SubElement(root, "TreeNodesModel")
    for tag, cls in _selected(reg, include_all, packages):
        add_node_model(model, tag, cls)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


#: An embedded model, with the whitespace before it, in a tree file's text.
_EMBEDDED = re.compile(r"\s*<TreeNodesModel\s*/>|\s*<TreeNodesModel>.*?</TreeNodesModel>", re.S)


def embed_nodes_model(
    path: str | os.PathLike[str],
    registry: Registry | None = None,
    *,
    packages: Iterable[str] = ("planner",),
) -> str:
    """The text of a tree file with its ``<TreeNodesModel>`` made anew: the models, as
    :func:`nodes_model_xml` writes them, of the leaves its trees use (those defined in
    ``packages``), so Groot2 opens it with its nodes' kinds and ports.

    The rest of the text (comments, layout) is kept; a model already there is replaced, else
    the new one goes last in ``<root>``. Of the model there, what the leaves' models do not
    say is kept: its ``<SubTree>`` entries (their ports and defaults are the trees' meaning)
    and those of nodes the trees use that no registered leaf models (another robot's, for
    stubs). The file itself is not written.

    Raises
    ------
    planner.tree_problems.TreeFileError
        If the file cannot be read, or is not XML.
    """
    doc = read_tree_document(path, registry)
    used = {
        elem.tag for bt in doc.root.findall("BehaviorTree") for elem in bt.iter() if elem is not bt
    }
    reg = get_ports_registry() if registry is None else registry
    model = ET.Element("TreeNodesModel")
    made = set()
    for tag, cls in _selected(reg, False, packages):
        if tag in used:
            add_node_model(model, tag, cls)
            made.add(tag)
    kept = set()
    for old in doc.root.findall("TreeNodesModel"):
        for entry in old:
            entry_id = entry.attrib.get("ID")
            if entry.tag == "SubTree" or (entry_id in used and entry_id not in made):
                entry.tail = None
                model.append(entry)
                kept.add(entry_id)
    # A leaf nothing models would open in Groot2 as an unknown node, its ports lost.
    unknown = sorted(
        tag
        for tag in used - made - kept
        if tag != "SubTree"
        and tag.lower() not in TRANSLATED_TAGS
        and tag not in builtin_nodes()
        and registry_class(reg[tag] if tag in reg else None) is None
    )
    if unknown:
        raise TreeFileError(
            [
                TreeProblem(
                    str(path),
                    None,
                    "",
                    f"expected leaves Duet or a --leaves file models, got {', '.join(unknown)} "
                    "(register them with --leaves FILE.py|MODULE; nothing was written)",
                )
            ]
        )
    ET.indent(model, level=1)
    block = "\n\n  " + ET.tostring(model, encoding="unicode")
    with open(path, encoding="utf-8") as handle:
        text = _EMBEDDED.sub("", handle.read())
    end = text.rindex("</root>")
    return text[:end].rstrip() + block + "\n" + text[end:]
