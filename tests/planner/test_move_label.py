"""A carry's progress names its move as the run's summary counts them."""

from __future__ import annotations

from planner.leaves.base import move_label
from planner.port import Move, Pose

GOAL = Pose.of([0.6, 0.0, 0.675])


def test_a_move_is_named_by_the_world_files_count_and_its_steps() -> None:
    moves = [
        Move(GOAL, task_move=0),
        Move(GOAL, task_move=1, final=False),  # a turn made in two grasps
        Move(GOAL, task_move=1),
        Move(GOAL, task_move=2),
    ]
    labels = [move_label(moves, "parcel", i) for i in range(len(moves))]
    assert labels == [
        "parcel move 1",
        "parcel move 2, step 1 of 2",
        "parcel move 2, step 2 of 2",
        "parcel move 3",
    ]


def test_a_move_no_world_file_listed_keeps_its_index() -> None:
    assert move_label([Move(GOAL), Move(GOAL)], "parcel", 1) == "move 1"
