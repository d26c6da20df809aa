"""RunLog: JSON lines of every status change and blackboard write, stamped with sim time."""

from __future__ import annotations

import enum
import json
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
import pytest

from planner.loader import load_tree_string
from planner.runlog import RunLog, json_safe, node_labels
from tests.planner.stub_leaves import FakeClock, StubCheck

TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <Sequence name="seq">
      <StubCounter name="count" ticks="2" count="{n}"/>
      <StubCheck name="check" value="true"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def read(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_status_changes_and_writes_per_tick(tmp_path: Path) -> None:
    import tests.planner.stub_leaves  # noqa: F401

    tree = py_trees.trees.BehaviourTree(load_tree_string(TREE))
    clock = FakeClock(dt=0.5, start=1.0)
    path = tmp_path / "logs" / "run.jsonl"
    with RunLog(path, clock=clock) as log:
        log.attach(tree)
        for _ in range(3):
            tree.tick()
            clock.advance()
        # Readable before close, beside the final name (flushed per tick); renamed to it on
        # close, so run.jsonl is never half a log (issue 15, item 13).
        assert not path.exists()
        flushed = read(log.writing_path)
    records = read(path)
    assert flushed == records
    assert sorted(p.name for p in path.parent.iterdir()) == ["run.jsonl"]
    status = [
        (r["tick"], r["t"], r["node"], r["kind"], r["type"], r["from"], r["to"])
        for r in records
        if r["event"] == "status"
    ]
    assert status == [
        (1, 1.0, "seq.count", "Action", "StubCounter", "INVALID", "RUNNING"),
        (1, 1.0, "seq", "Sequence", "Sequence", "INVALID", "RUNNING"),
        (2, 1.5, "seq.count", "Action", "StubCounter", "RUNNING", "SUCCESS"),
        (2, 1.5, "seq.check", "Condition", "StubCheck", "INVALID", "SUCCESS"),
        (2, 1.5, "seq", "Sequence", "Sequence", "RUNNING", "SUCCESS"),
        # tick 3 re-runs the sequence: count starts again (SUCCESS -> RUNNING), check is
        # stopped by the sequence re-entering (SUCCESS -> INVALID)
        (3, 2.0, "seq.count", "Action", "StubCounter", "SUCCESS", "RUNNING"),
        (3, 2.0, "seq", "Sequence", "Sequence", "SUCCESS", "RUNNING"),
        (3, 2.0, "seq.check", "Condition", "StubCheck", "SUCCESS", "INVALID"),
    ]
    first = records[0]
    assert first["event"] == "status" and first["feedback"] == "tick 1"
    writes = [
        (r["tick"], r["key"], r["activity"], r["value"]) for r in records if r["event"] == "write"
    ]
    assert writes == [(1, "/n", "INITIALISED", 1), (2, "/n", "WRITE", 2), (3, "/n", "WRITE", 1)]
    assert next(r for r in records if r["event"] == "write")["client"] == "seq.count"
    assert py_trees.blackboard.Blackboard.activity_stream is None  # closed: stream given back
    assert tree.post_tick_handlers == [] and tree.visitors == []
    assert not any("stop" in vars(node) for node in tree.root.iterate())  # unwrapped


def test_writes_between_ticks_are_logged_with_the_next_tick(tmp_path: Path) -> None:
    tree = py_trees.trees.BehaviourTree(py_trees.behaviours.Success(name="ok"))
    path = tmp_path / "run.jsonl"
    with RunLog(path, clock=lambda: 3.0) as log:
        log.attach(tree)
        writer = py_trees.blackboard.Client(name="app")
        writer.register_key("/goal", access=py_trees.common.Access.WRITE)
        writer.set("/goal", np.array([0.1234567891, 2.0, 3.0]))
        tree.tick()
    records = read(path)
    assert records[0] == {
        "t": 3.0, "tick": 1, "event": "status", "node": "ok", "kind": "Action",
        "type": "Success", "from": "INVALID", "to": "SUCCESS", "feedback": "success",
    }  # fmt: skip
    assert records[1] == {
        "t": 3.0, "tick": 1, "event": "write", "key": "/goal", "client": "app",
        "activity": "INITIALISED", "value": [0.123457, 2.0, 3.0],
    }  # fmt: skip


class Colour(enum.Enum):
    RED = 1


def test_json_safe_summaries() -> None:
    assert json_safe(np.float64(1.23456789)) == 1.234568
    assert json_safe(np.int64(7)) == 7 and isinstance(json_safe(np.int64(7)), int)
    assert json_safe(float("nan")) == "nan" and json_safe(float("-inf")) == "-inf"
    assert json_safe(np.eye(2)) == [[1.0, 0.0], [0.0, 1.0]]
    assert json_safe(np.zeros((100, 3))) == {
        "shape": [100, 3], "dtype": "float64", "min": 0.0, "max": 0.0,
    }  # fmt: skip
    assert json_safe((1, "a", None, True)) == [1, "a", None, True]
    assert json_safe({"k": np.array([1, 2])}) == {"k": [1, 2]}
    assert json_safe(Colour.RED) == "RED"
    long = json_safe(object(), max_chars=20)
    assert long.startswith("<object object") and len(long) == 20 and long.endswith("...")
    json.dumps(json_safe({"x": np.array([np.nan])}), allow_nan=False)  # still valid JSON


def test_closed_or_reattached_log_is_refused(tmp_path: Path) -> None:
    tree = py_trees.trees.BehaviourTree(py_trees.behaviours.Success(name="ok"))
    log = RunLog(tmp_path / "run.jsonl")
    log.attach(tree)
    with pytest.raises(RuntimeError, match="already attached"):
        log.attach(tree)
    log.close()
    log.close()  # idempotent
    with pytest.raises(RuntimeError, match="closed"):
        log.attach(tree)
    tree.tick()  # detached: no handler left behind


def test_node_labels_are_names_or_paths_where_names_repeat() -> None:
    def check(name: str) -> StubCheck:
        return StubCheck(name)

    first = py_trees.composites.Sequence("try", memory=True, children=[check("a"), check("b")])
    second = py_trees.composites.Sequence("try", memory=True, children=[check("a"), check("c")])
    root = py_trees.composites.Selector("root", memory=True, children=[first, second])
    labels = node_labels(root)
    assert [labels[n.id] for n in root.iterate()] == [
        "root/try[0]/a",
        "b",
        "root/try[0]",
        "root/try[1]/a",
        "c",
        "root/try[1]",
        "root",
    ]


UNNAMED = """<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Main">
  <Sequence>
    <Fallback><AlwaysFailure/><AlwaysSuccess/></Fallback>
    <Inverter><AlwaysFailure/></Inverter>
  </Sequence>
</BehaviorTree></root>"""


def test_unnamed_nodes_are_labelled_by_their_type_the_same_in_every_load() -> None:
    # Groot2 leaves names empty: py_trees names such nodes by a fresh uuid4, which had
    # reached run.jsonl's labels and `render-tree --format ascii` (another in every run).
    from planner.render import render_tree

    labels = [list(node_labels(load_tree_string(UNNAMED)).values()) for _ in range(2)]
    assert labels[0] == labels[1]
    assert sorted(labels[0]) == sorted(
        [
            "Sequence",
            "Fallback",
            "AlwaysSuccess",
            "Inverter",
            "Sequence/Fallback/AlwaysFailure",
            "Sequence/Inverter/AlwaysFailure",
        ]
    )
    text = render_tree(load_tree_string(UNNAMED), "ascii")
    assert text == render_tree(load_tree_string(UNNAMED), "ascii")
    assert "-^- Inverter\n" in text and "{o} Fallback\n" in text and "_" not in text


def writes_of_one_tick(tmp_path: Path, xml: str) -> list[dict[str, Any]]:
    """The write events ``run.jsonl`` holds of one tick of the tree in ``xml``."""
    tree = py_trees.trees.BehaviourTree(load_tree_string(xml))
    tree.setup(clock=FakeClock())
    path = tmp_path / "run.jsonl"
    with RunLog(path, clock=lambda: 0.0) as log:
        log.attach(tree)
        tree.tick()
    return [r for r in read(path) if r["event"] == "write"]


def test_script_and_condition_writes_are_logged_as_a_clients_are(tmp_path: Path) -> None:
    # A script wrote the blackboard past its activity stream: run.jsonl, which says it holds
    # every write, had none of a Script's, a _post's or an _onSuccess's.
    import tests.planner.stub_leaves  # noqa: F401

    records = writes_of_one_tick(
        tmp_path,
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence name="seq">'
        '<Script name="sc" code="m := 3; m += 1"/>'
        '<StubCheck name="check" value="true" _onSuccess="done := true"/>'
        "</Sequence></BehaviorTree></root>",
    )
    writes = [(r["key"], r["client"], r["activity"], r["value"]) for r in records]
    assert writes == [
        ("/m", "seq.sc", "INITIALISED", 3),
        ("/m", "seq.sc", "WRITE", 4),
        ("/done", "seq.check _onSuccess", "INITIALISED", True),
    ]


def test_writes_of_unnamed_nodes_name_their_client_without_uuids(tmp_path: Path) -> None:
    # "client": "main.Script_55dc3015-..." had differed from run to run.
    records = writes_of_one_tick(
        tmp_path,
        '<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>'
        '<Script code="m := 3"/></Sequence></BehaviorTree></root>',
    )
    assert [r["client"] for r in records] == ["Script"]


def test_unnamed_subtrees_are_named_by_their_id_each_its_own_instance() -> None:
    # Groot2 saves a <SubTree> without a name: py_trees had named it by a fresh uuid4, which
    # reached run.btlog's subtree IDs and run.jsonl's labels and clients.
    xml = """<root BTCPP_format="4" main_tree_to_execute="Main">
<BehaviorTree ID="Main"><Sequence name="main">
  <Script name="init" code="a := 0; b := 0"/>
  <SubTree ID="Put" value="1" out="{a}"/>
  <SubTree ID="Put" value="2" out="{b}"/>
  <ScriptCondition name="both" code="a == 1 &amp;&amp; b == 2"/>
</Sequence></BehaviorTree>
<BehaviorTree ID="Put"><Script name="put" code="out := value"/></BehaviorTree>
</root>"""
    root = load_tree_string(xml)
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(clock=FakeClock())
    tree.tick()
    assert root.status == py_trees.common.Status.SUCCESS  # each wrote its own caller's key
    assert list(node_labels(root).values()) == [
        "main",
        "main.init",
        "main.Put::1.put",
        "main.Put::2.put",
        "main.both",
    ]
