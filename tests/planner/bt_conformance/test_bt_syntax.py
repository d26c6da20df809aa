"""BT.CPP syntax: a lone <BehaviorTree> without ID; attributes not supported are named."""

from __future__ import annotations

import py_trees
import pytest

from planner.loader import TreeFileError, load_tree_string
from tests.planner.bt_conformance.conftest import F, R, S, Ticker


def test_single_behavior_tree_without_id_is_the_main_tree() -> None:
    t = Ticker('<Sequence name="s"><StubScripted name="a" script="R,S"/></Sequence>', single=True)
    t.run(("s", "a"), [(R, R), (S, S)])


def test_two_trees_without_ids_are_refused() -> None:
    text = (
        '<root BTCPP_format="4"><BehaviorTree><AlwaysSuccess/></BehaviorTree>'
        "<BehaviorTree><AlwaysFailure/></BehaviorTree></root>"
    )
    with pytest.raises(TreeFileError, match=r'expected an ID="\.\.\." attribute'):
        load_tree_string(text, "two.xml")


def test_unknown_underscore_attribute_is_named() -> None:
    with pytest.raises(TreeFileError, match="unknown attribute '_skipif'; expected one of"):
        Ticker('<AlwaysFailure name="a" _skipif="x"/>')


def test_explicit_action_form_of_a_builtin() -> None:
    t = Ticker('<Action ID="AlwaysFailure" name="a"/>')
    t.run(("a",), [(F,)])


def _load(text: str) -> py_trees.behaviour.Behaviour:
    root = load_tree_string(text, "ports.xml")
    py_trees.trees.BehaviourTree(root).setup()
    return root


def test_same_name_remap() -> None:
    root = _load(
        '<root BTCPP_format="4"><BehaviorTree><Sequence name="s">'
        '<StubCounter name="a" ticks="1" count="{=}"/></Sequence></BehaviorTree></root>'
    )
    root.tick_once()
    assert py_trees.blackboard.Blackboard.get("/count") == 1


def test_root_key_from_a_nested_subtree() -> None:
    root = _load(
        '<root BTCPP_format="4" main_tree_to_execute="T">'
        '<BehaviorTree ID="T"><Sequence name="s"><SubTree ID="A" name="a"/>'
        '<StubCounter name="m" ticks="1" count="{mine}"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="A"><SubTree ID="B" name="b"/></BehaviorTree>'
        '<BehaviorTree ID="B"><StubCounter name="deep" ticks="1" count="{@hits}"/></BehaviorTree>'
        "</root>"
    )
    root.tick_once()
    assert root.status == S
    assert py_trees.blackboard.Blackboard.get("/hits") == 1
    assert py_trees.blackboard.Blackboard.get("/mine") == 1


def test_autoremap_shares_every_key_of_the_subtree() -> None:
    root = _load(
        '<root BTCPP_format="4" main_tree_to_execute="T">'
        '<BehaviorTree ID="T"><Sequence name="s"><SubTree ID="A" name="a" _autoremap="true"/>'
        '<SubTree ID="A" name="b"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="A"><StubCounter name="c" ticks="1" count="{n}"/></BehaviorTree>'
        "</root>"
    )
    root.tick_once()
    assert py_trees.blackboard.Blackboard.get("/n") == 1  # autoremapped: the caller's key
    assert py_trees.blackboard.Blackboard.get("/b/n") == 1  # not remapped: the subtree's own


def test_autoremap_passes_keys_through_a_middle_tree_that_never_names_them() -> None:
    # BT.CPP looks a key up through every autoremapping parent. The middle tree's keys alone
    # had been remapped: the inner script failed, 'x' not found, and the checker refused the
    # tree's ports as written by nothing.
    root = _load(
        '<root BTCPP_format="4" main_tree_to_execute="T">'
        '<BehaviorTree ID="T"><Sequence name="s"><Script name="v" code="x := 1"/>'
        '<SubTree ID="Outer" name="o" _autoremap="true"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="Outer"><SubTree ID="Inner" name="i" _autoremap="true"/></BehaviorTree>'
        '<BehaviorTree ID="Inner"><Sequence name="q"><Script name="w" code="x := x + 1"/>'
        '<StubCounter name="c" ticks="1" count="{n}"/></Sequence></BehaviorTree>'
        "</root>"
    )
    root.tick_once()
    assert root.status == S
    assert py_trees.blackboard.Blackboard.get("/x") == 2
    assert py_trees.blackboard.Blackboard.get("/n") == 1


