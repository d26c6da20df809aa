"""Where a turned move's steps stand (skills.turns.move_holds, planner.port.stepped_moves)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from planner.port import Move, Pose, stepped_moves
from skills import quaternion as quat
from skills.turns import move_holds, yaw_of

Z = np.array([0.0, 0.0, 1.0])
START = np.array([0.60, -0.15, 0.675])
GOAL = np.array([0.60, 0.15, 0.675])
PLACE = np.array([0.55, 0.0, 0.675])


def _deg(values: list[float]) -> list[float]:
    return [math.degrees(v) for v in values]


def test_a_quarter_turn_is_two_grasps_on_the_two_face_pairs_at_the_goal() -> None:
    holds = move_holds(START, 0.0, GOAL, math.pi / 2, math.radians(45))
    assert_allclose(_deg([h.object_yaw for h in holds]), [0, 45, 45, 90], atol=1e-9)
    # the first grasp turns its grip to the limit; the second holds the faces a quarter back
    assert_allclose(_deg([h.grip_yaw for h in holds]), [0, 45, -45, 0], atol=1e-9)
    assert [h.quarter_turns % 2 for h in holds] == [0, 0, 1, 1]
    for hold, at in zip(holds, [START, GOAL, GOAL, GOAL], strict=True):
        assert_allclose(hold.position, at, atol=0)


def test_elsewhere_the_same_grips_stand_at_the_place_and_the_last_lets_go_at_the_goal() -> None:
    at_goal = move_holds(START, 0.0, GOAL, math.pi / 2, math.radians(45))
    there = move_holds(START, 0.0, GOAL, math.pi / 2, math.radians(45), place=PLACE)
    assert [(h.object_yaw, h.grip_yaw, h.quarter_turns) for h in there] == [
        (h.object_yaw, h.grip_yaw, h.quarter_turns) for h in at_goal
    ]
    for hold, at in zip(there, [START, PLACE, PLACE, GOAL], strict=True):
        assert_allclose(hold.position, at, atol=0)


def test_a_move_one_grasp_makes_has_two_holds_wherever_the_place() -> None:
    holds = move_holds(START, 0.0, GOAL, math.radians(30), math.radians(45), place=PLACE)
    assert len(holds) == 2
    assert_allclose(holds[1].position, GOAL, atol=0)


def test_stepped_moves_put_the_steps_before_the_last_at_each_moves_place() -> None:
    moves = [
        Move(Pose.of(GOAL, quat.from_axis_angle(Z, math.pi / 2)), ("ball",)),
        Move(Pose.of(START, quat.from_axis_angle(Z, math.pi))),
    ]
    steps = stepped_moves(moves, 0.0, math.radians(45), places=[PLACE, None])
    assert [m.task_move for m in steps] == [0, 0, 1, 1]
    assert [m.final for m in steps] == [False, True, False, True]
    assert_allclose(steps[0].goal.position, PLACE, atol=0)  # turned half way, at the place
    assert_allclose(math.degrees(yaw_of(steps[0].goal.orientation)), 45, atol=1e-9)
    assert_allclose(steps[1].goal.position, GOAL, atol=0)  # then carried on to the goal
    assert_allclose(steps[1].goal.orientation, moves[0].goal.orientation, atol=0)
    assert_allclose(steps[2].goal.position, START, atol=0)  # the next move: at its goal
    assert all(m.obstacles == ("ball",) for m in steps[:2])


def test_stepped_moves_want_one_place_per_move() -> None:
    moves = [Move(Pose.of(GOAL, quat.from_axis_angle(Z, math.pi / 2)))]
    with pytest.raises(ValueError, match=r"places: expected one per move \(1\), got 2"):
        stepped_moves(moves, 0.0, math.radians(45), places=[None, None])
