"""The physical truth: what physics builds, what the robot is told and what it senses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from skills import quaternion as quat
from worlds.spec import SceneSpec
from worlds.truth import ObjectTruth, PhysicalTruth, physical_scene, sensed_pose

PARCEL = ObjectTruth("parcel", 1.4, 0.75, (0.004, -0.003), math.radians(2.0))
TRUTH = PhysicalTruth((PARCEL,), palm_friction_scale=0.85, table_dz_m=-0.02)


def test_the_physical_scene_scales_and_raises_what_the_truth_says() -> None:
    spec = SceneSpec()
    built = physical_scene(spec, TRUTH)
    told, true = spec.objects[0], built.objects[0]
    assert_allclose([true.mass, true.friction], [1.4 * told.mass, 0.75 * told.friction])
    assert_allclose(true.position, np.add(told.position, [0.0, 0.0, -0.02]), atol=1e-15)
    assert_allclose(built.table.position, np.add(spec.table.position, [0, 0, -0.02]))
    assert_allclose(built.table.size, np.add(spec.table.size, [0, 0, -0.02]))
    # The object still rests on the table: its bottom on the true top.
    assert_allclose(true.position[2] - 0.075, built.table.position[2], atol=1e-12)
    assert physical_scene(spec, PhysicalTruth()) == spec


def test_a_truth_the_scene_cannot_take_is_refused() -> None:
    with pytest.raises(ValueError, match=r"object names in \['parcel'\], got \['box'\]"):
        physical_scene(SceneSpec(), PhysicalTruth((ObjectTruth("box"),)))
    with pytest.raises(ValueError, match=r"table_dz_m > -0.6 m .* got -0.7"):
        physical_scene(SceneSpec(), PhysicalTruth(table_dz_m=-0.7))
    with pytest.raises(ValueError, match="mass_scale > 0"):
        ObjectTruth("parcel", mass_scale=0.0)
    with pytest.raises(ValueError, match="palm_friction_scale finite and >= 0"):
        PhysicalTruth(palm_friction_scale=-1.0)


def test_the_sensed_pose_is_offset_along_x_y_and_yaw_only() -> None:
    q = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.3)
    p, sensed_q = sensed_pose([0.6, 0.1, 0.675], q, PARCEL)
    assert_allclose(p, [0.604, 0.097, 0.675], atol=1e-15)
    expected = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.3 + math.radians(2.0))
    assert_allclose(quat.angle_between(sensed_q, expected), 0.0, atol=1e-7)


@pytest.mark.sim
def test_physics_has_the_truth_and_the_robot_the_file() -> None:
    import pybullet as pb

    from skills.vocabulary import ARMS
    from worlds.palm_poses import lateral_grasp_palm_poses
    from worlds.scene import Scene
    from worlds.sim_world import SimWorld
    from worlds.testing import DEFAULT_WORLD
    from worlds.world_file import load_world

    world = load_world(DEFAULT_WORLD)
    told = world.objects[0]
    with Scene.from_world(world) as plain:
        palm_mu = {
            a: pb.getDynamicsInfo(
                plain.robot_ids[plain.robot.arms[a].body],
                plain.robot.arms[a].palm_link,
                physicsClientId=plain.client,
            )[1]
            for a in ARMS
        }
    with SimWorld(world, truth=TRUTH) as sim:
        scene, c = sim.scene, sim.scene.client
        body = scene.object_ids["parcel"]
        mass, mu = pb.getDynamicsInfo(body, -1, physicsClientId=c)[:2]
        assert_allclose([mass, mu], [1.4 * told.mass, 0.75 * told.friction], rtol=1e-12)
        for a in ARMS:
            arm = scene.robot.arms[a]
            got = pb.getDynamicsInfo(scene.robot_ids[arm.body], arm.palm_link, physicsClientId=c)
            assert_allclose(got[1], 0.85 * palm_mu[a], rtol=1e-12)
        top = pb.getAABB(scene.table_id, physicsClientId=c)[1][2]
        assert_allclose(top, world.table.position[2] - 0.02, atol=1e-3)  # AABB margin
        # What the reasoner is given: the file's mass and friction, the sensed start pose.
        context = sim.object_context("parcel")
        assert (context.mass_kg, context.friction) == (told.mass, told.friction)
        true_start = np.add(told.pose.position, [0.0, 0.0, -0.02])
        assert_allclose(context.position, true_start + [0.004, -0.003, 0.0], atol=1e-12)
        assert_allclose(context.yaw, math.radians(2.0), atol=1e-12)
        assert scene.spec.objects[0].mass == told.mass  # the scene's spec stays the file's
        # Sensed off until both palms hold it, where it is from then on.
        assert_allclose(sim.object_pose("parcel").position, context.position, atol=1e-12)
        half = told.shape.size[1] / 2.0  # type: ignore[union-attr]
        sim.scene.place_palms(
            lateral_grasp_palm_poses(true_start, half, world.robot.palm_size[2], gap=-0.004)
        )
        for _ in range(10):
            sim.advance(1.0 / 60.0)
            if all(sim.contact_force(a, "parcel") >= 0.5 for a in ARMS):
                break
        assert all(sim.contact_force(a, "parcel") >= 0.5 for a in ARMS)
        p, q = scene.object_pose("parcel")
        assert_array_equal(sim.object_pose("parcel").position, p)
        assert_array_equal(sim.object_pose("parcel").orientation, q)
