"""load_tree: BT.CPP v4 spellings, subtrees, simulated-time Timeout, and errors that say where."""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.common import Status
from py_trees.ports import BehaviourWithPorts, PortInformation, get_ports_registry

from planner.decorators import SimTimeout
from planner.loader import TreeFileError, load_tree, load_tree_string
from tests.planner.stub_leaves import FakeClock, StubAt, StubCounter, StubFlaky

TREES = Path(__file__).resolve().parents[1] / "data" / "trees"
S, F, R, INV = Status.SUCCESS, Status.FAILURE, Status.RUNNING, Status.INVALID


def by_short_name(root: py_trees.behaviour.Behaviour) -> dict[str, py_trees.behaviour.Behaviour]:
    return {node.name.rsplit(".", 1)[-1]: node for node in root.iterate()}


def test_btcpp_spellings_build_py_trees_nodes() -> None:
    root = load_tree(TREES / "retry_timeout.xml")
    nodes = by_short_name(root)
    assert isinstance(root, py_trees.composites.Selector)  # Fallback
    assert isinstance(nodes["retry"], py_trees.decorators.Retry)
    assert nodes["retry"].num_failures == 3  # num_attempts
    assert isinstance(nodes["limit"], SimTimeout)
    assert nodes["limit"].duration == pytest.approx(0.5)  # msec="500"
    assert isinstance(nodes["give_up"], py_trees.decorators.Inverter)
    # The subtree instance name prefixes the nodes inside it.
    assert nodes["squeeze"].name == "root.attempt.grip.grip_seq.squeeze"


def test_subtree_retry_timeout_fallback_tick_by_tick_on_a_fake_clock() -> None:
    root = load_tree(TREES / "retry_timeout.xml")
    clock = FakeClock(dt=0.125)
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(clock=clock)
    n = by_short_name(root)
    order = ["squeeze", "held", "grip_seq", "flaky", "retry", "slow", "limit", "attempt"]
    order += ["never", "give_up", "root"]
    expected = [
        # t=0: the subtree grips; the flaky leaf fails its first attempt, Retry keeps running
        [S, S, S, F, R, INV, INV, R, INV, INV, R],
        # t=.125: second attempt succeeds; the Timeout starts its 0.5 s on the slow counter
        [S, S, S, S, S, R, R, R, INV, INV, R],
        [S, S, S, S, S, R, R, R, INV, INV, R],  # t=.25
        [S, S, S, S, S, R, R, R, INV, INV, R],  # t=.375
        [S, S, S, S, S, R, R, R, INV, INV, R],  # t=.5
        # t=.625: 0.5 s since the Timeout was entered: halt the counter, fail; Fallback recovers
        [S, S, S, S, S, INV, F, F, F, S, S],
    ]
    for tick, statuses in enumerate(expected):
        tree.tick()
        got = [n[name].status for name in order]
        assert got == statuses, f"tick {tick} (t={clock.now}): {dict(zip(order, got, strict=True))}"
        clock.advance()
    assert "timed out after 0.500 s" in n["limit"].feedback_message
    assert isinstance(n["slow"], StubCounter) and n["slow"].count == 5
    assert isinstance(n["flaky"], StubFlaky) and n["flaky"].attempts == 2
    # The subtree's force literal reached the leaf; its local key stays in its namespace.
    assert py_trees.blackboard.Blackboard.get("/grip/held") is True


def test_py_trees_spellings_and_list_ports() -> None:
    root = load_tree(TREES / "good_pytrees.xml")
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup()
    statuses = []
    for _ in range(3):
        tree.tick()
        statuses.append(root.status)
    assert statuses == [R, R, S]
    at = by_short_name(root)["at"]
    assert isinstance(at, StubAt)
    assert py_trees.blackboard.Blackboard.get("/where") == pytest.approx([0.1, 0.2, 0.3])


def test_explicit_node_form_reactive_nodes_and_parallel_counts() -> None:
    root = load_tree_string(
        """
        <root BTCPP_format="4">
          <BehaviorTree ID="Only">
            <Parallel name="par" success_count="1" failure_count="1">
              <ReactiveSequence name="rs">
                <Action ID="StubGrasp" name="grip" force_n="1.5"/>
              </ReactiveSequence>
              <ReactiveFallback name="rf">
                <Condition ID="StubCheck" name="check" value="true"/>
              </ReactiveFallback>
              <ForceSuccess name="fs"><StubCheck name="no" value="false"/></ForceSuccess>
              <Parallel name="all">
                <StubCheck name="yes" value="true"/>
              </Parallel>
            </Parallel>
          </BehaviorTree>
        </root>
        """
    )
    n = by_short_name(root)
    assert isinstance(root, py_trees.composites.Parallel)
    assert isinstance(root.policy, py_trees.common.ParallelPolicy.SuccessOnOne)
    # BT.CPP's default for a Parallel without success_count: all children must succeed.
    assert isinstance(n["all"], py_trees.composites.Parallel)
    assert isinstance(n["all"].policy, py_trees.common.ParallelPolicy.SuccessOnAll)
    assert isinstance(n["rs"], py_trees.composites.Sequence) and not n["rs"].memory
    assert isinstance(n["rf"], py_trees.composites.Selector) and not n["rf"].memory
    assert isinstance(n["fs"], py_trees.decorators.FailureIsSuccess)
    root.tick_once()
    assert [n[k].status for k in ("grip", "check", "no", "fs", "par")] == [S, S, F, S, S]


