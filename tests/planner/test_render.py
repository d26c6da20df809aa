"""render_tree: ascii, dot and a self-made SVG layout with one box per node."""

from __future__ import annotations

import itertools
import xml.etree.ElementTree as ET
from pathlib import Path

import py_trees
import pytest

from planner.loader import load_tree
from planner.render import node_kind, render_cli, render_tree, short_name

TREES = Path(__file__).resolve().parents[1] / "data" / "trees"
SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture
def root() -> py_trees.behaviour.Behaviour:
    import tests.planner.stub_leaves  # noqa: F401

    return load_tree(TREES / "retry_timeout.xml")


def boxes(svg_text: str) -> list[ET.Element]:
    svg = ET.fromstring(svg_text)
    assert svg.tag == f"{SVG}svg"
    return [r for r in svg.iter(f"{SVG}rect") if "node" in r.attrib.get("class", "").split()]


def test_svg_has_one_box_per_node_with_name_and_type(root: py_trees.behaviour.Behaviour) -> None:
    text = render_tree(root, "svg")
    nodes = list(root.iterate())
    rects = boxes(text)
    assert len(rects) == len(nodes) == 11
    kinds = sorted(r.attrib["class"].split()[1] for r in rects)
    assert kinds == sorted(node_kind(n).lower() for n in nodes)
    labels = [t.text or "" for t in ET.fromstring(text).iter(f"{SVG}text")]
    assert "StubFlaky · Action" in labels
    assert "StubCheck · Condition" in labels
    assert "Timeout" in labels
    assert any(label.endswith("squeeze") for label in labels)
    paths = list(ET.fromstring(text).iter(f"{SVG}path"))
    assert len(paths) == len(nodes) - 1  # one edge per child


def test_svg_boxes_on_a_layer_do_not_overlap_and_fit(root: py_trees.behaviour.Behaviour) -> None:
    svg = ET.fromstring(render_tree(root, "svg"))
    width = float(svg.attrib["width"])
    layers: dict[float, list[tuple[float, float]]] = {}
    for r in boxes(ET.tostring(svg, encoding="unicode")):
        x, w = float(r.attrib["x"]), float(r.attrib["width"])
        assert 0.0 <= x and x + w <= width
        layers.setdefault(float(r.attrib["y"]), []).append((x, x + w))
    assert len(layers) == 4  # root, attempt/give_up, grip_seq/retry/limit/never, leaves
    for spans in layers.values():
        spans.sort()
        for (_, right), (left, _) in itertools.pairwise(spans):
            assert right <= left


def test_svg_status_outline_and_escaping() -> None:
    node = py_trees.behaviours.Success(name='a <b> & "c"')
    seq = py_trees.composites.Sequence(name="seq", memory=True, children=[node])
    seq.tick_once()
    text = render_tree(seq, "svg", show_status=True)
    rects = boxes(text)
    assert [r.attrib["stroke"] for r in rects] == ["#2e7d32", "#2e7d32"]
    assert 'a <b> & "c"' in [t.text for t in ET.fromstring(text).iter(f"{SVG}text")]


def test_ascii_and_dot(root: py_trees.behaviour.Behaviour) -> None:
    ascii_text = render_tree(root, "ascii")
    assert "root.attempt.limit.slow" in ascii_text
    assert all(ord(c) < 128 for c in ascii_text)
    dot = render_tree(root, "dot")
    assert dot.startswith("digraph")
    assert '"root.attempt.limit.slow"' in dot


def test_unknown_format() -> None:
    with pytest.raises(ValueError, match=r"expected format one of ascii, unicode, dot, svg"):
        render_tree(py_trees.behaviours.Success(name="s"), "png")


def test_short_names_drop_prefix_and_uuid() -> None:
    uid = "0b6e6f4e-8e4b-4c55-9a7b-1f0a2b3c4d5e"
    node = py_trees.composites.Sequence(name=f"a.b.Sequence_{uid}", memory=True)
    assert short_name(node) == "Sequence"
    # Unnamed, a node is named by its type as BehaviorTree.CPP spells it, not py_trees' class.
    fallback = py_trees.composites.Selector(name=f"a.Selector_{uid}", memory=False)
    assert short_name(fallback) == "ReactiveFallback"
    assert short_name(py_trees.composites.Selector(name="a.b.pick", memory=True)) == "pick"


def test_render_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import tests.planner.stub_leaves  # noqa: F401

    out = tmp_path / "tree.svg"
    assert render_cli(TREES / "retry_timeout.xml", "svg", out=str(out)) == 0
    assert len(boxes(out.read_text())) == 11
    assert render_cli(TREES / "retry_timeout.xml", "ascii") == 0
    assert "root.attempt" in capsys.readouterr().out
    assert render_cli(TREES / "bad_unknown_port.xml", "svg") == 2
    assert "unknown port 'forse'" in capsys.readouterr().err
    assert render_cli(TREES / "retry_timeout.xml", "gif") == 2
    # --out naming the tree itself would replace the tree by its picture.
    mine = tmp_path / "mine.xml"
    mine.write_bytes((TREES / "retry_timeout.xml").read_bytes())
    assert render_cli(mine, "svg", out=str(mine)) == 2
    assert "which the tree was read from" in capsys.readouterr().err
    assert mine.read_bytes() == (TREES / "retry_timeout.xml").read_bytes()
    # Nor a file the tree includes.
    (tmp_path / "sub.xml").write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="Sub"><AlwaysSuccess/></BehaviorTree></root>',
        encoding="utf-8",
    )
    (tmp_path / "main.xml").write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main"><include path="sub.xml"/>'
        '<BehaviorTree ID="Main"><SubTree ID="Sub"/></BehaviorTree></root>',
        encoding="utf-8",
    )
    included = (tmp_path / "sub.xml").read_bytes()
    assert render_cli(tmp_path / "main.xml", "ascii", out=str(tmp_path / "sub.xml")) == 2
    assert "sub.xml, which the tree was read from" in capsys.readouterr().err
    assert (tmp_path / "sub.xml").read_bytes() == included
