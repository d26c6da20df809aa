"""Draw a behaviour tree as text, Graphviz dot source, or SVG (no Graphviz needed).

``render_tree(root, "svg")`` lays the tree out itself: each subtree gets a horizontal span wide
enough for its children side by side, a parent sits centred over its children, one layer per
depth. Boxes are coloured and shaped per kind (Sequence, Selector, Parallel, decorator, Action,
Condition) and show the node's short name and its type.
"""

from __future__ import annotations

import os
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import py_trees
from py_trees.common import Status
from py_trees.ports_utils import get_base_name

from planner.atomic_file import atomic_open
from planner.decorators import SimTimeout
from planner.loader import TreeFileError, load_document
from planner.runner import readable, unnamed
from planner.tree_reading import read_tree_document, source_file

__all__ = ["FORMATS", "node_kind", "node_type", "render_cli", "render_tree", "short_name"]

FORMATS = ("ascii", "unicode", "dot", "svg")

#: Fill, stroke, corner radius (None: pill) and glyph per kind.
_STYLE: dict[str, tuple[str, str, float | None, str]] = {
    "Sequence": ("#fde2c4", "#c26a00", 2.0, "→"),
    "Selector": ("#cfe3fb", "#1f5fa8", 2.0, "?"),
    "Parallel": ("#e3d4f5", "#6b3fa0", 2.0, "⇉"),
    "Decorator": ("#eeeeee", "#555555", 10.0, "◇"),
    "Action": ("#d8f0d2", "#2e7d32", 8.0, ""),
    "Condition": ("#fff5c2", "#a08900", None, ""),
}
_STATUS_STROKE = {
    Status.SUCCESS: "#2e7d32",
    Status.FAILURE: "#c62828",
    Status.RUNNING: "#1565c0",
}
_CHAR_W = 7.0  # px per character at font-size 12 (estimate; no font metrics offline)
_BOX_H = 38.0
_PAD_X = 12.0
_GAP_X = 16.0
_GAP_Y = 44.0
_MARGIN = 12.0


def node_kind(behaviour: py_trees.behaviour.Behaviour) -> str:
    """Return Sequence, Selector, Parallel, Decorator, Action or Condition.

    Leaves are ``Action`` unless their class says ``NODE_TYPE = "Condition"``.
    """
    if isinstance(behaviour, py_trees.composites.Sequence):
        return "Sequence"
    if isinstance(behaviour, py_trees.composites.Selector):
        return "Selector"
    if isinstance(behaviour, py_trees.composites.Parallel):
        return "Parallel"
    if isinstance(behaviour, py_trees.decorators.Decorator):
        return "Decorator"
    if isinstance(behaviour, py_trees.composites.Composite):
        return "Sequence"
    return "Condition" if getattr(behaviour, "NODE_TYPE", "Action") == "Condition" else "Action"


def node_type(behaviour: py_trees.behaviour.Behaviour) -> str:
    """Return the node's tag: the registry name of a ports node, else its class name."""
    return str(getattr(behaviour, "behaviour_class_name", type(behaviour).__name__))


def bt_type(behaviour: py_trees.behaviour.Behaviour) -> str:
    """The node's type as BehaviorTree.CPP spells it (``Fallback``, ``ReactiveSequence``,
    ``RetryUntilSuccessful``, ``ForceSuccess``; a leaf's tag), not py_trees' class name."""
    if isinstance(behaviour, py_trees.composites.Sequence):
        return "Sequence" if behaviour.memory else "ReactiveSequence"
    if isinstance(behaviour, py_trees.composites.Selector):
        return "Fallback" if behaviour.memory else "ReactiveFallback"
    if isinstance(behaviour, py_trees.composites.Parallel):
        return "Parallel"
    if isinstance(behaviour, py_trees.decorators.Retry):
        return "RetryUntilSuccessful"
    if isinstance(behaviour, py_trees.decorators.Repeat):
        return "Repeat"
    if isinstance(behaviour, SimTimeout):
        return "Timeout"
    return BT_DECORATORS.get(type(behaviour), node_type(behaviour))


#: py_trees' decorators BehaviorTree.CPP has under another name.
BT_DECORATORS: dict[type, str] = {
    py_trees.decorators.FailureIsSuccess: "ForceSuccess",
    py_trees.decorators.SuccessIsFailure: "ForceFailure",
    py_trees.decorators.Inverter: "Inverter",
}


def short_name(behaviour: py_trees.behaviour.Behaviour) -> str:
    """The name as written: without the parent prefix or generated uuid the XML parser adds; a
    node the file leaves unnamed is named by its type, as BehaviorTree.CPP names it."""
    if unnamed(behaviour.name):
        return bt_type(behaviour)
    return get_base_name(behaviour.name, strip_uuid=True) or behaviour.name


