"""Arm links predicted along a palm path by inverse kinematics on a kinematic copy
(:mod:`worlds.arm_prediction`), on the iCub, whose torso swings both arms: the prediction is
checked against where the physics puts the forearms under impedance control, and against the
rigid carry it replaces on robots whose arms share joints."""

from __future__ import annotations

import numpy as np
import pybullet as pb
import pytest
from numpy.typing import NDArray

from skills.vocabulary import ARMS, Arm
from tests.worlds.test_icub import WORLD, empty_scene, minimum_jerk, start
from worlds.arm_prediction import ArmPredictor
from worlds.control import PalmCommand
from worlds.palm_poses import lateral_grasp_palm_poses
from worlds.scene import Scene
from worlds.world_file import World, load_world

pytestmark = pytest.mark.sim


@pytest.fixture(scope="module")
def world() -> World:
    return load_world(WORLD)


def _forearm_links(scene: Scene, arm: Arm) -> tuple[int, ...]:
    body, c = scene.robot_ids[scene.robot.arms[arm].body], scene.client
    names = scene.robot.forearm_link_names[arm]
    return tuple(
        j
        for j in range(pb.getNumJoints(body, physicsClientId=c))
        if pb.getJointInfo(body, j, physicsClientId=c)[12].decode() in names
    )


def _frames(scene: Scene, arm: Arm, links: tuple[int, ...]) -> NDArray[np.float64]:
    body = scene.robot_ids[scene.robot.arms[arm].body]
    read = pb.getLinkStates(
        body, list(links), computeForwardKinematics=1, physicsClientId=scene.client
    )
    return np.array([s[0] for s in read])


def test_a_still_path_predicts_the_links_where_they_are(world: World) -> None:
    centre, half_span, thickness = start(world)
    with empty_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.02))
        scene.step(120)
        palms = [scene.palm_state(a) for a in ARMS]
        path_p = np.tile(np.array([p.position for p in palms]), (5, 1, 1))
        path_q = np.tile(np.array([p.quaternion for p in palms]), (5, 1, 1))
        links = {a: _forearm_links(scene, a) for a in ARMS}
        predictor = ArmPredictor(scene)
        try:
            frames = predictor.link_frames(path_p, path_q, links)
        finally:
            predictor.close()
        for arm in ARMS:
            now = _frames(scene, arm, links[arm])
            np.testing.assert_allclose(
                frames[arm].positions, np.broadcast_to(now, (5, *now.shape)), atol=1e-3
            )


def test_the_forearms_are_predicted_along_a_sideways_carry(world: World) -> None:
    """Palms carried 12 cm to the robot's right (the trials' goals lie 11-14 cm to either
    side): the physics' forearms end within 2 cm of the prediction, where the rigid carry
    misses by more (the torso turns and leans, which the palms alone do not say)."""
    centre, half_span, thickness = start(world)
    goal = centre + np.array([0.0, -0.12, 0.03])
    with empty_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.02))
        scene.step(120)
        links = {a: _forearm_links(scene, a) for a in ARMS}
        before = {a: _frames(scene, a, links[a]) for a in ARMS}
        palms_before = {a: scene.palm_state(a) for a in ARMS}
        samples = np.linspace(0.0, 1.0, 31)
        poses = [
            lateral_grasp_palm_poses(
                centre + (goal - centre) * minimum_jerk(s), half_span, thickness, 0.02
            )
            for s in samples
        ]
        path_p = np.array([[p[a][0] for a in ARMS] for p in poses])
        path_q = np.array([[p[a][1] for a in ARMS] for p in poses])
        predictor = ArmPredictor(scene)
        try:
            predicted = predictor.link_frames(path_p, path_q, links)
        finally:
            predictor.close()
        per_command = scene.spec.physics_hz // scene.spec.control_hz
        steps = 2 * scene.spec.physics_hz  # 2 s
        for k in range(0, steps, per_command):
            s = float(minimum_jerk((k + per_command) / steps))
            for arm, (p, q) in lateral_grasp_palm_poses(
                centre + (goal - centre) * s, half_span, thickness, 0.02
            ).items():
                scene.set_palm_command(arm, PalmCommand(p, q))
            scene.step(per_command)
        scene.step(240)
        for arm in ARMS:
            actual = _frames(scene, arm, links[arm])
            ik_miss = np.linalg.norm(predicted[arm].positions[-1] - actual, axis=-1).max()
            # The rigid carry: the links keep their offset from the palm (no turn here).
            shift = scene.palm_state(arm).position - palms_before[arm].position
            rigid_miss = np.linalg.norm(before[arm] + shift - actual, axis=-1).max()
            assert ik_miss < 0.02, f"{arm}: IK prediction off by {ik_miss * 1000:.1f} mm"
            assert ik_miss < rigid_miss, (arm, ik_miss, rigid_miss)
            print(arm, f"ik {ik_miss * 1000:.1f} mm, rigid {rigid_miss * 1000:.1f} mm")


def test_predictors_of_one_robot_share_its_copy_and_answer_alike(world: World) -> None:
    """The process keeps one kinematic copy per robot: a second predictor loads nothing, and
    what it predicts does not depend on a prediction made before it (each solve resets the
    joints it moves), bit for bit."""
    centre, half_span, thickness = start(world)
    with empty_scene(world) as scene:
        scene.place_palms(lateral_grasp_palm_poses(centre, half_span, thickness, gap=0.02))
        scene.step(60)
        links = {a: _forearm_links(scene, a) for a in ARMS}
        palms = [scene.palm_state(a) for a in ARMS]
        still_p = np.tile(np.array([p.position for p in palms]), (3, 1, 1))
        still_q = np.tile(np.array([p.quaternion for p in palms]), (3, 1, 1))
        first = ArmPredictor(scene)
        alone = first.link_frames(still_p, still_q, links)
        # Another path first, far from this one: the copy's joints end elsewhere.
        aside = still_p + np.array([0.0, -0.12, 0.05])
        first.link_frames(aside, still_q, links)
        client = first._client
        first.close()
        assert pb.isConnected(physicsClientId=client)  # closing lets go, it does not unload
        second = ArmPredictor(scene)
        assert second._client == client
        after = second.link_frames(still_p, still_q, links)
        second.close()
        for arm in ARMS:
            np.testing.assert_array_equal(after[arm].positions, alone[arm].positions)
            np.testing.assert_array_equal(after[arm].quaternions, alone[arm].quaternions)