def test_subtree_port_default_from_the_tree_nodes_model() -> None:
    root = _load(
        '<root BTCPP_format="4" main_tree_to_execute="T">'
        '<BehaviorTree ID="T"><Sequence name="s"><SubTree ID="A" name="a" out="{got}"/>'
        '<SubTree ID="A" name="b" out="{got2}" limit="3"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="A"><StubCounter name="c" ticks="{limit}" count="{out}"/></BehaviorTree>'
        '<TreeNodesModel><SubTree ID="A"><input_port name="limit" default="2"/>'
        '<output_port name="out"/></SubTree></TreeNodesModel></root>'
    )
    statuses = []
    for _ in range(4):
        root.tick_once()
        statuses.append(root.status)
    # a counts to the model's default 2, b to its own 3 (b starts in a's last tick).
    assert statuses == [R, R, R, S]
    assert py_trees.blackboard.Blackboard.get("/got") == 2
    assert py_trees.blackboard.Blackboard.get("/got2") == 3


def test_scripts_in_a_subtree_follow_its_port_remapping() -> None:
    # BT.CPP's own tutorial on subtree ports: the subtree's scripts read and write the ports.
    root = _load(
        '<root BTCPP_format="4" main_tree_to_execute="T">'
        '<BehaviorTree ID="T"><Sequence name="s">'
        '<Script name="goal" code="move_goal := 5"/>'
        '<SubTree ID="Move" name="m" target="{move_goal}" result="{move_result}" mode="fast"/>'
        "</Sequence></BehaviorTree>"
        '<BehaviorTree ID="Move"><Sequence name="q">'
        '<ScriptCondition name="c" code="target == 5 &amp;&amp; mode == \'fast\'"/>'
        "<Script name=\"r\" code=\"result := 'reached'; mode := 'slow'; own := 1\"/>"
        "</Sequence></BehaviorTree></root>"
    )
    root.tick_once()
    get = py_trees.blackboard.Blackboard.get
    assert root.status == S
    assert get("/move_result") == "reached"  # the caller's key
    # A literal port reads as its text; what the subtree writes stays in its own namespace.
    assert (get("/m/mode"), get("/m/own")) == ("slow", 1)
    assert not py_trees.blackboard.Blackboard.exists("/result")


def test_autoremap_and_a_model_port_cover_keys_only_scripts_use() -> None:
    root = _load(
        '<root BTCPP_format="4" main_tree_to_execute="T">'
        '<BehaviorTree ID="T"><Sequence name="s"><Script name="v" code="value := 0"/>'
        '<SubTree ID="A" name="a" _autoremap="1"/>'
        '<SubTree ID="B" name="b" out="{from_b}"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="A"><Script name="w" code="value += 1"/></BehaviorTree>'
        '<BehaviorTree ID="B"><AlwaysSuccess name="nothing"/></BehaviorTree>'
        '<TreeNodesModel><SubTree ID="B"><output_port name="out"/></SubTree></TreeNodesModel>'
        "</root>"
    )
    root.tick_once()
    assert root.status == S
    assert py_trees.blackboard.Blackboard.get("/value") == 1


def test_bare_less_than_and_ampersands_in_attributes_read_as_bt_cpp_reads_them() -> None:
    # tinyxml2, BT.CPP's parser, takes them; BT.CPP's own examples write scripts so.
    text = (
        '\n  <?xml version="1.0"?>\n<root BTCPP_format="4"><BehaviorTree>'
        '<Sequence name="s"><Script name="a" code="A := 1; ok := A<2 && A>0 &amp;&amp; true"/>'
        '<StubScripted name="b" script="S" _skipIf="A<2"/></Sequence></BehaviorTree></root>'
    )
    root = _load(text)
    root.tick_once()
    assert py_trees.blackboard.Blackboard.get("/ok") is True
    assert root.status == S and root.children[1].ticks == 0  # skipped: A < 2


def test_xml_that_is_broken_either_way_reports_the_first_error() -> None:
    # The '<' in the value is expat's error; read leniently, the missing </Sequence> is.
    with pytest.raises(TreeFileError, match=r"ports.xml:2:29: XML syntax error: not well-formed"):
        _load('<root BTCPP_format="4">\n<BehaviorTree><Sequence a="x<y"></BehaviorTree></root>')


def test_white_space_around_a_key_is_trimmed() -> None:
    root = _load(
        '<root BTCPP_format="4"><BehaviorTree><Sequence name="s">'
        '<StubCounter name="a" ticks="1" count=" {n}  "/></Sequence></BehaviorTree></root>'
    )
    root.tick_once()
    assert py_trees.blackboard.Blackboard.get("/n") == 1
