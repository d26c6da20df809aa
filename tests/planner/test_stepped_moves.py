"""A task's turned moves as a world shows them through the port (planner.port.stepped_moves)."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from planner.port import Move, Pose, stepped_moves
from skills import quaternion as quat
from skills.turns import yaw_of

Z = np.array([0.0, 0.0, 1.0])


def _turned(deg: float) -> np.ndarray:
    return quat.from_axis_angle(Z, math.radians(deg))


def test_a_turn_beyond_the_grip_becomes_a_carry_then_turns_in_place() -> None:
    moves = [
        Move(Pose.of([0.65, 0.0, 0.675], _turned(90)), ("ball",)),
        Move(Pose.of([0.60, -0.15, 0.675], _turned(60))),
    ]
    steps = stepped_moves(moves, 0.0, math.radians(45))
    yaws = [math.degrees(yaw_of(m.goal.orientation)) for m in steps]
    assert_allclose(yaws, [45, 90, 60], atol=1e-9)
    assert [m.task_move for m in steps] == [0, 0, 1]
    assert [m.final for m in steps] == [False, True, True]
    # every step of a move goes to its goal position, with its obstacles
    assert_allclose(steps[0].goal.position, [0.65, 0.0, 0.675])
    assert steps[0].obstacles == ("ball",) and steps[1].obstacles == ("ball",)
    # the last step is the task's own goal pose
    assert_allclose(steps[1].goal.orientation, moves[0].goal.orientation, atol=0)


def test_moves_within_the_grip_are_left_as_they_are() -> None:
    moves = [Move(Pose.of([0.6, 0.1, 0.675], _turned(30)))]
    (only,) = stepped_moves(moves, 0.0, math.radians(45))
    assert_allclose(only.goal.position, moves[0].goal.position, atol=0)
    assert_allclose(only.goal.orientation, moves[0].goal.orientation, atol=0)
    assert only.task_move == 0 and only.final
