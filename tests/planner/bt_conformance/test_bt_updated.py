"""BT.CPP WasEntryUpdated, SkipUnlessUpdated and WaitValueUpdate: writes counted by stamp."""

from __future__ import annotations

import py_trees
import pytest

from planner import bt_entry_stamps
from planner.loader import TreeFileError, load_tree_string
from planner.validate import validate_tree_string
from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker

Blackboard = py_trees.blackboard.Blackboard
Behaviour = py_trees.behaviour.Behaviour


def leaf(name: str, script: str) -> str:
    return f'<StubScripted name="{name}" script="{script}"/>'


def test_was_entry_updated_fails_on_a_missing_entry_then_sees_each_write_once() -> None:
    t = Ticker('<WasEntryUpdated name="u" entry="{a}"/>')
    t.run(("u",), [(F,)])
    Blackboard.set("/a", 1)
    t.run(("u",), [(S,), (F,)])
    Blackboard.set("/a", 1)  # the same value written again is a write
    t.run(("u",), [(S,), (F,)])


def test_an_entry_written_before_the_first_tick_is_updated_at_the_first_tick() -> None:
    Blackboard.set("/a", 1)
    t = Ticker('<WasEntryUpdated name="u" entry="a"/>')  # BT.CPP also takes the key bare
    t.run(("u",), [(S,), (F,)])


def test_two_nodes_watching_one_entry_each_see_the_write() -> None:
    t = Ticker(
        '<Sequence name="q"><Script name="w" code="a := 1"/>'
        '<WasEntryUpdated name="u1" entry="{a}"/><WasEntryUpdated name="u2" entry="{a}"/>'
        "</Sequence>"
    )
    t.run(("q", "u1", "u2"), [(S, S, S), (S, S, S)])  # the script writes it every tick


def test_set_blackboard_and_output_ports_count_as_writes() -> None:
    t = Ticker(
        '<Sequence name="q">'
        '<Fallback name="f"><WasEntryUpdated name="u" entry="{a}"/>'
        '<AlwaysSuccess name="none"/></Fallback>'
        '<SetBlackboard name="set" value="7" output_key="a"/></Sequence>'
    )
    # Tick 1: no entry yet (FAILURE), then SetBlackboard writes it; each next tick sees the
    # write of the tick before.
    t.run(("u", "set"), [(F, S), (S, S), (S, S)])
    Blackboard.set("/n", 0)
    t2 = Ticker(
        '<Sequence name="q"><WasEntryUpdated name="u" entry="{n}"/>'
        '<StubCounter name="c" ticks="1" count="{n}"/></Sequence>'
    )
    t2.run(("u", "c"), [(S, S), (S, S)])  # the counter's output port writes {n} each tick


def _loaded(text: str) -> tuple[py_trees.trees.BehaviourTree, dict[str, Behaviour]]:
    tree = py_trees.trees.BehaviourTree(load_tree_string(text))
    tree.setup()
    return tree, {n.name.rsplit(".", 1)[-1]: n for n in tree.root.iterate()}


def test_a_write_inside_a_subtree_counts_for_the_callers_key() -> None:
    tree, nodes = _loaded(
        '<root BTCPP_format="4" main_tree_to_execute="Main">'
        '<BehaviorTree ID="Main"><Sequence name="q">'
        '<ForceSuccess name="fs"><WasEntryUpdated name="before" entry="{x}"/></ForceSuccess>'
        '<SubTree ID="W" name="w" out="{x}"/>'
        '<WasEntryUpdated name="after" entry="{x}"/></Sequence></BehaviorTree>'
        '<BehaviorTree ID="W"><SetBlackboard name="s" value="3" output_key="{out}"/>'
        "</BehaviorTree></root>"
    )
    tree.tick()
    assert (nodes["before"].status, nodes["after"].status) == (F, S)
    assert Blackboard.get("/x") == "3"


def test_a_root_key_watched_from_a_subtree_sees_the_runs_own_write() -> None:
    tree, nodes = _loaded(
        '<root BTCPP_format="4" main_tree_to_execute="Main">'
        '<BehaviorTree ID="Main"><SubTree ID="C" name="c"/></BehaviorTree>'
        '<BehaviorTree ID="C"><WasEntryUpdated name="u" entry="{@object}"/></BehaviorTree>'
        "</root>"
    )
    tree.tick()
    assert nodes["u"].status == F
    Blackboard.set("/object", "parcel")  # as the runner seeds {object}
    tree.tick()
    assert nodes["u"].status == S


def test_a_removed_then_rewritten_entry_is_updated() -> None:
    t = Ticker(
        '<Sequence name="q"><WasEntryUpdated name="u" entry="{a}"/>'
        '<UnsetBlackboard name="x" key="a"/></Sequence>'
    )
    Blackboard.set("/a", 1)
    t.run(("u", "x"), [(S, S), (F, INV)])
    Blackboard.set("/a", 1)
    t.run(("u", "x"), [(S, S)])


def test_skip_unless_updated_ticks_its_child_only_after_a_write() -> None:
    t = Ticker(
        '<Sequence name="q"><SkipUnlessUpdated name="k" entry="{a}">'
        f"{leaf('c', 'S')}</SkipUnlessUpdated>{leaf('after', 'S')}</Sequence>"
    )
    # No entry: SKIPPED, given as SUCCESS in a Sequence (the sequence carries on).
    t.run(("q", "k", "c", "after"), [(S, S, INV, S)])
    Blackboard.set("/a", 1)
    t.run(("k", "c"), [(S, S), (S, INV)])
    assert t.nodes["c"].ticks == 1