def shown_name(behaviour: py_trees.behaviour.Behaviour) -> str:
    """The node's full name without py_trees' uuids, an unnamed node's last part its
    BehaviorTree.CPP type (:func:`bt_type`): the same in every run."""
    name = readable(behaviour.name)
    if not unnamed(behaviour.name):
        return name
    head, dot, _ = name.rpartition(".")
    return f"{head}{dot}{bt_type(behaviour)}"


def _children(behaviour: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    return list(behaviour.children)


@dataclass
class _Box:
    node: py_trees.behaviour.Behaviour
    depth: int
    width: float
    children: list[_Box] = field(default_factory=list)
    span: float = 0.0
    x: float = 0.0  # centre, px


def _label_lines(node: py_trees.behaviour.Behaviour) -> tuple[str, str]:
    kind = node_kind(node)
    glyph = _STYLE[kind][3]
    title = f"{glyph} {short_name(node)}" if glyph else short_name(node)
    tag = node_type(node)
    is_leaf = kind in ("Action", "Condition")
    subtitle = f"{tag} · {kind}" if is_leaf else tag
    if isinstance(node, py_trees.composites.Sequence | py_trees.composites.Selector):
        subtitle += "" if node.memory else " (reactive)"
    return title, subtitle


def _measure(node: py_trees.behaviour.Behaviour, depth: int) -> _Box:
    title, subtitle = _label_lines(node)
    width = max(len(title), len(subtitle)) * _CHAR_W + 2 * _PAD_X
    box = _Box(node, depth, width, [_measure(c, depth + 1) for c in _children(node)])
    children_span = sum(c.span for c in box.children) + _GAP_X * max(len(box.children) - 1, 0)
    box.span = max(box.width, children_span)
    return box


def _place(box: _Box, left: float) -> None:
    """Give ``box`` and its subtree x centres inside [left, left + span]."""
    if not box.children:
        box.x = left + box.span / 2.0
        return
    children_span = sum(c.span for c in box.children) + _GAP_X * (len(box.children) - 1)
    cursor = left + (box.span - children_span) / 2.0
    for child in box.children:
        _place(child, cursor)
        cursor += child.span + _GAP_X
    box.x = (box.children[0].x + box.children[-1].x) / 2.0


def _walk(box: _Box) -> list[_Box]:
    out = [box]
    for child in box.children:
        out.extend(_walk(child))
    return out


def _fmt(value: float) -> str:
    return f"{value:.1f}"


def render_svg(root: py_trees.behaviour.Behaviour, show_status: bool = False) -> str:
    """Return SVG text: one rounded box per node (``<rect class="node ...">``), edges as paths.

    Parameters
    ----------
    root : py_trees.behaviour.Behaviour
        Tree root.
    show_status : bool
        Outline each box in the colour of the node's last status (green, red, blue).
    """
    top = _measure(root, 0)
    _place(top, _MARGIN)
    boxes = _walk(top)
    depth = max(b.depth for b in boxes)
    width = top.span + 2 * _MARGIN
    height = (depth + 1) * _BOX_H + depth * _GAP_Y + 2 * _MARGIN

    def y_top(b: _Box) -> float:
        return _MARGIN + b.depth * (_BOX_H + _GAP_Y)

    svg = ET.Element(
        "svg",
        {
            "xmlns": "http://www.w3.org/2000/svg",
            "width": _fmt(width),
            "height": _fmt(height),
            "viewBox": f"0 0 {_fmt(width)} {_fmt(height)}",
            "font-family": "DejaVu Sans, Helvetica, Arial, sans-serif",
            "font-size": "12",
        },
    )
    ET.SubElement(svg, "title").text = short_name(root)
    edges = ET.SubElement(svg, "g", {"class": "edges", "fill": "none", "stroke": "#777"})
    for b in boxes:
        for c in b.children:
            x1, y1 = b.x, y_top(b) + _BOX_H
            x2, y2 = c.x, y_top(c)
            ym = (y1 + y2) / 2.0
            ET.SubElement(
                edges,
                "path",
                {"d": f"M{_fmt(x1)},{_fmt(y1)} C{_fmt(x1)},{_fmt(ym)} {_fmt(x2)},{_fmt(ym)} "
                 f"{_fmt(x2)},{_fmt(y2)}"},
            )  # fmt: skip
    nodes = ET.SubElement(svg, "g", {"class": "nodes"})
    for b in boxes:
        kind = node_kind(b.node)
        fill, stroke, radius, _ = _STYLE[kind]
        if show_status and b.node.status in _STATUS_STROKE:
            stroke = _STATUS_STROKE[b.node.status]
        rx = _BOX_H / 2.0 if radius is None else radius
        group = ET.SubElement(nodes, "g", {"class": f"node-group {kind.lower()}"})
        tooltip = f"{b.node.name} [{node_type(b.node)}]"
        if show_status:
            tooltip += f" {b.node.status.value}"
            if b.node.feedback_message:
                tooltip += f": {b.node.feedback_message}"
        ET.SubElement(group, "title").text = tooltip
        attrib = {
            "class": f"node {kind.lower()}",
            "x": _fmt(b.x - b.width / 2.0),
            "y": _fmt(y_top(b)),
            "width": _fmt(b.width),
            "height": _fmt(_BOX_H),
            "rx": _fmt(rx),
            "fill": fill,
            "stroke": stroke,
            "stroke-width": "2" if show_status else "1.5",
        }
        if kind == "Decorator":
            attrib["stroke-dasharray"] = "4 2"
        ET.SubElement(group, "rect", attrib)
        title, subtitle = _label_lines(b.node)
        ET.SubElement(
            group,
            "text",
            {"x": _fmt(b.x), "y": _fmt(y_top(b) + 16.0), "text-anchor": "middle",
             "font-weight": "bold"},
        ).text = title  # fmt: skip
        ET.SubElement(
            group,
            "text",
            {"x": _fmt(b.x), "y": _fmt(y_top(b) + 31.0), "text-anchor": "middle",
             "font-size": "10", "fill": "#444"},
        ).text = subtitle  # fmt: skip
    ET.indent(svg)
    return ET.tostring(svg, encoding="unicode") + "\n"


def render_tree(root: py_trees.behaviour.Behaviour, fmt: str, show_status: bool = False) -> str:
    """Render a tree as ``ascii``, ``unicode``, ``dot`` (Graphviz source) or ``svg``.

    Parameters
    ----------
    root : py_trees.behaviour.Behaviour
        Tree root.
    fmt : str
        One of :data:`FORMATS`.
    show_status : bool
        Include each node's last status (text and SVG formats).

    Raises
    ------
    ValueError
        For an unknown format.
    """
    # An unnamed node is named by its type, as BehaviorTree.CPP names it, not py_trees' uuid.
    if fmt == "ascii":
        return _bt_names(py_trees.display.ascii_tree(root, show_status=show_status), root)
    if fmt == "unicode":
        return _bt_names(py_trees.display.unicode_tree(root, show_status=show_status), root)
    if fmt == "dot":
        return str(py_trees.display.dot_tree(root).to_string())
    if fmt == "svg":
        return render_svg(root, show_status=show_status)
    raise ValueError(f"render: expected format one of {', '.join(FORMATS)}, got {fmt!r}")


def _bt_names(text: str, root: py_trees.behaviour.Behaviour) -> str:
    """``text`` with each unnamed node's py_trees name (``Selector_<uuid4>``, unique by its
    uuid) its BehaviorTree.CPP type, and py_trees' other uuids taken out."""
    for node in root.iterate():
        if unnamed(node.name):
            own = node.name.rpartition(".")[2]
            text = text.replace(own, bt_type(node))
    return readable(text)


def render_cli(
    path: str | os.PathLike[str], fmt: str, out: str | None = None, main_tree: str | None = None
) -> int:
    """Load a tree file (its ``main_tree`` if given) and print (or write to ``out``) its rendering.

    Returns 0 on success, 2 for a bad tree file or format (the reason goes to stderr).
    """
    if fmt not in FORMATS:
        print(f"render: expected format one of {', '.join(FORMATS)}, got {fmt!r}", file=sys.stderr)
        return 2
    try:
        doc = read_tree_document(path, main_tree_id=main_tree)
        # Every file the tree was read from: the one named and those it includes.
        read = {str(path)} | {source_file(e, str(path)) for e in doc.root.iter()}
        root = load_document(doc)
    except TreeFileError as exc:
        print(exc, file=sys.stderr)
        return 2
    overwritten = sorted(f for f in read if out is not None and _same_file(f, out))
    if overwritten:
        print(
            f"--out {out}: expected a file other than the tree's, got {overwritten[0]}, which "
            "the tree was read from (it would be overwritten by its picture)",
            file=sys.stderr,
        )
        return 2
    text = render_tree(root, fmt)
    if out is None:
        sys.stdout.write(text)
    else:
        try:
            with atomic_open(out) as handle:
                handle.write(text)
        except OSError as exc:
            print(f"{out}: cannot write: {exc.strerror}", file=sys.stderr)
            return 2
    return 0


def _same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether two paths name one file (through links too); False if either is not there."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False
