"""BT.CPP built-in leaves: AlwaysSuccess, AlwaysFailure, Sleep (simulated ms), SetBlackboard,
UnsetBlackboard."""

from __future__ import annotations

import py_trees
import pytest
from py_trees.common import Status

from planner.loader import TreeFileError
from tests.planner.bt_conformance.conftest import INV, F, R, S, Ticker


def test_always_success_and_failure() -> None:
    t = Ticker(
        '<Sequence name="s"><AlwaysSuccess name="a"/><AlwaysFailure name="b"/>'
        '<StubScripted name="c" script="S"/></Sequence>'
    )
    t.run(("s", "a", "b", "c"), [(F, S, F, INV), (F, S, F, INV)])


def test_always_success_is_not_mistaken_for_a_decorator() -> None:
    Ticker('<AlwaysSuccess name="a"/>')  # no "did you mean FailureIsSuccess"


def test_always_failure_takes_no_ports() -> None:
    with pytest.raises(TreeFileError, match="unknown port 'speed'"):
        Ticker('<AlwaysFailure name="a" speed="2"/>')


def test_sleep_runs_for_its_simulated_milliseconds() -> None:
    t = Ticker('<Sleep name="z" msec="250"/>', dt=0.1)  # ticks at t = 0, .1, .2, .3
    t.run(("z",), [(R,), (R,), (R,), (S,)])


def test_sleep_restarts_after_a_halt() -> None:
    t = Ticker(
        '<ReactiveFallback name="f"><StubScripted name="c" script="F,S,F"/>'
        '<Sleep name="z" msec="150"/></ReactiveFallback>',
        dt=0.1,
    )
    # t=0 sleep starts; t=.1 the condition succeeds and halts it; t=.2 it starts afresh.
    t.run(("f", "z"), [(R, R), (S, INV), (R, R), (R, R), (S, S)])


def test_sleep_msec_from_the_blackboard() -> None:
    t = Ticker(
        '<Sequence name="s"><SetBlackboard name="w" value="100" output_key="{ms}"/>'
        '<Sleep name="z" msec="{ms}"/></Sequence>',
        dt=0.1,
    )
    t.run(("s", "z"), [(R, R), (S, S)])


def test_sleep_rejects_a_non_integer() -> None:
    with pytest.raises(TreeFileError, match="port 'msec': cannot convert 'soon' to int"):
        Ticker('<Sleep name="z" msec="soon"/>')


@pytest.mark.parametrize("key", ["answer", "{answer}"])
def test_set_blackboard_writes_a_literal(key: str) -> None:
    t = Ticker(f'<SetBlackboard name="w" value="42" output_key="{key}"/>')
    t.run(("w",), [(S,)])
    assert py_trees.blackboard.Blackboard.get("/answer") == "42"


def test_set_blackboard_without_its_output_key_is_refused() -> None:
    # BT.CPP's SetBlackboard throws "missing port [output_key]" at its first tick.
    with pytest.raises(TreeFileError, match="missing required output port 'output_key'"):
        Ticker('<SetBlackboard name="w" value="42"/>')


def test_set_blackboard_copies_another_key_and_unset_removes_it() -> None:
    t = Ticker(
        '<Sequence name="s"><SetBlackboard name="a" value="7" output_key="src"/>'
        '<SetBlackboard name="b" value="{src}" output_key="dst"/>'
        '<UnsetBlackboard name="u" key="src"/></Sequence>'
    )
    t.run(("s", "a", "b", "u"), [(S, S, S, S)])
    assert py_trees.blackboard.Blackboard.get("/dst") == "7"
    assert not py_trees.blackboard.Blackboard.exists("/src")


def test_a_robot_leaf_reads_a_set_blackboard_string_as_its_ports_type() -> None:
    # BT.CPP converts a string entry when a port of another type reads it; the robot's leaves
    # did not, and a tree the checks accepted failed mid-run (TypeError on Approach).
    import planner.leaves  # noqa: F401  (registers the robot's leaves)
    from planner.loader import load_tree_string

    root = load_tree_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>'
        '<SetBlackboard value="0.05" output_key="standoff"/>'
        '<Approach name="in" object="parcel" standoff_m="{standoff}"/>'
        "</Sequence></BehaviorTree></root>"
    )
    approach = next(n for n in root.iterate() if n.name == "in")
    py_trees.blackboard.Blackboard.set("/standoff", "0.05")
    assert approach.get_input("standoff_m") == pytest.approx(0.05)
    assert isinstance(approach.get_input("standoff_m"), float)
    py_trees.blackboard.Blackboard.set("/standoff", "near")
    with pytest.raises(TypeError, match="port 'standoff_m': cannot convert 'near' to float"):
        approach.get_input("standoff_m")


def test_set_blackboard_copies_a_non_string_entry_as_it_is() -> None:
    # BT.CPP: value="{src}" copies the entry's type and content. The port had been typed str,
    # and a script's number copied so raised a TypeError out of the tick (exit 1, a traceback).
    t = Ticker(
        '<Sequence name="s"><Script name="a" code="n := 42"/>'
        '<SetBlackboard name="b" value="{n}" output_key="m"/></Sequence>'
    )
    t.run(("s", "b"), [(S, S)])
    assert py_trees.blackboard.Blackboard.get("/m") == 42


@pytest.mark.parametrize(
    ("script", "node"),
    [
        ("t := 1000 / 4", '<Sleep name="z" msec="{t}"/>'),  # 250.0: a script's / is a double
        ("t := 250", '<Sleep name="z" msec="{t}"/>'),
        ("t := 500 / 2", '<Delay name="z" delay_msec="{t}"><AlwaysSuccess/></Delay>'),
        ("t := 600 / 2", '<Timeout name="z" msec="{t}"><Sleep msec="1000"/></Timeout>'),
    ],
)
def test_a_scripts_whole_double_times_a_node_as_bt_cpp_reads_it(script: str, node: str) -> None:
    t = Ticker(f'<Sequence name="s"><Script name="a" code="{script}"/>{node}</Sequence>', dt=0.1)
    statuses = [t.tick("z")[0] for _ in range(5)]
    # Sleep 250 ms and Delay 250 ms succeed at the fourth tick (t = 0.3 s); Timeout 300 ms
    # fails its child there.
    assert statuses[:3] == [R, R, R] and statuses[3] in (S, F)


@pytest.mark.parametrize(
    ("script", "node", "done"),
    [
        ("n := 4 / 2", '<Repeat name="z" num_cycles="{n}"><AlwaysSuccess/></Repeat>', S),
        (
            "n := 2.0",
            '<RetryUntilSuccessful name="z" num_attempts="{n}"><AlwaysFailure/>'
            "</RetryUntilSuccessful>",
            F,
        ),
    ],
)
def test_a_scripts_whole_double_counts_a_loop(script: str, node: str, done: Status) -> None:
    t = Ticker(f'<Sequence name="s"><Script name="a" code="{script}"/>{node}</Sequence>')
    t.run(("z",), [(R,), (done,)])  # a cycle, an attempt a tick: two of them


def test_a_fraction_where_a_count_is_read_names_the_node_port_and_value() -> None:
    from planner.tree_problems import PortValueError

    t = Ticker(
        '<Sequence name="s"><Script name="a" code="t := 1 / 3"/>'
        '<Sleep name="z" msec="{t}"/></Sequence>'
    )
    says = r"port 'msec': cannot convert 0\.333\d* \(float\) to int"
    with pytest.raises(PortValueError, match=says):
        t.tick("z")
