"""BT.CPP syntax: a lone <BehaviorTree> without ID; attributes not supported are named."""

from __future__ import annotations

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
