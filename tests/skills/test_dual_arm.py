"""Grasp map and composition: rigid-body consistency and space orthogonality."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.dual_arm import (
    GraspGeometry,
    contact_twists,
    grasp_matrix,
    integrate_twist,
    shift_along_face,
    skew,
)
from skills.vocabulary import Arm

RNG = np.random.default_rng(11)


def test_skew_is_the_cross_product() -> None:
    r, x = RNG.normal(size=3), RNG.normal(size=3)
    assert_allclose(skew(r) @ x, np.cross(r, x), atol=1e-15)


def test_grasp_matrix_transpose_gives_rigid_body_contact_twists() -> None:
    r = RNG.normal(size=(2, 3))
    twist = RNG.normal(size=6)
    g = grasp_matrix(r)
    assert g.shape == (6, 12)
    per_contact = (g.T @ twist).reshape(2, 6)
    for i in range(2):
        assert_allclose(per_contact[i, :3], twist[:3] + np.cross(twist[3:], r[i]), atol=1e-14)
        assert_allclose(per_contact[i, 3:], twist[3:], atol=1e-15)
    assert_allclose(contact_twists(twist, r), per_contact, atol=1e-14)


def test_grasp_matrix_sums_contact_wrenches_at_the_centre() -> None:
    r = np.array([[0.0, 0.15, 0.0], [0.0, -0.15, 0.0]])
    squeeze = np.array([0.0, -20.0, 0.0, 0, 0, 0, 0.0, 20.0, 0.0, 0, 0, 0])
    assert_allclose(grasp_matrix(r) @ squeeze, np.zeros(6), atol=1e-12)  # internal force only
    lift = np.array([0.0, 0.0, 5.0, 0, 0, 0, 0.0, 0.0, 5.0, 0, 0, 0])
    assert_allclose(grasp_matrix(r) @ lift, [0, 0, 10.0, 0, 0, 0], atol=1e-12)


def palms_in_world(
    obj_p: np.ndarray, obj_q: np.ndarray, rel_p: np.ndarray, rel_q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``palm2world`` (2, 3), (2, 4) from ``object2world`` and each ``palm2object``."""
    return obj_p + quat.rotate(obj_q, rel_p), quat.multiply(obj_q, rel_q)


def test_absolute_skills_alone_move_the_palms_as_one_rigid_body() -> None:
    geometry = GraspGeometry.lateral(0.30)
    obj_p, obj_q = np.array([0.6, 0.0, 0.675]), quat.from_axis_angle([0.1, 0.2, 1.0], 0.3)
    rel_p = np.stack((geometry.left_position, geometry.right_position))
    rel_q = np.stack((geometry.left_orientation, geometry.right_orientation))
    palms_p, palms_q = palms_in_world(obj_p, obj_q, rel_p, rel_q)
    d0 = np.linalg.norm(palms_p[0] - palms_p[1])
    rel0 = quat.multiply(quat.conjugate(palms_q[0]), palms_q[1])
    dt = 0.004
    for k in range(1000):
        # Two absolute skills with time-varying twists, mixed with weights.
        t = k * dt
        twists = np.array(
            [
                [0.1 * np.cos(t), 0.05, 0.02 * np.sin(3 * t), 0.0, 0.0, 0.4 * np.sin(t)],
                [0.0, -0.03, 0.01, 0.2 * np.cos(2 * t), -0.1, 0.3],
            ]
        )
        obj_twist = np.array([0.7, 0.3]) @ twists
        palm_twists = contact_twists(obj_twist, palms_p - obj_p)
        obj_p, obj_q = integrate_twist(obj_p, obj_q, obj_twist, dt)
        palms_p, palms_q = integrate_twist(palms_p, palms_q, palm_twists, dt)
    # Distance and relative orientation between the palms are unchanged (rounding only).
    assert abs(np.linalg.norm(palms_p[0] - palms_p[1]) - d0) < 1e-9
    rel = quat.multiply(quat.conjugate(palms_q[0]), palms_q[1])
    assert quat.angle_between(rel, rel0) < 1e-9
    # And the palms are still where the object's pose says they are.
    expect_p, expect_q = palms_in_world(obj_p, obj_q, rel_p, rel_q)
    assert_allclose(palms_p, expect_p, atol=1e-9)
    assert np.all(quat.angle_between(palms_q, expect_q) < 1e-9)