def test_skip_unless_updated_under_a_fallback_lets_the_fallback_move_on() -> None:
    t = Ticker(
        '<Fallback name="f"><SkipUnlessUpdated name="k" entry="{a}">'
        f"{leaf('c', 'S')}</SkipUnlessUpdated>{leaf('other', 'S')}</Fallback>"
    )
    t.run(("f", "k", "c", "other"), [(S, F, INV, S)])


def test_skip_unless_updated_keeps_ticking_a_running_child_without_looking_again() -> None:
    Blackboard.set("/a", 1)
    t = Ticker(
        f'<SkipUnlessUpdated name="k" entry="{{a}}">{leaf("c", "R,R,F")}</SkipUnlessUpdated>'
    )
    t.run(("k", "c"), [(R, R), (R, R), (F, F), (S, F)])
    assert t.nodes["c"].ticks == 3


def test_skip_unless_updated_halted_looks_again_and_keeps_what_it_saw() -> None:
    t = Ticker(
        '<ReactiveSequence name="q">'
        f"{leaf('gate', 'S,F,S')}"
        f'<SkipUnlessUpdated name="k" entry="{{a}}">{leaf("c", "R")}</SkipUnlessUpdated>'
        "</ReactiveSequence>"
    )
    Blackboard.set("/a", 1)
    # Tick 2 halts the running child; tick 3 looks again: no write since, so it skips.
    t.run(("q", "k", "c"), [(R, R, R), (F, INV, INV), (S, S, INV)])
    assert t.nodes["c"].halts == 1


def test_wait_value_update_is_running_until_a_write() -> None:
    t = Ticker(f'<WaitValueUpdate name="w" entry="{{a}}">{leaf("c", "S")}</WaitValueUpdate>')
    t.run(("w", "c"), [(R, INV), (R, INV)])
    Blackboard.set("/a", 2)
    t.run(("w", "c"), [(S, S), (R, S)])


CHECK = (
    '<BehaviorTree ID="Check"><Sequence name="check">'
    '<Fallback name="f"><WasEntryUpdated name="was" entry="A"/>'
    '<StubScripted name="test_a" script="S"/></Fallback>'
    '<SkipUnlessUpdated name="skip" entry="A"><StubScripted name="test_b" script="S"/>'
    "</SkipUnlessUpdated></Sequence></BehaviorTree>"
)


@pytest.mark.parametrize(
    ("main", "ticks_a", "ticks_b"),
    [
        # Nothing writes A: the fallback runs test_a, test_b is skipped.
        ('<Sequence name="m"><SubTree ID="Check" name="c" _autoremap="true"/></Sequence>', 1, 0),
        (
            '<Sequence name="m"><Script name="s" code="A:=1;B:=1"/>'
            '<SubTree ID="Check" name="c" _autoremap="true"/></Sequence>',
            0,
            1,
        ),
        # Written once, checked twice: the second look sees no update.
        (
            '<Sequence name="m"><Script name="s" code="A:=1"/><Repeat name="r" num_cycles="2">'
            '<SubTree ID="Check" name="c" _autoremap="true"/></Repeat></Sequence>',
            1,
            1,
        ),
        # Written before each check.
        (
            '<Repeat name="r" num_cycles="2"><Sequence name="m"><Script name="s" code="A:=1"/>'
            '<SubTree ID="Check" name="c" _autoremap="true"/></Sequence></Repeat>',
            0,
            2,
        ),
    ],
)
def test_updates_through_an_autoremapped_subtree(main: str, ticks_a: int, ticks_b: int) -> None:
    tree, nodes = _loaded(
        f'<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Main">{main}'
        f"</BehaviorTree>{CHECK}</root>"
    )
    for _ in range(5):
        tree.tick()
        if tree.root.status != R:
            break
    assert tree.root.status == S
    assert (nodes["test_a"].ticks, nodes["test_b"].ticks) == (ticks_a, ticks_b)


def test_the_validator_takes_a_watched_key_nothing_writes_and_needs_the_entry() -> None:
    ok = (
        '<root BTCPP_format="4"><BehaviorTree><WasEntryUpdated name="u" entry="{never}"/>'
        "</BehaviorTree></root>"
    )
    assert validate_tree_string(ok, run_keys=frozenset()) == []
    missing = (
        '<root BTCPP_format="4"><BehaviorTree><WasEntryUpdated name="u"/></BehaviorTree></root>'
    )
    assert [p.message for p in validate_tree_string(missing)] == [
        "missing required input port 'entry' (object); give a literal or a blackboard key "
        "such as {entry}"
    ]
    with pytest.raises(TreeFileError, match="missing required input port 'entry'"):
        Ticker('<SkipUnlessUpdated name="k"><AlwaysSuccess name="a"/></SkipUnlessUpdated>')


def test_stamps_survive_a_plain_storage_dict_put_back() -> None:
    Blackboard.set("/a", 1)
    t = Ticker('<WasEntryUpdated name="u" entry="{a}"/>')
    t.run(("u",), [(S,), (F,)])
    # py_trees.tests.clear_blackboard replaces the storage with a plain dict.
    Blackboard.storage = {"/a": 1}
    t.run(("u",), [(S,), (F,)])
    assert isinstance(Blackboard.storage, bt_entry_stamps.StampedStorage)
