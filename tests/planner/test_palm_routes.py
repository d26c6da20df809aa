"""Approach and Retreat predict their palms' path and take another way round a sphere in it."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.testing import assert_allclose
from py_trees.common import Status

from planner.leaves import Approach, Retreat
from planner.leaves.palm_motion import measured_state
from planner.leaves.palm_routes import predict_palm_path
from planner.port import ObstacleInfo, Pose
from planner.testing import FakeWorld
from planner.testing.fake_world import FakeObject
from planner.testing.harness import TickLog
from skills import quaternion as quat
from skills.vocabulary import ARMS, Arm

Tick = Callable[..., TickLog]
DT = 1.0 / 60.0
BOX = np.array([0.20, 0.30, 0.15])


def commanded_path(world: FakeWorld) -> np.ndarray:
    """Palm positions as commanded, (N, 2, 3), left then right."""
    per_arm = [np.array([c.pose.position for c in world.commands if c.arm is a]) for a in ARMS]
    return np.stack(per_arm, axis=1)


def palms_beside_box(obstacles: list[ObstacleInfo]) -> FakeWorld:
    """The palms open 4 cm beside the box's faces (as after a release)."""
    world = FakeWorld(objects=[FakeObject("parcel", BOX)], obstacles=obstacles)
    for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0)):
        rest = world.rest_palm_pose(arm)
        world.command_palm(arm, Pose.of([0.55, side * 0.21, 0.675], rest.orientation))
    world.advance(DT)
    world.commands.clear()
    return world


def default_retreat(world: FakeWorld, back: float, rise: float) -> dict[Arm, list[Pose]]:
    out = {}
    for arm in ARMS:
        here = world.palm_pose(arm)
        away = here.position - back * quat.rotate(here.orientation, np.array([0.0, 0.0, 1.0]))
        out[arm] = [
            Pose(away, here.orientation),
            Pose(away + np.array([0.0, 0.0, rise]), here.orientation),
            world.rest_palm_pose(arm),
        ]
    return out


def test_retreat_with_nothing_near_takes_the_usual_way_exactly(tick_leaf: Tick) -> None:
    world = palms_beside_box([ObstacleInfo("far", np.array([1.5, 0.0, 0.8]), 0.04)])
    world.set_active_obstacles(["far"])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    usual = predict_palm_path(starts, default_retreat(world, 0.04, 0.1), 1.0, DT)
    log = tick_leaf(Retreat("retreat"), world, back_m=0.04, segment_s=1.0)
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback == "palms at rest"
    path = commanded_path(world)
    assert_allclose(path, usual.positions[1 : len(path) + 1], rtol=0.0, atol=0.0)


def test_retreat_goes_round_a_sphere_on_its_usual_path(tick_leaf: Tick) -> None:
    world = palms_beside_box([])
    usual = default_retreat(world, 0.04, 0.1)
    # A sphere where the right palm would rise to.
    sphere = ObstacleInfo("ball", usual[Arm.RIGHT][1].position.copy(), 0.03)
    world = palms_beside_box([sphere])
    world.set_active_obstacles(["ball"])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    predicted = predict_palm_path(starts, usual, 1.0, DT)
    assert not world.check_palm_path(predicted.positions, predicted.orientations, 0.01).clear
    log = tick_leaf(Retreat("retreat"), world, back_m=0.04, segment_s=1.0)
    assert log.final == Status.SUCCESS, log.feedback
    assert "refused backing away and rising" in log.feedback
    path = commanded_path(world)
    check = world.check_palm_path(path, np.zeros((len(path), 2, 4)), 0.01)
    assert check.clear, check.detail


def test_approach_with_nothing_near_takes_the_usual_way(tick_leaf: Tick) -> None:
    world = FakeWorld(objects=[FakeObject("parcel", BOX)])
    log = tick_leaf(Approach("approach"), world, object="parcel")
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback == "palms at the pre-grasp poses"


def test_approach_goes_round_a_sphere_on_its_usual_path(tick_leaf: Tick) -> None:
    plain = FakeWorld(objects=[FakeObject("parcel", BOX)])
    assert tick_leaf(Approach("approach"), plain, object="parcel").final == Status.SUCCESS
    usual = commanded_path(plain)
    # A small sphere a little below the right palm's usual way in, a fifth of the way along:
    # coming in from above passes over it.
    sphere = ObstacleInfo("ball", usual[len(usual) // 5, 1] - np.array([0.0, 0.0, 0.04]), 0.02)
    world = FakeWorld(objects=[FakeObject("parcel", BOX)], obstacles=[sphere])
    world.set_active_obstacles(["ball"])
    assert not world.check_palm_path(usual, np.zeros((len(usual), 2, 4)), 0.01).clear
    log = tick_leaf(Approach("approach"), world, object="parcel")
    assert log.final == Status.SUCCESS, log.feedback
    assert log.feedback.startswith("palms at the pre-grasp poses (by coming in from above")
    path = commanded_path(world)
    check = world.check_palm_path(path, np.zeros((len(path), 2, 4)), 0.01)
    assert check.clear, check.detail
    # Either way, the palms end beside the faces.
    assert_allclose(path[-1], usual[-1], atol=3e-3)


def test_a_leaf_boxed_in_keeps_the_usual_way_and_says_so(tick_leaf: Tick) -> None:
    world = palms_beside_box([])
    usual = default_retreat(world, 0.04, 0.1)
    # A sphere swallowing the right palm where it stands: every way starts in contact.
    sphere = ObstacleInfo("ball", world.palm_pose(Arm.RIGHT).position.copy(), 0.08)
    world = palms_beside_box([sphere])
    world.set_active_obstacles(["ball"])
    starts = {a: measured_state(world.palm_pose(a), world.palm_twist(a)) for a in ARMS}
    expected = predict_palm_path(starts, usual, 1.0, DT)
    log = tick_leaf(Retreat("retreat"), world, back_m=0.04, segment_s=1.0)
    assert log.final == Status.SUCCESS
    assert "no way predicted clear, by backing away and rising" in log.feedback
    path = commanded_path(world)
    assert_allclose(path, expected.positions[1 : len(path) + 1], rtol=0.0, atol=0.0)


def test_approach_refuses_an_object_fallen_off_the_table_saying_where(tick_leaf: Tick) -> None:
    fallen = FakeObject("parcel", BOX, pose=Pose.of([0.9, -0.3, 0.05]))
    log = tick_leaf(Approach("approach"), FakeWorld(objects=[fallen]), object="parcel")
    assert log.final == Status.FAILURE
    assert "parcel lies off the table, out of reach: at (0.90, -0.30, 0.05) m" in log.feedback
    assert "below the table top" in log.feedback
    beyond = FakeObject("parcel", BOX, pose=Pose.of([1.2, 0.0, 0.675]))
    log = tick_leaf(Approach("approach"), FakeWorld(objects=[beyond]), object="parcel")
    assert log.final == Status.FAILURE
    assert "beyond the table's edge" in log.feedback