def test_lateral_geometry_faces_the_palms_inward() -> None:
    g = GraspGeometry.lateral(0.30)
    assert_allclose(g.position(Arm.LEFT), [0, 0.15, 0])
    # The palm's contact axis (z) points along the inward normal.
    assert_allclose(quat.rotate(g.orientation(Arm.LEFT), [0, 0, 1.0]), [0, -1.0, 0], atol=1e-12)
    assert_allclose(quat.rotate(g.orientation(Arm.RIGHT), [0, 0, 1.0]), [0, 1.0, 0], atol=1e-12)
    assert_allclose(g.squeezed(0.015).position(Arm.RIGHT), [0, -0.135, 0], atol=1e-15)
    # The palm's x axis points down, as the simulator's palms are mounted.
    assert_allclose(quat.rotate(g.orientation(Arm.LEFT), [1.0, 0, 0]), [0, 0, -1.0], atol=1e-12)
    thick = GraspGeometry.lateral(0.30, palm_thickness=0.02)
    assert_allclose(thick.position(Arm.LEFT), [0, 0.16, 0], atol=1e-15)


def test_lateral_geometry_matches_the_simulator_palm_frames() -> None:
    # Palm axes as columns in the object frame: x down, z into the object.
    left = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])
    right = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    g = GraspGeometry.lateral(0.30)
    assert_allclose(quat.to_matrix(g.orientation(Arm.LEFT)), left, atol=1e-12)
    assert_allclose(quat.to_matrix(g.orientation(Arm.RIGHT)), right, atol=1e-12)


def test_integrate_twist_matches_a_pure_rotation_about_a_point() -> None:
    # Spin about z at 1 rad/s through the origin; a frame at (1, 0, 0) moves on a circle.
    p, q = np.array([1.0, 0.0, 0.0]), quat.IDENTITY.copy()
    for _ in range(100):
        p, q = integrate_twist(p, q, twist_at(p, twist_origin=np.array([0, 0, 0, 0, 0, 1.0])), 0.01)
    assert_allclose(p, [np.cos(1.0), np.sin(1.0), 0.0], atol=1e-12)
    assert quat.angle_between(q, quat.from_axis_angle([0, 0, 1], 1.0)) < 1e-12


def twist_at(point: np.ndarray, twist_origin: np.ndarray) -> np.ndarray:
    """The twist of a body, given at the origin, expressed at ``point``."""
    return np.concatenate((twist_origin[:3] + np.cross(twist_origin[3:], point), twist_origin[3:]))


def test_shift_along_face_counts_sliding_not_pressing() -> None:
    reference = np.array([[0.0, 0.16, 0.0], [0.0, -0.16, 0.0]])  # palms on the +-y faces
    # sliding 30 mm down the face and 40 mm along x is 50 mm; pressing 5 mm deeper is none
    moved = reference + np.array([[0.04, -0.005, -0.03], [0.0, 0.005, 0.0]])
    assert_allclose(shift_along_face(moved, reference), [0.05, 0.0], atol=1e-12)
    # the object turned 10 degrees about z in the grip: the palm moved along the face by
    # 0.16 sin(10 deg) (and towards the centre by 0.16 (1 - cos), which is not counted)
    turned = quat.rotate(quat.from_axis_angle([0.0, 0.0, 1.0], np.radians(10.0)), reference)
    assert_allclose(shift_along_face(turned, reference), 0.16 * np.sin(np.radians(10.0)))
