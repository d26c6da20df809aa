"""Which faces a two-palm grip holds and how a turn is split into steps (skills.turns)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.dual_arm import GraspGeometry
from skills.turns import (
    grip_options,
    grip_yaw,
    held_quarter_turns,
    lateral_quarter_turns,
    turn_steps,
    wrap_angle,
    yaw_of,
)
from skills.vocabulary import Arm

D = math.radians
MAX = D(45.0)


def _deg(values: list[float]) -> list[float]:
    return [math.degrees(v) for v in values]


@pytest.mark.parametrize(
    ("start", "goal", "expected"),
    [
        (0, 20, [20]),
        (0, 45, [45]),
        (0, 90, [45, 90]),
        (0, -90, [-45, -90]),
        # a half turn is a real one: four steps, never the box's symmetric "no turn"
        (0, 180, [-45, -90, -135, -180]),
        (30, 90, [45, 90]),
        (0, 135, [45, 90, 135]),
        # across the wrap: from 170 to -170 is 20 degrees, not 340
        (170, -170, [190]),
        (-90, 90, [-135, -180, -225, -270]),
    ],
)
def test_turn_steps_split_a_turn_into_steps_the_grip_can_make(
    start: float, goal: float, expected: list[float]
) -> None:
    steps = turn_steps(D(start), D(goal), MAX)
    assert_allclose(_deg(steps), expected, atol=1e-9)
    # every step turns at most max_turn, and the last one lands on the goal's orientation
    turns = np.diff([D(start), *steps])
    assert np.all(np.abs(turns) <= MAX + 1e-12)
    assert abs(wrap_angle(steps[-1] - D(goal))) < 1e-12


def test_each_step_keeps_the_grip_within_max_turn() -> None:
    rng = np.random.default_rng(0)
    for start, goal in rng.uniform(-math.pi, math.pi, size=(200, 2)):
        yaw = float(start)
        for step in turn_steps(float(start), float(goal), MAX):
            k = lateral_quarter_turns(yaw, step - yaw)
            first, last = grip_yaw(yaw, k), grip_yaw(yaw, k) + (step - yaw)
            assert max(abs(first), abs(last)) <= MAX + 1e-9, (start, goal, yaw, step)
            yaw = step


def test_turn_steps_on_a_turned_robot_are_the_same_turns() -> None:
    assert_allclose(_deg(turn_steps(D(30), D(120), MAX, robot_yaw=D(30))), [75, 120], atol=1e-9)


def test_turn_steps_refuses_a_grip_that_cannot_reach_every_yaw() -> None:
    with pytest.raises(ValueError, match=r"max_turn: expected an angle in \[pi/4, pi/2\)"):
        turn_steps(0.0, 1.0, D(30))
    with pytest.raises(ValueError, match=r"goal_yaw: expected a finite angle"):
        turn_steps(0.0, math.nan, MAX)


def test_faces_nearest_the_robot_y_axis_without_a_turn() -> None:
    assert lateral_quarter_turns(D(10)) == 0
    assert lateral_quarter_turns(D(80)) == 3  # the object's x faces now face the palms
    assert lateral_quarter_turns(D(-80)) == 1
    assert lateral_quarter_turns(D(170)) == 2


def test_faces_for_a_turn_are_the_pair_that_stays_within_reach() -> None:
    # At 45 degrees, turning on by 45: the pair a quarter turn back starts at -45 and ends at 0.
    k = lateral_quarter_turns(D(45), D(45))
    assert k == 3
    assert math.degrees(grip_yaw(D(45), k)) == pytest.approx(-45.0)


def test_grip_options_list_the_usual_pair_then_others_that_make_the_turn() -> None:
    # A box set down at 44 degrees: the pairs at grip yaws 44 and -46 both hold it within 50.
    options = grip_options(D(44), 0.0, D(50))
    assert options[0] == lateral_quarter_turns(D(44))
    assert len(options) == 2
    assert sorted(abs(math.degrees(grip_yaw(D(44), k))) for k in options) == pytest.approx(
        [44.0, 46.0]
    )
    # Each listed pair stays within the limit over the whole turn.
    for k in grip_options(D(30), D(10), D(50)):
        start = math.degrees(grip_yaw(D(30), k))
        assert max(abs(start), abs(start + 10.0)) <= 50.0 + 1e-9


def test_grip_options_keep_the_usual_pair_alone_when_no_other_makes_the_turn() -> None:
    assert grip_options(D(10), 0.0, D(50)) == [lateral_quarter_turns(D(10))]
    # A turn no pair makes within the limit: the usual pair, whose turn goes in steps.
    assert grip_options(D(0), D(120), D(50)) == [lateral_quarter_turns(D(0), D(120))]
    # A turned robot: the same pairs as the object turned back by its heading.
    assert grip_options(D(74), 0.0, D(50), robot_yaw=D(30)) == grip_options(D(44), 0.0, D(50))


def test_held_faces_from_the_left_palm_position() -> None:
    for k in range(4):
        g = GraspGeometry.lateral(0.2, 0.02, quarter_turns=k)
        assert held_quarter_turns(g.position(Arm.LEFT)) == k


def test_lateral_geometry_on_the_x_faces() -> None:
    g = GraspGeometry.lateral(0.20, 0.02, quarter_turns=3)
    # the left palm on the +x face, pushing towards -x, the palm's x axis still down
    assert_allclose(g.position(Arm.LEFT), [0.11, 0.0, 0.0], atol=1e-15)
    assert_allclose(g.normal(Arm.LEFT), [-1.0, 0.0, 0.0], atol=1e-15)
    assert_allclose(quat.rotate(g.orientation(Arm.LEFT), [0, 0, 1.0]), [-1, 0, 0], atol=1e-12)
    assert_allclose(quat.rotate(g.orientation(Arm.RIGHT), [1.0, 0, 0]), [0, 0, -1], atol=1e-12)


def test_yaw_of_a_quaternion() -> None:
    q = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), D(-120))
    assert math.degrees(yaw_of(q)) == pytest.approx(-120.0)
