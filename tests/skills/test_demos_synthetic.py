"""The synthetic human-like teachers: seeded, at rest at both ends, and learnable."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.demonstration import Demonstration
from skills.demos import avoidance_demo, rotation_demo, straight_demo
from skills.pose_dmp import PoseState, fit_pose, pose_rollout

START = np.array([0.4, -0.3, 0.8])
GOAL = np.array([0.4, 0.3, 0.8])
Z = np.array([0.0, 0.0, 1.0])


def test_avoidance_demo_keeps_its_clearance_and_rests_at_both_ends() -> None:
    centre = np.array([0.4, 0.0, 0.8])  # on the line: the teacher goes over the top
    t, p, q = avoidance_demo(
        START, GOAL, centre, 0.06, clearance=0.05, rng=np.random.default_rng(1)
    )
    assert t.shape == (400,) and p.shape == (400, 3) and q.shape == (400, 4)
    assert_allclose(q, np.tile(quat.IDENTITY, (400, 1)))
    assert_allclose(p[[0, -1]], [START, GOAL], atol=1e-12)
    demo = Demonstration.create(t, p, q)
    v, a = demo.position_derivatives()
    # Bound: one-sided finite differences of a path at rest: h^2 jerk / 3 ~ 1e-4 m/s.
    assert_allclose(v[[0, -1]], 0.0, atol=5e-4)
    dist = np.linalg.norm(p - centre, axis=1)
    # Bound: the via-point sits at 0.11 m; tremor and via jitter are 0.5 mm.
    assert 0.105 < dist.min() < 0.115
    i = int(np.argmin(dist))
    assert p[i, 2] > centre[2]  # over the top
    assert np.max(np.linalg.norm(a, axis=1)) < 20.0  # a hand's accelerations, not noise


def test_avoidance_demo_passes_on_the_free_side_of_an_off_line_obstacle() -> None:
    centre = np.array([0.4, 0.0, 0.79])  # below the line: pass above
    _, p, _ = avoidance_demo(START, GOAL, centre, 0.05, noise=0.0)
    i = int(np.argmin(np.linalg.norm(p - centre, axis=1)))
    assert p[i, 2] > 0.8
    assert_allclose(np.linalg.norm(p[i] - centre), 0.1, atol=2e-3)


def test_demos_are_deterministic_for_a_seed_and_vary_between_seeds() -> None:
    a = avoidance_demo(START, GOAL, [0.4, 0, 0.8], 0.06, rng=np.random.default_rng(5))[1]
    b = avoidance_demo(START, GOAL, [0.4, 0, 0.8], 0.06, rng=np.random.default_rng(5))[1]
    c = avoidance_demo(START, GOAL, [0.4, 0, 0.8], 0.06, rng=np.random.default_rng(6))[1]
    assert_allclose(a, b, rtol=0, atol=0)
    assert np.max(np.abs(a - c)) > 1e-4


def test_straight_demo_is_a_line_without_noise() -> None:
    _, p, _ = straight_demo(START, GOAL, noise=0.0)
    assert_allclose(p[:, [0, 2]], np.tile(START[[0, 2]], (len(p), 1)), atol=1e-12)
    assert np.all(np.diff(p[:, 1]) >= -1e-12)


def test_rotation_demo_turns_about_world_z_and_rests() -> None:
    t, p, q = rotation_demo(math.pi / 2, rng=np.random.default_rng(2))
    assert_allclose(p, np.tile([0.5, 0.0, 0.8], (len(t), 1)))
    assert_allclose(q[-1], quat.from_axis_angle(Z, math.pi / 2), atol=1e-12)
    assert_allclose(q[0], quat.IDENTITY, atol=1e-12)
    omega, _ = Demonstration.create(t, p, q).orientation_derivatives()
    # Bound: one-sided finite differences of a turn at rest: h^2 jerk / 3 ~ 1e-4 rad/s.
    assert_allclose(omega[[0, -1]], 0.0, atol=5e-4)


def test_fit_pose_reproduces_the_turn_and_generalises_to_45_degrees() -> None:
    t, p, q = rotation_demo(math.pi / 2, duration=2.0, rng=np.random.default_rng(3))
    demo = Demonstration.create(t, p, q, name="turn")
    model = fit_pose(demo)
    start = PoseState.at_rest(p[0], q[0])
    n = len(t) - 1
    target = model.target(p[0], q[0], p[-1], q[-1])
    traj = pose_rollout(model, target, start, t[1], n)
    # Bound: 5 mrad along the way (50 basis functions for a 1.57 rad turn with tremor).
    assert np.max(quat.angle_between(traj.orientations, q)) < 5e-3
    goal45 = quat.from_axis_angle(Z, math.pi / 4)
    target45 = model.target(p[0], q[0], p[0], goal45)
    traj45 = pose_rollout(model, target45, start, 0.004, int(3.0 / 0.004))
    assert quat.angle_between(traj45.orientations[-1], goal45) < 1e-3
    assert np.linalg.norm(traj45.angular_velocities[-1]) < 1e-2
    # It stays a turn about z: tilt away from the vertical stays within the tremor's size.
    up = quat.rotate(traj45.orientations, Z)
    assert np.max(np.arccos(np.clip(up[:, 2], -1, 1))) < 0.03
    yaw = 2 * np.arctan2(traj45.orientations[:, 2], traj45.orientations[:, 3])
    assert yaw.max() < math.pi / 4 * 1.1  # no large overshoot


def test_bad_teacher_arguments_name_the_field() -> None:
    with pytest.raises(ValueError, match="obstacle_radius"):
        avoidance_demo(START, GOAL, [0.4, 0, 0.8], 0.0)
    with pytest.raises(ValueError, match="goal: expected a goal away from the start"):
        straight_demo(START, START)
    with pytest.raises(ValueError, match="n_samples"):
        straight_demo(START, GOAL, n_samples=5)
    with pytest.raises(ValueError, match="angle"):
        rotation_demo(0.0)
    with pytest.raises(ValueError, match="noise"):
        rotation_demo(1.0, noise=-1.0)
