"""BT.CPP Switch2..Switch6 and AsyncSequence/AsyncFallback."""

from __future__ import annotations

import py_trees
import pytest

from planner.loader import TreeFileError
from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker


def leaf(name: str, script: str) -> str:
    return f'<StubScripted name="{name}" script="{script}"/>'


def test_switch_ticks_the_matching_case_and_halts_the_one_no_longer_chosen() -> None:
    t = Ticker(
        f'<Switch2 name="w" variable="{{mode}}" case_1="1" case_2="walk">{leaf("one", "R")}'
        f"{leaf('walk', 'R')}{leaf('default', 'S')}</Switch2>"
    )
    bb = py_trees.blackboard.Client(name="test")
    bb.register_key("/mode", access=py_trees.common.Access.WRITE)
    bb.set("/mode", 1.0)  # compares as a number with case_1="1"
    t.run(("w", "one", "walk"), [(R, R, INV)])
    bb.set("/mode", "walk")
    t.run(("w", "one", "walk"), [(R, INV, R)])
    assert t.nodes["one"].halts == 1
    bb.set("/mode", "swim")
    t.run(("w", "walk", "default"), [(S, INV, S)])
    assert t.nodes["walk"].halts == 1


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6])
def test_switch_n_takes_n_cases_and_a_default(n: int) -> None:
    cases = " ".join(f'case_{i}="{i}"' for i in range(1, n + 1))
    kids = "".join(leaf(f"c{i}", "S") for i in range(n + 1))
    t = Ticker(f'<Switch{n} name="w" variable="{n}" {cases}>{kids}</Switch{n}>')
    t.run(("w", f"c{n - 1}", f"c{n}"), [(S, S, INV)])
    with pytest.raises(TreeFileError, match=f"a Switch{n} node takes exactly {n + 1} child"):
        Ticker(f'<Switch{n} name="w" variable="1" {cases}>{kids}{leaf("x", "S")}</Switch{n}>')


def test_async_sequence_gives_the_tick_back_after_each_success() -> None:
    t = Ticker(
        f'<AsyncSequence name="q">{leaf("a", "S")}{leaf("b", "R,S")}{leaf("c", "S")}'
        "</AsyncSequence>"
    )
    t.run(("q", "a", "b", "c"), [(R, S, INV, INV), (R, S, R, INV), (R, S, S, INV), (S, S, S, S)])


def test_async_sequence_fails_with_a_child() -> None:
    t = Ticker(f'<AsyncSequence name="q">{leaf("a", "S")}{leaf("b", "F")}</AsyncSequence>')
    t.run(("q", "b"), [(R, INV), (F, F)])


def test_async_fallback_gives_the_tick_back_after_each_failure() -> None:
    t = Ticker(f'<AsyncFallback name="q">{leaf("a", "F")}{leaf("b", "S")}</AsyncFallback>')
    t.run(("q", "a", "b"), [(R, F, INV), (S, F, S)])
