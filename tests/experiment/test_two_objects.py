"""Every object's task runs and is judged: two parcels, each moved twice, in physics."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from py_trees.common import Status

from experiment.episode import move_keys, run_episode, task_steps
from experiment.judge import judge, move_labels
from experiment.summary import reason_of
from planner.default_tree import TaskStep, pick_and_place_xml
from planner.runner import RunResult
from worlds.safety_monitor import SafetyRecord
from worlds.world_file import load_world

TWO_PARCELS = Path(__file__).resolve().parents[1] / "data" / "worlds" / "two_parcels.yaml"
PLACED = ["parcel_left", "parcel_left", "parcel_right", "parcel_right"]


def test_the_task_is_read_step_by_step_with_each_objects_move_indices() -> None:
    world = load_world(TWO_PARCELS)
    assert task_steps(world) == [
        TaskStep("parcel_left", 2, 0, task_moves=(0, 1)),
        TaskStep("parcel_right", 2, 0, task_moves=(0, 1)),
    ]
    assert move_keys(world) == [
        ("parcel_left", 0),
        ("parcel_left", 1),
        ("parcel_right", 0),
        ("parcel_right", 1),
    ]
    assert move_labels(PLACED) == [
        "parcel_left move 1",
        "parcel_left move 2",
        "parcel_right move 1",
        "parcel_right move 2",
    ]


def test_a_move_without_a_placement_fails_the_run_whatever_the_tree_said() -> None:
    tree_ok = RunResult(Status.SUCCESS, 10.0, 1.0, 600, "")
    sim: Any = SimpleNamespace(safety=SafetyRecord())  # what judge reads of a SimWorld
    ok, failure = judge(tree_ok, sim, PLACED, [0.001, 0.002, None, None], [0.1, 0.1, None, None])
    assert (ok, failure) == (False, "not placed: parcel_right move 1, parcel_right move 2")
    ok, failure = judge(tree_ok, sim, PLACED, [0.001, 0.002, 0.03, 0.001], [0.1] * 4)
    assert (ok, failure) == (False, "parcel_right move 1 placed 3.0 cm, 0.1 deg from its goal")
    ok, failure = judge(tree_ok, sim, PLACED, [0.001] * 4, [0.1] * 4)
    assert (ok, failure) == (True, "")


def test_a_placed_object_knocked_away_afterwards_fails_the_run() -> None:
    tree_ok = RunResult(Status.SUCCESS, 10.0, 1.0, 600, "")
    sim: Any = SimpleNamespace(safety=SafetyRecord())
    placed = [0.001] * 4, [0.1] * 4
    # Where the last moves left them, give or take what the retreats nudge: a success.
    still = [("parcel_left", 0.004, 1.0), ("parcel_right", 0.0, 0.0)]
    assert judge(tree_ok, sim, PLACED, *placed, still) == (True, "")
    # The way in to the second parcel swept the first 12 cm off its goal.
    knocked = [("parcel_left", 0.12, 3.0), ("parcel_right", 0.0, 0.0)]
    assert judge(tree_ok, sim, PLACED, *placed, knocked) == (
        False,
        "parcel_left moved 12.0 cm, 3.0 deg after it was placed",
    )
    turned = [("parcel_left", 0.0, 0.0), ("parcel_right", 0.01, 25.0)]
    assert judge(tree_ok, sim, PLACED, *placed, turned)[1].startswith("parcel_right moved")
    # Knocked off the table, the safety record says dropped: that is the reason given.
    sim.safety.dropped = True
    sim.safety.dropped_object = "parcel_left"
    assert judge(tree_ok, sim, PLACED, *placed, knocked) == (False, "dropped parcel_left")


def test_an_object_knocked_off_the_table_is_the_reason_a_failed_run_gives() -> None:
    # An iCub palm placed inside a parcel knocked it to the floor before any grasp: the run
    # had failed "arms touched", the parcel's fall unsaid (no palm had held it: no drop).
    tree_failed = RunResult(Status.FAILURE, 10.0, 1.0, 600, "approach: timed out")
    sim: Any = SimpleNamespace(safety=SafetyRecord(arm_contacts=3))
    fell = "parcel_left lies off the table, out of reach: at (0.76, -0.28, 0.06) m, 0.60 m below"
    placed = [0.001] * 4, [0.1] * 4
    assert judge(tree_failed, sim, PLACED, *placed, (), (), [fell]) == (False, fell)
    assert judge(tree_failed, sim, PLACED, *placed)[1] == "arms touched"
    # A drop stays the first reason: the fall follows from it.
    sim.safety.dropped, sim.safety.dropped_object = True, "parcel_left"
    assert judge(tree_failed, sim, PLACED, *placed, (), (), [fell])[1] == "dropped parcel_left"


def test_an_object_the_task_leaves_standing_shoved_away_fails_the_run() -> None:
    tree_ok = RunResult(Status.SUCCESS, 10.0, 1.0, 600, "")
    sim: Any = SimpleNamespace(safety=SafetyRecord())
    placed = [0.001] * 4, [0.1] * 4
    nudged = [("crate", 0.004, 1.0)]  # a bystander grazed by a wrist: within the tolerance
    assert judge(tree_ok, sim, PLACED, *placed, (), nudged) == (True, "")
    shoved = [("crate", 0.118, 16.4)]
    failure = "crate moved 11.8 cm, 16.4 deg from where it stood (the task does not move it)"
    assert judge(tree_ok, sim, PLACED, *placed, (), shoved) == (False, failure)
    assert reason_of(failure) == "crate moved from where it stood (the task does not move it)"
    # A task that already failed keeps its own reason.
    assert judge(tree_ok, sim, PLACED, [0.001, 0.002, None, None], [0.1] * 4, (), shoved)[1] == (
        "not placed: parcel_right move 1, parcel_right move 2"
    )


@pytest.fixture(scope="module")
def two_parcels_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path]:
    out = tmp_path_factory.mktemp("two_parcels")
    return run_episode(load_world(TWO_PARCELS), out=out, animation=False), out


@pytest.mark.sim
@pytest.mark.xfail(
    strict=True,
    reason="known: from parcel_right's grasp on, the left forearm lies on the placed "
    "parcel_left's front top edge, and the carry pushes parcel_left about 4 cm (README, "
    "Status: two objects)",
)
def test_two_parcels_end_where_they_were_placed(two_parcels_run: tuple[Any, Path]) -> None:
    report, _ = two_parcels_run
    assert report.success, report.failure


@pytest.mark.sim
def test_two_parcels_are_each_placed_twice_and_every_placement_is_judged(
    two_parcels_run: tuple[Any, Path],
) -> None:
    report, tmp_path = two_parcels_run
    assert report.tree_status == "SUCCESS"
    assert report.placement_objects == PLACED
    assert len(report.placement_error_m) == len(report.placement_error_deg) == 4
    assert all(e is not None and e < 0.02 for e in report.placement_error_m)
    assert all(d is not None and d < 10.0 for d in report.placement_error_deg)
    assert report.skills == ["pick_and_place"] * 4  # the skill each move's Transport ran
    assert not report.obstacle_contacts and report.arm_contacts == 0 and not report.dropped
    summary = json.loads(json.dumps(report.summary()))
    assert summary["placement_objects"] == PLACED
    assert summary["placement_error_m"] == report.placement_error_m
    # Every node of the two instances is told apart in the run log.
    nodes = {json.loads(line).get("node") for line in (tmp_path / "run.jsonl").open()}
    assert any(str(n).startswith("task.parcel_right.pick_and_place.") for n in nodes)
    assert (tmp_path / "trajectories.png").stat().st_size > 0


@pytest.mark.sim
def test_a_tree_that_leaves_the_second_parcel_untouched_fails_naming_its_moves(
    tmp_path: Path,
) -> None:
    # The shipped tree for one object (the blackboard's /object, the task's first) and two
    # moves: it succeeds, but the second parcel's task is undone.
    tree = tmp_path / "first_only.xml"
    tree.write_text(pick_and_place_xml(2), encoding="utf-8")
    report = run_episode(load_world(TWO_PARCELS), tree, out=None, animation=False)
    assert report.tree_status == "SUCCESS"
    assert not report.success
    assert report.failure == "not placed: parcel_right move 1, parcel_right move 2"
    assert all(e is not None and e < 0.02 for e in report.placement_error_m[:2])
    assert report.placement_error_m[2:] == [None, None]


def test_a_move_never_carried_is_drawn_from_where_its_object_would_rest() -> None:
    # A run stopped before any carry: each object's first move starts where the world puts
    # it, each later move at the goal before it (not at its own goal, as if done already).
    from experiment.episode import robot_moves
    from experiment.move_recorder import MoveRecorder
    from skills.default_library import build_default_library
    from worlds.sim_world import SimWorld

    world = load_world(TWO_PARCELS)
    with SimWorld(world) as sim:
        recorder = MoveRecorder(sim, move_keys(world), robot_moves(world), 1.0 / 60.0)
        traces = recorder.traces(build_default_library())
    objects = {o.name: o for o in world.objects}
    goals = {s.object: [m.goal.position for m in s.moves] for s in world.task}
    assert [t.label for t in traces] == move_labels(PLACED)
    assert all(len(t.path) == 0 for t in traces)
    for name in ("parcel_left", "parcel_right"):
        first, second = (t for t in traces if t.label.startswith(name))
        assert first.start == pytest.approx(objects[name].pose.position)
        assert first.goal == pytest.approx(goals[name][0])
        assert second.start == pytest.approx(goals[name][0])
        assert second.goal == pytest.approx(goals[name][1])
    # Its obstacles are the task's for that move (they had been left out: a panel "never
    # carried" drew an empty workspace while the failure named its sphere).
    moves = [m for s in world.task for m in s.moves]
    assert [tuple(o.name for o in t.obstacles) for t in traces] == [
        tuple(m.obstacles) for m in moves
    ]
    assert any(t.obstacles for t in traces)
    # The other object is drawn where it lay when the run ended (it never moved).
    for trace, name in zip(traces, PLACED, strict=True):
        (other,) = trace.others
        assert other.name != name
        assert other.position == pytest.approx(objects[other.name].pose.position, abs=1e-3)
