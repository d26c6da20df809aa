"""The whole pick-and-place tree against the in-memory world: success, and a regrasp on drop."""

from __future__ import annotations

import json
from itertools import pairwise
from pathlib import Path

import py_trees
from py_trees.common import Status

from planner.default_tree import default_tree
from planner.runlog import RunLog, node_labels
from planner.runner import run_tree
from planner.testing import FakeWorld
from skills.library import SkillLibrary
from skills.vocabulary import Arm

DT = 1.0 / 60.0


def statuses_of(root: py_trees.behaviour.Behaviour, kind: str) -> list[Status]:
    return [n.status for n in root.iterate() if type(n).__name__ == kind]


def test_the_tree_does_the_three_moves(fake_world: FakeWorld, library: SkillLibrary) -> None:
    root = default_tree()
    result = run_tree(root, fake_world, library, DT, 120.0, {"/object": "parcel"})
    assert result.status == Status.SUCCESS, result.reason
    # each move placed within 5 mm and 3 degrees at once: no correction carried
    assert [n.status for n in root.iterate() if n.name.endswith(".at_goal_closely")] == [
        Status.SUCCESS
    ] * 3
    assert fake_world.contact_force(Arm.LEFT, "parcel") == 0.0  # released


def test_the_run_log_names_each_node_of_the_default_run_once(
    fake_world: FakeWorld, library: SkillLibrary, tmp_path: Path
) -> None:
    root = default_tree()
    with RunLog(tmp_path / "run.jsonl", clock=fake_world.time) as log:
        result = run_tree(
            root, fake_world, library, DT, 120.0, {"/object": "parcel"}, attach=(log.attach,)
        )
    assert result.status == Status.SUCCESS, result.reason
    labels = node_labels(root)
    assert len(set(labels.values())) == len(labels)  # no two nodes alike
    records = [json.loads(line) for line in (tmp_path / "run.jsonl").read_text().splitlines()]
    changes: dict[str, list[tuple[str, str]]] = {}
    for r in records:
        if r["event"] == "status":
            changes.setdefault(r["node"], []).append((r["from"], r["to"]))
    assert set(changes) <= set(labels.values())
    carried = {r["node"] for r in records if r.get("type") == "Transport" and r["to"] == "SUCCESS"}
    assert len(carried) == 3  # one Transport per move, told apart
    for node, steps in changes.items():  # one node's story: each change starts where it was
        assert all(a[1] == b[0] for a, b in pairwise(steps)), (node, steps)


def test_a_drop_during_a_move_leads_to_a_regrasp(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    root = default_tree()
    events: list[str] = []

    def slip(tree: py_trees.trees.BehaviourTree) -> None:
        running = [n for n in tree.root.iterate() if n.status == Status.RUNNING]
        carrying = [n for n in running if type(n).__name__ == "Transport"]
        approaching = [n for n in running if type(n).__name__ == "Approach"]
        if not events and carrying and int(carrying[0].get_input("move")) == 1:
            fake_world.drop("parcel")  # the grip fails mid-carry ...
            events.append("dropped")
        elif events == ["dropped"] and approaching:
            fake_world.restore_grip("parcel")  # ... and the hands can grip again
            events.append("regrasping")

    result = run_tree(root, fake_world, library, DT, 200.0, {"/object": "parcel"}, on_tick=slip)
    assert events == ["dropped", "regrasping"]
    assert result.status == Status.SUCCESS, result.reason
    # each move placed within 5 mm and 3 degrees at once: no correction carried
    assert [n.status for n in root.iterate() if n.name.endswith(".at_goal_closely")] == [
        Status.SUCCESS
    ] * 3
