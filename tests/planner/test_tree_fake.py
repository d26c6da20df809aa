"""The whole pick-and-place tree against the in-memory world: success, a regrasp on drop, and
every object of a task."""

from __future__ import annotations

import json
from itertools import pairwise
from pathlib import Path

import numpy as np
import py_trees
from py_trees.common import Status

from planner.default_tree import TaskStep, default_tree
from planner.move_result import move_results
from planner.port import Move, Pose
from planner.runlog import RunLog, node_labels
from planner.runner import run_tree
from planner.testing import FakeWorld
from planner.testing.fake_world import FakeObject
from skills import quaternion as quat
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


def two_boxes() -> FakeWorld:
    """Two boxes side by side, each with two moves (the second turned)."""
    turned = quat.from_axis_angle([0, 0, 1], 0.2)
    return FakeWorld(
        objects=[
            FakeObject("left", np.array([0.20, 0.30, 0.15]), pose=Pose.of([0.50, 0.20, 0.675])),
            FakeObject("right", np.array([0.20, 0.30, 0.15]), pose=Pose.of([0.70, -0.22, 0.675])),
        ],
        moves={
            "left": (Move(Pose.of([0.56, 0.22, 0.675])), Move(Pose.of([0.48, 0.18, 0.675]))),
            "right": (
                Move(Pose.of([0.66, -0.18, 0.675])),
                Move(Pose.of([0.72, -0.24, 0.675], turned)),
            ),
        },
    )


def test_the_default_tree_does_every_objects_moves_in_task_order(
    library: SkillLibrary, tmp_path: Path
) -> None:
    world = two_boxes()
    root = default_tree([TaskStep("left", 2), TaskStep("right", 2)])
    with RunLog(tmp_path / "run.jsonl", clock=world.time) as log:
        result = run_tree(root, world, library, DT, 200.0, attach=(log.attach,))
    assert result.status == Status.SUCCESS, result.reason
    assert [n.status for n in root.iterate() if n.name.endswith(".at_goal_closely")] == [
        Status.SUCCESS
    ] * 4
    for name in ("left", "right"):  # each object ends at its last goal
        goal = world.task_moves(name)[-1].goal
        pose = world.object_pose(name)
        assert np.linalg.norm(pose.position - goal.position) < 0.005
        assert quat.angle_between(pose.orientation, goal.orientation) < np.radians(1.0)
    done = move_results()
    assert sorted(done) == [("left", 0), ("left", 1), ("right", 0), ("right", 1)]
    assert all(r.status == Status.SUCCESS and r.skill == "pick_and_place" for r in done.values())
    # The run log tells every node apart, and the moves were carried in the task's order.
    labels = node_labels(root)
    assert len(set(labels.values())) == len(labels)
    records = [json.loads(line) for line in (tmp_path / "run.jsonl").read_text().splitlines()]
    carried = [
        r["node"].split(".")[1] + " " + r["node"].split(".")[3]
        for r in records
        if r["event"] == "status" and r.get("type") == "Transport" and r["to"] == "SUCCESS"
    ]
    assert carried == [
        "left move_centre",
        "left move_right",
        "right move_centre",
        "right move_right",
    ]
