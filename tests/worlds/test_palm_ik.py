"""Palm inverse kinematics (worlds.palm_ik): the damped step's formula and solves with known
answers."""

from __future__ import annotations

import numpy as np
import pybullet as pb
import pytest

from skills import quaternion as quat
from skills.vocabulary import Arm
from worlds.palm_ik import dls_step, solve_palms
from worlds.scene import Scene
from worlds.spec import SceneSpec


def test_the_step_is_the_weighted_damped_pseudo_inverse_with_the_posture_in_its_null_space() -> (
    None
):
    rng = np.random.default_rng(0)
    jacobian = rng.normal(size=(6, 7))
    error = 1e-3 * rng.normal(size=6)
    q, rest = rng.normal(size=7), rng.normal(size=7)
    cost = rng.uniform(0.5, 2.0, size=7)
    damping, gain = 1e-2, 0.1
    w_inv = np.diag(1.0 / cost)
    pinv = (
        w_inv @ jacobian.T @ np.linalg.inv(jacobian @ w_inv @ jacobian.T + damping**2 * np.eye(6))
    )
    expected = pinv @ error + (np.eye(7) - pinv @ jacobian) @ (gain * (rest - q))
    expected *= min(1.0, 0.2 / np.max(np.abs(expected)))
    got = dls_step(jacobian, error, q, rest, cost, damping, gain, 0.2)
    np.testing.assert_allclose(got, expected, atol=1e-12)
    assert np.max(np.abs(dls_step(jacobian, 100 * error, q, rest, cost))) <= 0.2 + 1e-12


@pytest.mark.sim
def test_a_palm_pose_reached_by_some_joints_is_solved_to_it() -> None:
    """Pose the arm at random joints, read its palm, start elsewhere: the solve puts the palm
    back on that pose, inside the joint limits. The pull to the rest posture leaks through the
    damped projection: a residual of a tenth of a millimetre, not the tolerance asked."""
    with Scene(SceneSpec()) as scene:
        spec = scene.robot.arms[Arm.LEFT]
        body, c = scene.robot_ids[spec.body], scene.client
        joints = list(spec.joint_indices)
        lower, upper = np.asarray(spec.lower), np.asarray(spec.upper)
        rng = np.random.default_rng(5)
        goal_q = rng.uniform(0.5 * lower, 0.5 * upper)
        for joint, value in zip(joints, goal_q, strict=True):
            pb.resetJointState(body, joint, float(value), 0.0, physicsClientId=c)
        state = pb.getLinkState(body, spec.palm_link, computeForwardKinematics=1, physicsClientId=c)
        target = (np.asarray(state[4]), np.asarray(state[5]))
        start = np.clip(goal_q + 0.3, lower, upper)
        q = solve_palms(
            c,
            body,
            joints,
            [spec.palm_link],
            [target],
            start,
            lower,
            upper,
            np.zeros(len(joints)),
            np.ones(len(joints)),
            iterations=500,
            tolerance=1e-6,
        )
        assert np.all(q >= lower) and np.all(q <= upper)
        reached = pb.getLinkState(
            body, spec.palm_link, computeForwardKinematics=1, physicsClientId=c
        )
        assert np.linalg.norm(np.asarray(reached[4]) - target[0]) < 3e-4
        assert np.linalg.norm(quat.rotation_error(target[1], np.asarray(reached[5]))) < 1e-3
