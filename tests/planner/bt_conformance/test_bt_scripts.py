"""Script, ScriptCondition, Precondition and the pre/post-condition attributes on leaves,
controls, decorators and SubTrees, with BT.CPP's order and running-state rules."""

from __future__ import annotations

import py_trees
import pytest

from planner.loader import TreeFileError, load_tree_string
from planner.script_enums import clear_script_enums, register_script_enums
from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker

get = py_trees.blackboard.Blackboard.get
SKIP = '_skipIf="true"'
SUCCESS_AND_SKIP = '_successIf="true" _skipIf="true"'
WHILE_ON = "_while='on' _onHalted='halted := 1'"


def leaf(name: str, script: str, extra: str = "") -> str:
    return f'<StubScripted name="{name}" script="{script}" {extra}/>'


def test_script_assigns_and_script_condition_tests() -> None:
    t = Ticker(
        '<Sequence name="s"><Script name="a" code="x := 3; y := x * 2"/>'
        '<ScriptCondition name="c" code="y == 6 &amp;&amp; x &lt; 4"/></Sequence>'
    )
    t.run(("s", "a", "c"), [(S, S, S)])
    assert (get("/x"), get("/y")) == (3, 6)


def test_script_runtime_error_is_a_failure_with_the_reason() -> None:
    t = Ticker('<Script name="a" code="y = missing + 1"/>')
    t.run(("a",), [(F,)])
    assert "column" in t.nodes["a"].feedback_message


def test_bad_script_is_refused_at_validate_with_its_column() -> None:
    text = (
        '<root BTCPP_format="4"><BehaviorTree>\n'
        '<Script name="a" code="x := (1 + "/></BehaviorTree></root>'
    )
    with pytest.raises(TreeFileError, match=r"bad\.xml:2: .*attribute 'code': column \d+ in the"):
        load_tree_string(text, "bad.xml")


def test_precondition_checks_once_on_entry() -> None:
    t = Ticker(
        '<Sequence name="s"><Script name="w" code="go := true"/>'
        f'<Precondition name="p" if="go" else="FAILURE">{leaf("a", "R,R,S")}</Precondition>'
        "</Sequence>"
    )
    t.run(("p", "a"), [(R, R)])
    py_trees.blackboard.Blackboard.set("/go", False)  # not checked again while a runs
    t.tick("p")
    t.run(("p", "a"), [(S, S)])


def test_precondition_else_status() -> None:
    t = Ticker(f'<Precondition name="p" if="false" else="SUCCESS">{leaf("a", "F")}</Precondition>')
    t.run(("p", "a"), [(S, INV)])


def test_failure_if_then_success_if_then_skip_if_in_that_order() -> None:
    both = '_failureIf="true" _successIf="true"'
    t = Ticker(f'<Sequence name="s">{leaf("a", "S", both)}</Sequence>')
    t.run(("s", "a"), [(F, F)])
    assert t.nodes["a"].ticks == 0
    t2 = Ticker('<Sequence name="s">' + leaf("a", "F", SUCCESS_AND_SKIP) + "</Sequence>")
    t2.run(("a",), [(S,)])


def test_skip_if_lets_a_sequence_and_a_fallback_carry_on() -> None:
    t = Ticker('<Sequence name="s">' + leaf("a", "F", SKIP) + leaf("b", "S") + "</Sequence>")
    t.run(("s",), [(S,)])
    assert t.nodes["a"].ticks == 0
    t2 = Ticker('<Fallback name="f">' + leaf("a", "S", SKIP) + leaf("b", "F") + "</Fallback>")
    t2.run(("f",), [(F,)])


def test_a_control_node_whose_children_are_all_skipped_is_skipped_itself() -> None:
    # BT.CPP v4: a Fallback of optional branches, each skipped, is SKIPPED, and the Sequence
    # above carries on (it had failed the Sequence: a Fallback of failures).
    optional = '<Fallback name="f">' + leaf("a", "S", SKIP) + leaf("b", "S", SKIP) + "</Fallback>"
    t = Ticker('<Sequence name="s">' + optional + leaf("c", "S") + "</Sequence>")
    t.run(("s", "f", "c"), [(S, S, S)])
    assert t.nodes["a"].ticks == t.nodes["b"].ticks == 0
    # A Sequence of skipped children in a Fallback is skipped there: the Fallback moves on.
    inner = '<Sequence name="q">' + leaf("a", "F", SKIP) + "</Sequence>"
    t2 = Ticker('<Fallback name="f">' + inner + leaf("b", "S") + "</Fallback>")
    t2.run(("f", "q", "b"), [(S, F, S)])
    # An Inverter over a skipped child is skipped, not inverted.
    t3 = Ticker(
        '<Sequence name="s"><Inverter name="i">' + leaf("a", "S", SKIP) + "</Inverter>"
        + leaf("b", "S") + "</Sequence>"
    )  # fmt: skip
    t3.run(("s", "i", "b"), [(S, S, S)])
    # One child that ran decides as before.
    t4 = Ticker('<Fallback name="f">' + leaf("a", "S", SKIP) + leaf("b", "F") + "</Fallback>")
    t4.run(("f",), [(F,)])


