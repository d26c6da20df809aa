"""BT.CPP control nodes, status of each node at each tick, halts included."""

from __future__ import annotations

import py_trees
import pytest

from planner.loader import TreeFileError
from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker


def leaf(name: str, script: str) -> str:
    return f'<StubScripted name="{name}" script="{script}"/>'


def test_sequence_with_memory_skips_succeeded_children_and_keeps_its_place_on_failure() -> None:
    t = Ticker(
        f'<SequenceWithMemory name="q">{leaf("a", "S")}{leaf("b", "R,F,S")}</SequenceWithMemory>'
    )
    t.run(("q", "a", "b"), [(R, S, R), (F, S, F), (S, S, S)])
    # After the failure the next tick went on at b: a was ticked only once.
    assert (t.nodes["a"].ticks, t.nodes["b"].ticks) == (1, 3)


def test_reactive_sequence_halts_a_running_later_child_when_an_earlier_one_fails() -> None:
    t = Ticker(f'<ReactiveSequence name="q">{leaf("a", "S,F")}{leaf("b", "R")}</ReactiveSequence>')
    t.run(("q", "a", "b"), [(R, S, R), (F, F, INV)])
    assert t.nodes["b"].halts == 1


def test_if_then_else_is_not_reactive() -> None:
    t = Ticker(
        f'<IfThenElse name="i">{leaf("c", "S,F")}{leaf("then", "R,R,S")}{leaf("else", "S")}'
        "</IfThenElse>"
    )
    # The condition is ticked once; the then-branch runs to its end although c would fail now.
    t.run(("i", "c", "then", "else"), [(R, S, R, INV), (R, S, R, INV), (S, S, S, INV)])
    assert t.nodes["c"].ticks == 1


def test_if_then_else_takes_the_else_branch_or_fails_without_one() -> None:
    t = Ticker(
        f'<IfThenElse name="i">{leaf("c", "F")}{leaf("then", "S")}{leaf("else", "R,F")}'
        "</IfThenElse>"
    )
    t.run(("i", "then", "else"), [(R, INV, R), (F, INV, F)])
    t2 = Ticker(f'<IfThenElse name="i">{leaf("c", "F")}{leaf("then", "S")}</IfThenElse>')
    t2.run(("i", "then"), [(F, INV)])


def test_while_do_else_halts_the_branch_no_longer_selected() -> None:
    t = Ticker(
        f'<WhileDoElse name="w">{leaf("c", "S,S,F,F")}{leaf("do", "R")}{leaf("else", "R,S")}'
        "</WhileDoElse>"
    )
    t.run(("w", "do", "else"), [(R, R, INV), (R, R, INV), (R, INV, R), (S, INV, S)])
    assert t.nodes["do"].halts == 1


def test_while_do_else_with_two_children_fails_and_halts_on_a_false_condition() -> None:
    t = Ticker(f'<WhileDoElse name="w">{leaf("c", "S,F")}{leaf("do", "R")}</WhileDoElse>')
    t.run(("w", "do"), [(R, R), (F, INV)])
    assert t.nodes["do"].halts == 1


@pytest.mark.parametrize("tag", ["IfThenElse", "WhileDoElse"])
def test_if_and_while_take_two_or_three_children(tag: str) -> None:
    with pytest.raises(TreeFileError, match=f"a {tag} node takes at most 3 children, found 4"):
        Ticker(
            f'<{tag} name="i">{leaf("a", "S")}{leaf("b", "S")}{leaf("c", "S")}{leaf("d", "S")}'
            f"</{tag}>"
        )
    with pytest.raises(TreeFileError, match=f"a {tag} node needs at least 2 child, found 1"):
        Ticker(f'<{tag} name="i">{leaf("a", "S")}</{tag}>')


def test_try_catch_runs_the_catch_after_a_failure_and_fails() -> None:
    t = Ticker(
        f'<TryCatch name="t">{leaf("a", "S")}{leaf("b", "R,F")}{leaf("catch", "R,S")}</TryCatch>'
    )
    t.run(("t", "a", "b", "catch"), [(R, S, R, INV), (R, S, F, R), (F, S, F, S)])


def test_try_catch_succeeds_without_running_the_catch() -> None:
    t = Ticker(f'<TryCatch name="t">{leaf("a", "R,S")}{leaf("catch", "S")}</TryCatch>')
    t.run(("t", "a", "catch"), [(R, R, INV), (S, S, INV)])
    assert t.nodes["catch"].ticks == 0


def _halted_try_catch(catch_on_halt: str, tries: str, catch: str) -> Ticker:
    """A TryCatch under a ReactiveSequence whose gate fails at the second tick (a halt)."""
    attr = f' catch_on_halt="{catch_on_halt}"' if catch_on_halt else ""
    return Ticker(
        f'<ReactiveSequence name="q">{leaf("gate", "S,F")}'
        f'<TryCatch name="t"{attr}>{leaf("a", tries)}{leaf("catch", catch)}</TryCatch>'
        "</ReactiveSequence>"
    )


def test_try_catch_halted_in_its_try_block_runs_the_catch_once_with_catch_on_halt() -> None:
    t = _halted_try_catch("true", "R", "S")
    t.run(("q", "t", "a", "catch"), [(R, R, R, INV), (F, INV, INV, INV)])
    assert (t.nodes["a"].halts, t.nodes["catch"].ticks, t.nodes["catch"].halts) == (1, 1, 0)


def test_try_catch_on_halt_halts_a_catch_still_running_after_its_one_tick() -> None:
    t = _halted_try_catch("true", "R", "R")
    t.run(("q", "t", "a", "catch"), [(R, R, R, INV), (F, INV, INV, INV)])
    assert (t.nodes["catch"].ticks, t.nodes["catch"].halts) == (1, 1)


