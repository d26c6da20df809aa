"""BT.CPP LoopInt / LoopDouble / LoopString / LoopBool."""

from __future__ import annotations

import py_trees
import pytest

from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker


def test_loop_int_pops_a_literal_queue_one_value_per_child_run() -> None:
    t = Ticker(
        '<LoopInt name="l" queue="1;2;3" value="{v}">'
        '<StubCounter name="c" ticks="{v}" count="{n}"/></LoopInt>'
    )
    # 1: one tick; 2: two ticks; 3: three ticks; then the empty queue gives SUCCESS.
    t.run(("l", "c"), [(R, S), (R, R), (R, S), (R, R), (R, R), (R, S), (S, S)])


def test_loop_fails_with_its_child_and_if_empty() -> None:
    t = Ticker(
        '<LoopString name="l" queue="a;b"><StubScripted name="c" script="S,F"/></LoopString>'
    )
    t.run(("l", "c"), [(R, S), (F, F)])
    t2 = Ticker(
        '<LoopDouble name="l" queue="" if_empty="FAILURE"><StubScripted name="c" script="S"/>'
        "</LoopDouble>"
    )
    t2.run(("l", "c"), [(F, INV)])


def test_loop_consumes_a_shared_list_from_the_blackboard() -> None:
    py_trees.blackboard.Blackboard.set("/todo", [0.5, 1.5])
    t = Ticker(
        '<LoopDouble name="l" queue="{todo}" value="{x}"><StubScripted name="c" script="S"/>'
        "</LoopDouble>"
    )
    t.run(("l",), [(R,)])
    assert py_trees.blackboard.Blackboard.get("/x") == pytest.approx(0.5)
    assert py_trees.blackboard.Blackboard.get("/todo") == [1.5]
    t.run(("l",), [(R,), (S,)])
    assert py_trees.blackboard.Blackboard.get("/x") == pytest.approx(1.5)


def test_loop_bool_refuses_a_bad_value() -> None:
    t = Ticker(
        '<LoopBool name="l" queue="true;maybe"><StubScripted name="c" script="S"/></LoopBool>'
    )
    t.run(("l",), [(F,)])
    assert "expected true or false, got 'maybe'" in t.nodes["l"].feedback_message
