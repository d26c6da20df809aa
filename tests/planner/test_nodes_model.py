"""nodes_model_xml: a Groot2 TreeNodesModel listing our leaves, their kind and ports."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import ClassVar

import py_trees
import pytest
from py_trees.common import Status
from py_trees.ports import BehaviourWithPorts, PortInformation, get_ports_registry

from planner.nodes_model import leaf_kind, nodes_model_xml, summary_line
from tests.planner import stub_leaves


def model(**kwargs: object) -> ET.Element:
    root = ET.fromstring(nodes_model_xml(**kwargs))  # type: ignore[arg-type]
    assert root.tag == "root" and root.attrib == {"BTCPP_format": "4"}
    (tree_nodes,) = list(root)
    assert tree_nodes.tag == "TreeNodesModel"
    return tree_nodes


def test_lists_stub_leaves_with_kind_ports_defaults_and_descriptions() -> None:
    nodes = {n.attrib["ID"]: n for n in model(packages=("tests.planner",))}
    assert list(nodes) == sorted(nodes)
    assert {"StubAt", "StubCheck", "StubCounter", "StubFlaky", "StubForever", "StubGrasp"} <= set(
        nodes
    )
    grasp = nodes["StubGrasp"]
    assert grasp.tag == "Action"
    ports = [(p.tag, p.attrib, p.text) for p in grasp if p.tag.endswith("_port")]
    assert ports == [
        ("input_port", {"name": "force_n", "type": "float"}, "squeeze, N"),
        ("input_port", {"name": "timeout_s", "type": "float", "default": "1.0"}, "s"),
        ("output_port", {"name": "holding", "type": "bool"}, "grip closed"),
    ]
    (metadata,) = grasp.iter("Metadata")
    assert metadata.attrib == {"description": "Pretend to squeeze an object; succeeds at once."}
    assert nodes["StubCheck"].tag == "Condition"
    assert nodes["StubForever"].tag == "Action"  # no NODE_TYPE: Action
    (position,) = nodes["StubAt"].iter("input_port")
    assert position.attrib["type"] == "list[float]"


def test_a_description_is_the_docstrings_first_sentence_as_groot2_shows_it() -> None:
    class Wrapped:
        """Hold the object at ``height_m`` above the table (as
        :attr:`~planner.move_result.MoveResult.rested_z` says). Groot2 shows one line.

        More detail, not shown."""

    assert summary_line(Wrapped) == (
        "Hold the object at 'height_m' above the table (as rested_z says)."
    )


def test_default_lists_only_planner_classes() -> None:
    ids = {n.attrib["ID"] for n in model()}
    assert not any(i.startswith("Stub") for i in ids)
    for tag in ids:
        assert get_ports_registry()[tag].__module__.startswith("planner.")


def test_include_all_lists_every_registered_class() -> None:
    ids = {n.attrib["ID"] for n in model(include_all=True)}
    assert set(get_ports_registry()) == ids


def test_output_is_deterministic() -> None:
    assert nodes_model_xml(include_all=True) == nodes_model_xml(include_all=True)


class StubBadKind(BehaviourWithPorts, register=False):
    """A leaf with a NODE_TYPE Groot does not know."""

    NODE_TYPE: ClassVar[str] = "Sensor"
    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        return Status.SUCCESS


class StubWithList(BehaviourWithPorts, register=False):
    """Defaults of lists and booleans are written so the parser reads them back."""

    INPUT_PORTS = {
        "xs": PortInformation(data_type=list[float], default_value=[1.0, 2.5]),
        "on": PortInformation(data_type=bool, default_value=False),
    }
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def update(self) -> Status:
        return Status.SUCCESS


def test_explicit_registry_and_default_formatting() -> None:
    nodes = model(registry={"WithList": StubWithList}, include_all=True)
    (node,) = nodes
    assert node.attrib == {"ID": "WithList"}
    defaults = {p.attrib["name"]: p.attrib["default"] for p in node.iter("input_port")}
    assert defaults == {"xs": "1.0;2.5", "on": "false"}


def test_bad_node_type_is_explained() -> None:
    with pytest.raises(ValueError, match=r"StubBadKind\.NODE_TYPE: expected one of Action, "
                       r"Condition, got 'Sensor'"):  # fmt: skip
        nodes_model_xml(registry={"Bad": StubBadKind}, include_all=True)


def test_decorators_and_controls_are_labelled() -> None:
    from planner.decorators import SimTimeout

    assert leaf_kind(SimTimeout) == "Decorator"
    assert leaf_kind(stub_leaves.StubCheck) == "Condition"
    assert leaf_kind(py_trees.composites.Sequence) == "Control"


@pytest.mark.parametrize("name", ["pick_and_place.xml", "paper_composition.xml"])
def test_shipped_trees_embed_the_model_app_nodes_writes(name: str) -> None:
    import planner.leaves  # noqa: F401  (registers the leaves)
    from planner.default_tree import PICK_AND_PLACE_XML
    from planner.nodes_model import embed_nodes_model

    path = PICK_AND_PLACE_XML.parent / name
    text = path.read_text(encoding="utf-8")
    # embedding again changes nothing: the file holds the model of the leaves it uses now
    assert embed_nodes_model(path) == text, f"run: app.py nodes --embed {path}"
    embedded = ET.fromstring(text.encode("utf-8")).find("TreeNodesModel")
    assert embedded is not None
    used = {
        e.tag
        for bt in ET.fromstring(text.encode("utf-8")).findall("BehaviorTree")
        for e in bt.iter()
    }
    ours = {n.attrib["ID"]: n for n in model()}  # what `app.py nodes` prints
    assert [n.attrib["ID"] for n in embedded] == sorted(used & set(ours))
    for node in embedded:
        assert ET.canonicalize(ET.tostring(node), strip_text=True) == ET.canonicalize(
            ET.tostring(ours[node.attrib["ID"]]), strip_text=True
        )


def test_embed_replaces_a_model_and_keeps_the_rest(tmp_path: Path) -> None:
    from planner.nodes_model import embed_nodes_model

    path = tmp_path / "t.xml"
    path.write_text(
        '<root BTCPP_format="4">\n  <!-- keep me -->\n  <BehaviorTree ID="A">\n'
        '    <StubCheck value="true"/>\n  </BehaviorTree>\n  <TreeNodesModel>\n'
        '    <Action ID="Old"/>\n  </TreeNodesModel>\n</root>\n',
        encoding="utf-8",
    )
    text = embed_nodes_model(path, packages=("tests.planner",))
    assert "<!-- keep me -->" in text and 'ID="Old"' not in text
    assert text.count("<TreeNodesModel>") == 1
    embedded = ET.fromstring(text).find("TreeNodesModel")
    assert embedded is not None
    assert [(n.tag, n.attrib["ID"]) for n in embedded] == [("Condition", "StubCheck")]


def test_embed_keeps_the_subtree_ports_and_the_models_of_nodes_it_cannot_model(
    tmp_path: Path,
) -> None:
    # The model had been made anew from the registered leaves alone: a SubTree's port
    # defaults (what the tree means) and another robot's node were lost, and a tree that
    # validated was refused once embedded.
    from planner.nodes_model import embed_nodes_model

    path = tmp_path / "t.xml"
    path.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="M">\n'
        '  <BehaviorTree ID="M"><Sequence><SubTree ID="C"/><Wave/></Sequence></BehaviorTree>\n'
        '  <BehaviorTree ID="C"><StubCheck value="{ok}"/></BehaviorTree>\n'
        "  <TreeNodesModel>\n"
        '    <SubTree ID="C"><input_port name="ok" default="true"/></SubTree>\n'
        '    <Action ID="Wave"><input_port name="hand"/></Action>\n'
        '    <Action ID="Unused"/>\n'
        "  </TreeNodesModel>\n</root>\n",
        encoding="utf-8",
    )
    embedded = ET.fromstring(embed_nodes_model(path, packages=("tests.planner",)))
    model_there = embedded.find("TreeNodesModel")
    assert model_there is not None
    entries = {n.attrib["ID"]: n for n in model_there}
    assert sorted(entries) == ["C", "StubCheck", "Wave"]
    port = entries["C"].find("input_port")
    assert port is not None and port.attrib == {"name": "ok", "default": "true"}
    assert entries["Wave"].tag == "Action"


def test_embed_with_out_writes_a_copy_and_leaves_the_tree(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --out had been ignored beside --embed, the tree rewritten in place without a word.
    import app

    tree = tmp_path / "mine.xml"
    shipped = Path(__file__).resolve().parents[2] / "planner" / "trees" / "pick_and_place.xml"
    tree.write_bytes(shipped.read_bytes())
    copy = tmp_path / "with_model.xml"
    assert app.main(["nodes", "--embed", str(tree), "--out", str(copy)]) == app.EXIT_OK
    assert tree.read_bytes() == shipped.read_bytes()
    assert "<TreeNodesModel>" in copy.read_text(encoding="utf-8")
    assert f"into {copy}" in capsys.readouterr().out


def test_embed_refuses_a_tree_whose_leaves_nothing_models(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # It had written the model without them, exit 0: Groot2 then opened them as unknown
    # nodes, their ports lost (validate refuses the same tree).
    import app

    tree = tmp_path / "mine.xml"
    text = (
        '<root BTCPP_format="4" main_tree_to_execute="M">\n'
        '  <BehaviorTree ID="M"><Sequence><HeldStill object="parcel"/><AlwaysSuccess/>'
        '<IsHeld object="parcel"/></Sequence></BehaviorTree>\n</root>\n'
    )
    tree.write_text(text, encoding="utf-8")
    assert app.main(["nodes", "--embed", str(tree)]) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert (
        f"{tree}: expected leaves Duet or a --leaves file models, got HeldStill (register "
        "them with --leaves FILE.py|MODULE; nothing was written)"
    ) in err
    assert tree.read_text(encoding="utf-8") == text