@pytest.mark.parametrize("flag", ["", "false"])
def test_try_catch_halted_without_catch_on_halt_never_runs_the_catch(flag: str) -> None:
    t = _halted_try_catch(flag, "R", "S")
    t.run(("q", "t", "a", "catch"), [(R, R, R, INV), (F, INV, INV, INV)])
    assert (t.nodes["a"].halts, t.nodes["catch"].ticks) == (1, 0)


def test_try_catch_halted_in_its_catch_halts_the_catch_without_ticking_it_again() -> None:
    t = _halted_try_catch("true", "F", "R")
    t.run(("q", "t", "a", "catch"), [(R, R, F, R), (F, INV, INV, INV)])
    assert (t.nodes["catch"].ticks, t.nodes["catch"].halts) == (1, 1)


def test_try_catch_on_halt_from_a_key() -> None:
    py_trees.blackboard.Blackboard.set("/clean", "true")
    t = _halted_try_catch("{clean}", "R", "S")
    t.run(("q", "t"), [(R, R), (F, INV)])
    assert t.nodes["catch"].ticks == 1


def test_parallel_all_waits_for_every_child_then_counts_failures() -> None:
    t = Ticker(
        f'<ParallelAll name="p" max_failures="2">{leaf("a", "F")}{leaf("b", "R,S")}'
        f"{leaf('c', 'R,R,F')}</ParallelAll>"
    )
    t.run(("p", "a", "b", "c"), [(R, F, R, R), (R, F, S, R), (F, F, S, F)])
    assert t.nodes["a"].ticks == 1  # a finished child is not ticked again


def test_parallel_all_succeeds_below_max_failures() -> None:
    t = Ticker(
        f'<ParallelAll name="p" max_failures="2">{leaf("a", "F")}{leaf("b", "S")}</ParallelAll>'
    )
    t.run(("p",), [(S,)])


def test_parallel_failure_count_above_one() -> None:
    t = Ticker(
        f'<Parallel name="p" success_count="1" failure_count="2">{leaf("a", "F")}'
        f"{leaf('b', 'R,F')}{leaf('c', 'R')}</Parallel>"
    )
    # One failure is tolerated; the second ends it: c is not ticked again, and halted.
    t.run(("p", "a", "b", "c"), [(R, F, R, R), (F, F, F, INV)])
    assert (t.nodes["c"].halts, t.nodes["c"].ticks) == (1, 1)


def test_parallel_with_all_needed_fails_at_the_first_failure() -> None:
    t = Ticker(
        f'<Parallel name="p" success_count="-1" failure_count="2">{leaf("a", "R,F")}'
        f"{leaf('b', 'R')}</Parallel>"
    )
    t.run(("p", "a", "b"), [(R, R, R), (F, F, INV)])


def test_parallel_success_count_two_of_three() -> None:
    t = Ticker(
        f'<Parallel name="p" success_count="2" failure_count="2">{leaf("a", "R,S")}'
        f"{leaf('b', 'R,R,S')}{leaf('c', 'R')}</Parallel>"
    )
    t.run(("p", "a", "b", "c"), [(R, R, R, R), (R, S, R, R), (S, S, S, INV)])


def test_parallel_fails_when_success_is_out_of_reach() -> None:
    t = Ticker(
        f'<Parallel name="p" success_count="3" failure_count="3">{leaf("a", "F")}'
        f"{leaf('b', 'R')}{leaf('c', 'R')}</Parallel>"
    )
    t.run(("p", "b"), [(F, INV)])


def test_parallel_counts_beyond_the_children_are_refused_at_validate() -> None:
    with pytest.raises(TreeFileError, match=r"'success_count': expected at most 2 \(the number"):
        Ticker(f'<Parallel name="p" success_count="5">{leaf("a", "S")}{leaf("b", "S")}</Parallel>')


def test_parallel_counts_from_the_blackboard_out_of_range_fail_the_node() -> None:
    t = Ticker(
        '<Sequence name="s"><SetBlackboard name="w" value="9" output_key="k"/>'
        f'<Parallel name="p" success_count="{{k}}">{leaf("a", "S")}{leaf("b", "S")}</Parallel>'
        "</Sequence>"
    )
    t.run(("p",), [(F,)])
    assert "expected at most 2 (the number of children)" in t.nodes["p"].feedback_message


def test_parallel_negative_counts_are_counted_from_all_but_one() -> None:
    # BT.CPP's ParallelNode: a negative threshold is children + threshold + 1 (-2: all but one).
    t = Ticker(
        f'<Parallel name="p" success_count="-2" failure_count="3">{leaf("a", "S")}'
        f"{leaf('b', 'R')}{leaf('c', 'S')}</Parallel>"
    )
    t.run(("p", "a", "b", "c"), [(S, S, INV, S)])
    assert t.nodes["b"].halts == 1
    t = Ticker(
        f'<Parallel name="p" success_count="-1" failure_count="-3">{leaf("a", "F")}'
        f"{leaf('b', 'R,F')}{leaf('c', 'R')}</Parallel>"
    )
    # -3 of 3 children is one failure: the first ends it.
    t.run(("p", "a", "b"), [(F, F, INV)])


def test_parallel_success_count_zero_succeeds_after_its_first_child() -> None:
    # BT.CPP decides after each child it ticks: 0 successes are reached at once.
    t = Ticker(
        f'<Parallel name="p" success_count="0" failure_count="2">{leaf("a", "R")}'
        f"{leaf('b', 'R')}</Parallel>"
    )
    t.run(("p", "a", "b"), [(S, INV, INV)])
    assert t.nodes["b"].ticks == 0