def test_while_halts_a_running_node_when_it_turns_false() -> None:
    t = Ticker(
        '<Sequence name="s"><Script name="w" code="on := true"/>'
        + leaf("a", "R", WHILE_ON)
        + "</Sequence>"
    )
    t.run(("s", "a"), [(R, R)])
    py_trees.blackboard.Blackboard.set("/on", False)
    t.run(("a",), [(S,)])  # SKIPPED under a Sequence
    assert t.nodes["a"].halts == 1
    assert get("/halted") == 1


def test_success_if_is_not_checked_while_running() -> None:
    t = Ticker(
        '<Sequence name="s"><Script name="w" code="done := false"/>'
        + leaf("a", "R,R,F", "_successIf='done'")
        + "</Sequence>"
    )
    t.run(("a",), [(R,)])
    py_trees.blackboard.Blackboard.set("/done", True)
    t.run(("a",), [(R,), (F,)])


def test_on_success_on_failure_and_post() -> None:
    attrs = '_onSuccess="ok := 1" _onFailure="bad := 1" _post="n := 7"'
    t = Ticker(f'<Fallback name="f">{leaf("a", "R,F", attrs)}{leaf("b", "S")}</Fallback>')
    t.run(("a",), [(R,)])
    assert not py_trees.blackboard.Blackboard.exists("/n")
    t.run(("a",), [(F,)])
    assert (get("/bad"), get("/n")) == (1, 7)
    assert not py_trees.blackboard.Blackboard.exists("/ok")


def test_conditions_on_a_control_and_a_decorator() -> None:
    t = Ticker(
        '<Sequence name="s">'
        f'<Sequence name="inner" _onSuccess="seq := 1">{leaf("a", "S")}</Sequence>'
        f'<Inverter name="inv" _failureIf="seq == 1">{leaf("b", "F")}</Inverter></Sequence>'
    )
    t.run(("s", "inner", "inv", "b"), [(F, S, F, INV)])


def test_conditions_on_a_subtree_use_the_callers_keys() -> None:
    text = (
        '<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T"><Sequence name="s">'
        '<Script name="w" code="skip := true"/><SubTree ID="Sub" name="sub" _skipIf="skip"/>'
        f"{leaf('b', 'S')}</Sequence></BehaviorTree>"
        f'<BehaviorTree ID="Sub">{leaf("a", "F")}</BehaviorTree></root>'
    )
    root = load_tree_string(text, "sub.xml")
    root.tick_once()
    assert root.status == S
    assert next(n for n in root.iterate() if n.name.endswith(".a")).ticks == 0


def test_a_condition_that_cannot_run_fails_the_node() -> None:
    t = Ticker(leaf("a", "S", '_skipIf="nothere"'))
    t.run(("a",), [(F,)])
    assert "nothere" in t.nodes["a"].feedback_message


def test_precondition_else_must_be_a_status() -> None:
    with pytest.raises(TreeFileError, match="attribute 'else': expected SUCCESS, FAILURE or"):
        Ticker(f'<Precondition name="p" if="true" else="MAYBE">{leaf("a", "S")}</Precondition>')


def test_registered_enum_names_read_as_integers_and_win_over_a_key() -> None:
    register_script_enums({"RED": 1, "BLUE": 2}, "test")
    try:
        py_trees.blackboard.Blackboard.set("/BLUE", 7)
        t = Ticker(
            '<Sequence name="s"><Script name="a" code="c := BLUE; r := RED + 1"/>'
            '<ScriptCondition name="is" code="c == 2"/></Sequence>'
        )
        t.run(("s", "is"), [(S, S)])
        assert (get("/c"), get("/r")) == (2, 2)
    finally:
        clear_script_enums()
    t2 = Ticker('<Script name="a" code="c := RED"/>')
    t2.run(("a",), [(F,)])
    assert "variable 'RED' not found on the blackboard" in t2.nodes["a"].feedback_message


def test_on_failure_runs_before_the_fallback_ticks_its_next_child() -> None:
    # The next branch reads what the failed one's _onFailure wrote, in the same tick, also
    # when the failed leaf sits in a Sequence (which stops at it and never resumes it).
    t = Ticker(
        '<Fallback name="f"><Sequence name="s">'
        + leaf("a", "F", '_onFailure="refused := true"')
        + '</Sequence><ScriptCondition name="b" code="refused == true"/></Fallback>'
    )
    t.run(("f", "s", "a", "b"), [(S, F, F, S)])


def test_on_success_runs_before_the_sequence_ticks_its_next_child_and_not_while_running() -> None:
    t = Ticker(
        '<Sequence name="s"><Sequence name="inner">'
        + leaf("a", "R,S", '_onSuccess="n := 1" _post="m := 2"')
        + '</Sequence><ScriptCondition name="b" code="n + m == 3"/></Sequence>'
    )
    t.run(("s", "a"), [(R, R)])
    assert not py_trees.blackboard.Blackboard.exists("/n")
    assert not py_trees.blackboard.Blackboard.exists("/m")
    t.run(("s", "a", "b"), [(S, S, S)])
