"""run.btlog: BT.CPP's FileLogger2 layout, read back, and the same transitions as run.jsonl."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import py_trees
import pytest

from planner.btlog import BtLog, groot_tree_xml
from planner.default_tree import default_tree
from planner.loader import load_tree_string
from planner.runlog import RunLog, node_labels
from planner.runner import run_tree
from planner.testing import FakeWorld
from skills.library import SkillLibrary
from tests.planner.btlog_reader import read_btlog
from tests.planner.stub_leaves import FakeClock

CODES = {"INVALID": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3}

TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <ReactiveSequence name="seq">
      <StubCounter name="count" ticks="2" count="{n}"/>
      <RetryUntilSuccessful num_attempts="3">
        <StubCheck name="check" value="true"/>
      </RetryUntilSuccessful>
    </ReactiveSequence>
  </BehaviorTree>
</root>
"""


def status_events(path: Path) -> list[dict]:
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    return [r for r in lines if r["event"] == "status"]


def test_layout_and_transitions_of_a_small_tree(tmp_path: Path) -> None:
    import tests.planner.stub_leaves  # noqa: F401

    root = load_tree_string(TREE)
    tree = py_trees.trees.BehaviourTree(root)
    clock = FakeClock(dt=0.25, start=2.0)
    with (
        RunLog(tmp_path / "run.jsonl", clock=clock) as log,
        BtLog(tmp_path / "run.btlog", root, clock=clock) as btlog,
    ):
        log.add_status_listener(btlog.record)
        log.attach(tree)
        for _ in range(3):
            tree.tick()
            clock.advance()
    got = read_btlog(tmp_path / "run.btlog")
    assert got.protocol == 1
    assert got.first_us == 2_000_000
    elements = got.uids()
    assert sorted(elements) == [1, 2, 3, 4]  # numbered 1.. depth first
    assert [elements[u].tag for u in (1, 2, 3, 4)] == [
        "ReactiveSequence", "StubCounter", "RetryUntilSuccessful", "StubCheck",
    ]  # fmt: skip
    assert [elements[u].attrib["name"] for u in (1, 2, 4)] == ["seq", "count", "check"]
    assert elements[3].attrib["num_attempts"] == "3"
    model = {e.attrib["ID"]: e.tag for e in model_of(got.xml)}
    assert model == {"StubCheck": "Condition", "StubCounter": "Action"}  # built-ins need none
    # the same transitions as run.jsonl's status events, in order, at the same times
    labels = node_labels(root)
    uid_of = {labels[i]: btlog.uids[i] for i in labels}
    events = status_events(tmp_path / "run.jsonl")
    assert len(events) > 5
    expected = [(round((e["t"] - 2.0) * 1e6), uid_of[e["node"]], CODES[e["to"]]) for e in events]
    assert got.transitions == expected
    assert btlog.transitions == len(expected)


def model_of(text: str) -> list[ET.Element]:
    model = ET.fromstring(text).find("TreeNodesModel")
    assert model is not None
    return list(model)


def test_default_run_on_the_fake_world(
    fake_world: FakeWorld, library: SkillLibrary, tmp_path: Path
) -> None:
    root = default_tree()
    with (
        RunLog(tmp_path / "run.jsonl", clock=fake_world.time) as log,
        BtLog(tmp_path / "run.btlog", root, clock=fake_world.time) as btlog,
    ):
        log.add_status_listener(btlog.record)
        result = run_tree(
            root, fake_world, library, 1 / 60, 120.0, {"/object": "parcel"}, attach=(log.attach,)
        )
    assert result.success, result.reason
    got = read_btlog(tmp_path / "run.btlog")
    elements = got.uids()
    subtrees = {u for u, e in elements.items() if e.tag == "SubTree"}
    assert len(elements) - len(subtrees) == sum(1 for _ in root.iterate())
    # the subtrees as Groot2 expects them: a SubTree node, and a BehaviorTree per instance
    document = ET.fromstring(got.xml)
    instances = [(bt.attrib["ID"], bt.attrib["_fullpath"]) for bt in document.iter("BehaviorTree")]
    # The main tree by its own ID, as BT.CPP's WriteTreeToXML writes it (it had been
    # MainTree whatever the file called it).
    assert instances[:3] == [
        ("Task", ""), ("PickAndPlace", "first_object"),
        ("GraspObject", "first_object/grasp_object"),
    ]  # fmt: skip
    assert ("Move", "first_object/move_left") in instances
    assert len(instances) == len(subtrees) + 1
    assert {e.attrib["_fullpath"] for e in document.iter("SubTree")} == {
        p for _, p in instances[1:]
    }
    labels = node_labels(root)
    uid_of = {labels[i]: btlog.uids[i] for i in labels}
    events = status_events(tmp_path / "run.jsonl")
    own = [(u, s) for _, u, s in got.transitions if u not in subtrees]
    assert own == [(uid_of[e["node"]], CODES[e["to"]]) for e in events]
    # a SubTree node changes with its subtree's root node, at the same time, right after it
    for i, (t, u, s) in enumerate(got.transitions):
        if u in subtrees:
            before = got.transitions[i - 1]
            assert before[0] == t and before[2] == s
    first_object = next(
        int(e.attrib["_uid"])
        for e in document.iter("SubTree")
        if e.attrib["_fullpath"] == "first_object"
    )
    assert [s for _, u, s in got.transitions if u == first_object] == [1, 2]  # running, success
    times = [t for t, _, _ in got.transitions]
    assert times == sorted(times) and times[-1] == pytest.approx(result.sim_time * 1e6, abs=2e4)
    # every node ever logged has a model, or is a BT.CPP built-in Groot2 knows
    model = {e.attrib["ID"] for e in model_of(got.xml)}
    builtin = {"Sequence", "ReactiveSequence", "Fallback", "ReactiveFallback", "Parallel",
               "RetryUntilSuccessful", "Timeout", "ForceSuccess", "ForceFailure", "Inverter",
               "Repeat", "SubTree"}  # fmt: skip
    assert {e.tag for e in elements.values()} <= model | builtin


def test_wrong_suffix_and_too_many_nodes_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"ending in \.btlog"):
        BtLog(tmp_path / "run.log", py_trees.behaviours.Success("ok"), clock=lambda: 0.0)
    wide = py_trees.composites.Sequence(
        "wide", memory=True, children=[py_trees.behaviours.Success(f"s{i}") for i in range(65535)]
    )
    with pytest.raises(ValueError, match="at most 65535 nodes"):
        groot_tree_xml(wide)