def test_includes_are_inlined_relative_to_the_including_file() -> None:
    root = load_tree(TREES / "include_main.xml")
    assert by_short_name(root)["squeeze"].name == "main.grip.squeeze"
    root.tick_once()
    assert root.status == S


def test_main_tree_can_be_chosen_and_a_single_tree_needs_no_main() -> None:
    text = """
        <root>
          <BehaviorTree ID="A"><StubCheck name="a" value="true"/></BehaviorTree>
          <BehaviorTree ID="B"><StubCheck name="b" value="false"/></BehaviorTree>
        </root>"""
    assert load_tree_string(text, main_tree_id="B").name == "b"
    single = '<root><BehaviorTree ID="A"><StubCheck name="a" value="true"/></BehaviorTree></root>'
    assert load_tree_string(single).name == "a"
    with pytest.raises(TreeFileError, match=r"cannot tell the main tree.*\(A, B\)"):
        load_tree_string(text)
    with pytest.raises(TreeFileError, match=r"main tree 'C' not found; expected one of .*A, B"):
        load_tree_string(text, main_tree_id="C")


@pytest.mark.parametrize(
    ("name", "pattern"),
    [
        (
            "bad_unknown_port.xml",
            r"bad_unknown_port\.xml:4: <StubGrasp name=\"grip\">: unknown port 'forse'; "
            r"expected one of force_n, holding, timeout_s$",
        ),
        (
            "bad_missing_port.xml",
            r"bad_missing_port\.xml:4: <StubCounter name=\"count\">: missing required input "
            r"port 'ticks' \(int\)",
        ),
        (
            "bad_port_type.xml",
            r"bad_port_type\.xml:4: <StubGrasp name=\"grip\">: port 'force_n': cannot convert "
            r"'strong' to float",
        ),
        ("bad_unknown_tag.xml", r"bad_unknown_tag\.xml:5: <StubGrsp name=\"typo\">: unknown node"),
        ("bad_unknown_subtree.xml", r"bad_unknown_subtree\.xml:7: .*unknown subtree 'Grap'"),
        ("bad_syntax.xml", r"bad_syntax\.xml:5:7: XML syntax error: mismatched tag$"),
        (
            "bad_decorator.xml",
            r"bad_decorator\.xml:8: <Timeout name=\"none\">: missing required attribute 'msec'",
        ),
        ("bad_main.xml", r"bad_main\.xml:1: <root>: main tree 'Mian' not found"),
        ("include_bad.xml", r"include_bad_grip\.xml:4: <StubGrasp name=\"squeeze\">: unknown port"),
        (
            "no_such_file.xml",
            r"no_such_file\.xml: expected a readable BehaviorTree\.CPP XML file, got no such file",
        ),
    ],
)
def test_errors_name_file_line_node_and_expectation(name: str, pattern: str) -> None:
    with pytest.raises(TreeFileError) as info:
        load_tree(TREES / name)
    assert info.value.problems
    first = str(info.value).splitlines()[0]
    assert info.value.problems[0].file.endswith(name.replace("include_bad", "include_bad_grip"))
    assert re.search(pattern, first), first
    assert isinstance(info.value, ValueError)


def test_every_problem_is_reported_not_only_the_first() -> None:
    with pytest.raises(TreeFileError) as info:
        load_tree(TREES / "bad_port_type.xml")
    lines = str(info.value).splitlines()
    assert [p.line for p in info.value.problems] == [4, 5, 6]
    assert len(lines) == 3


class Explodes(BehaviourWithPorts, register=False):
    """A leaf whose constructor fails."""

    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}

    def __init__(self, name: str, **kwargs: Any) -> None:
        raise RuntimeError("no gripper configured")


def test_constructor_failures_become_tree_file_errors_at_the_element() -> None:
    registry = {**get_ports_registry(), "Explodes": Explodes}
    text = """<root main_tree_to_execute="M">
      <BehaviorTree ID="M">
        <Sequence name="s">
          <StubCheck name="ok" value="true"/>
          <Explodes name="bang"/>
        </Sequence>
      </BehaviorTree>
    </root>"""
    with pytest.raises(TreeFileError, match=r"^t\.xml:5: <Explodes name=\"bang\">: cannot build: .*"
                       r"no gripper configured"):  # fmt: skip
        load_tree_string(text, source="t.xml", registry=registry)


def test_explicit_registry_and_partials() -> None:
    registry = {"Count3": functools.partial(StubCounter)}
    root = load_tree_string(
        '<root><BehaviorTree ID="A"><Count3 name="c" ticks="3"/></BehaviorTree></root>',
        registry=registry,
    )
    assert isinstance(root, StubCounter)
    with pytest.raises(TreeFileError, match=r"unknown node type 'StubCheck'"):
        load_tree_string(
            '<root><BehaviorTree ID="A"><StubCheck name="c" value="1"/></BehaviorTree></root>',
            registry=registry,
        )


def test_constructor_hints_are_read_once_per_class_and_handed_out_as_copies(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import inspect

    import py_trees.ports_utils

    class Leaf:
        def __init__(self, name: str, gain: float = 1.0) -> None:
            del name, gain

    calls: list[object] = []
    signature = inspect.signature

    def counted(obj: object, *args: object, **kwargs: object) -> inspect.Signature:
        calls.append(obj)
        return signature(obj, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(py_trees.ports_utils.inspect, "signature", counted)
    first = py_trees.ports_utils.collect_type_hints(Leaf)
    first["gain"] = "changed"
    again = py_trees.ports_utils.collect_type_hints(Leaf)
    assert again == {"name": "str", "gain": "float"}  # annotations as written (postponed)
    assert calls.count(Leaf.__init__) == 1
