"""Letting go of, stepping back from and coming back to a box that stands turned in the grip."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.testing import assert_allclose

from planner.leaves.approach import clear_rise
from planner.leaves.release import palms_facing
from planner.port import Pose
from planner.testing import FakeObject, FakeWorld
from skills import quaternion as quat
from skills.composer import grasped_state
from skills.dual_arm import GraspGeometry

BOX = np.array([0.20, 0.30, 0.15])


def world_with_box_at(yaw_deg: float) -> tuple[FakeWorld, Pose]:
    pose = Pose.of([0.55, 0.0, 0.675], quat.from_axis_angle([0, 0, 1], np.radians(yaw_deg)))
    return FakeWorld(objects=[FakeObject("parcel", BOX, pose=pose)]), pose


def test_palms_open_along_their_own_normals_which_are_the_faces_for_a_flat_grip() -> None:
    g = GraspGeometry.lateral(0.30, 0.02)
    state = grasped_state(
        [0.55, 0.0, 0.675],
        quat.IDENTITY,
        (g.left_position, g.left_orientation),
        (g.right_position, g.right_orientation),
    )
    facing = palms_facing(state)
    assert_allclose(facing.left_normal, g.left_normal, atol=1e-12)
    assert_allclose(facing.right_normal, g.right_normal, atol=1e-12)
    # A palm turned in the grip opens straight back from what it presses, not along a face.
    turned = quat.multiply(quat.from_axis_angle([0, 0, 1], 0.6), g.left_orientation)
    state = replace(state, left=state.left._replace(orientation=turned))
    assert_allclose(
        palms_facing(state).left_normal, quat.rotate(turned, [0.0, 0.0, 1.0]), atol=1e-12
    )


def test_the_way_in_passes_above_a_box_turned_in_the_grip_only() -> None:
    world, pose = world_with_box_at(0.0)
    assert clear_rise(world, "parcel", pose, 0, 0.08) == 0.08  # the first grasp: as before
    world, pose = world_with_box_at(40.0)
    palm = max(world.robot_capabilities().palm_size_m[:2]) / 2.0
    assert clear_rise(world, "parcel", pose, 0, 0.08) >= BOX[2] / 2.0 + palm + 0.02 - 1e-12
    world, pose = world_with_box_at(90.0)  # a quarter turn: the next face pair is square on
    assert (
        clear_rise(world, "parcel", pose, 3, 0.08) == 0.08
        or clear_rise(world, "parcel", pose, 1, 0.08) == 0.08
    )
