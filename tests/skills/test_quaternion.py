"""Quaternion maths against scipy's Rotation (scalar-last, like ours)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation

from skills import quaternion as quat

RNG = np.random.default_rng(7)


def random_quats(n: int) -> np.ndarray:
    return Rotation.random(n, random_state=3).as_quat()


def test_multiply_matches_scipy_composition() -> None:
    p, q = random_quats(50), random_quats(50)[::-1]
    expected = (Rotation.from_quat(p) * Rotation.from_quat(q)).as_quat()
    assert_allclose(quat.canonical(quat.multiply(p, q)), quat.canonical(expected), atol=1e-12)


def test_log_exp_are_inverse_and_match_rotvec() -> None:
    q = quat.canonical(random_quats(100))
    r = quat.log(q)
    assert_allclose(2.0 * r, Rotation.from_quat(q).as_rotvec(), atol=1e-12)
    assert_allclose(quat.exp(r), q, atol=1e-12)


def test_log_and_exp_near_identity_are_smooth() -> None:
    tiny = np.array([1e-10, -2e-10, 3e-10])
    assert_allclose(quat.log(quat.exp(tiny)), tiny, atol=1e-18)
    assert_allclose(quat.log(quat.IDENTITY), np.zeros(3), atol=0)


def test_rotation_error_takes_the_short_way_for_either_sign() -> None:
    q, g = random_quats(30), random_quats(30)[::-1]
    expected = (Rotation.from_quat(g) * Rotation.from_quat(q).inv()).as_rotvec()
    assert_allclose(quat.rotation_error(g, q), expected, atol=1e-10)
    assert_allclose(quat.rotation_error(-g, q), expected, atol=1e-10)
    assert np.all(np.linalg.norm(quat.rotation_error(g, q), axis=1) <= np.pi + 1e-12)


def test_scalar_versions_match_vector_versions() -> None:
    q, g = random_quats(20), random_quats(20)[::-1]
    omega = RNG.normal(size=(20, 3))
    for i in range(20):
        gi, qi = tuple(g[i].tolist()), tuple(q[i].tolist())
        assert_allclose(
            quat.rotation_error_scalar(gi, qi), quat.rotation_error(g[i], q[i]), atol=1e-12
        )
        assert_allclose(
            quat.integrate_scalar(qi, tuple(omega[i].tolist()), 0.01),
            quat.integrate(q[i], omega[i], 0.01),
            atol=1e-15,
        )
        assert_allclose(
            np.reshape(quat.matrix_floats(qi), (3, 3)), quat.to_matrix(q[i]), atol=1e-15
        )


def test_batched_matrices_are_the_scalar_formula_to_the_bit() -> None:
    # Batches of every shape and layout, with non-unit, signed-zero and tiny components: each
    # entry must be the scalar formula's own floating-point result, not merely close to it.
    q = np.concatenate(
        (
            RNG.normal(size=(200, 4)),
            [[0.0, -0.0, 0.0, 1.0], [-0.0, -0.0, -0.0, -1.0], [1e-300, -1e-300, 3.0, 0.5]],
        )
    )
    for batch in (q, q.reshape(-1, 1, 4), q.reshape(29, 7, 4)[:, ::-1], q[5]):
        scalar = [quat.matrix_floats(tuple(qi.tolist())) for qi in batch.reshape(-1, 4)]
        got = quat.to_matrix(batch)
        assert got.shape == (*batch.shape[:-1], 3, 3)
        assert got.tobytes() == np.array(scalar).reshape(got.shape).tobytes()
    assert quat.to_matrix([0.0, 0.0, 0.0, 1.0]).tolist() == np.eye(3).tolist()


def test_batched_products_are_the_scalar_formula_to_the_bit() -> None:
    p = np.concatenate((RNG.normal(size=(60, 4)), [[0.0, -0.0, 0.0, 1.0], [-0.0, 0.0, -0.0, -1.0]]))
    q = p[::-1] * 0.5
    scalar = [
        quat.multiply_scalar(tuple(a.tolist()), tuple(b.tolist()))
        for a, b in zip(p, q, strict=True)
    ]
    assert quat.multiply(p, q).tobytes() == np.array(scalar).tobytes()
    assert quat.multiply(p[3], q[3]).tobytes() == np.array(scalar[3]).tobytes()
    # Broadcasting: one quaternion against a batch, on either side.
    assert quat.multiply(p[:, None], q[None, :5]).shape == (62, 5, 4)
    one = [quat.multiply_scalar(tuple(p[0].tolist()), tuple(b.tolist())) for b in q]
    assert quat.multiply(p[0], q).tobytes() == np.array(one).tobytes()


def test_log_is_the_plain_numpy_formula_to_the_bit() -> None:
    # log's clip and norm are called as bare ufuncs: the bits of np.clip and np.linalg.norm.
    q = np.concatenate(
        (
            quat.canonical(random_quats(50)),
            [[0.0, 0.0, 0.0, 1.0], [1e-13, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0000001]],
        )
    )
    for batch in (q, 3.0 * q, q.reshape(53, 1, 4), q[7]):
        v = batch[..., :3]
        vnorm = np.linalg.norm(v, axis=-1)
        angle = np.arctan2(vnorm, np.clip(batch[..., 3], -1.0, 1.0))
        expected = v * np.where(vnorm > 1e-12, angle / np.maximum(vnorm, 1e-12), 1.0)[..., None]
        assert quat.log(batch).tobytes() == expected.tobytes()
    g = random_quats(53)
    conj = quat.conjugate(q)
    expected = 2.0 * quat.log(quat.canonical(quat.multiply(g, conj)))
    assert quat.rotation_error(g, q).tobytes() == expected.tobytes()


def test_make_continuous_removes_sign_flips_only() -> None:
    angles = np.linspace(0, 3 * np.pi, 200)
    q = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), angles)
    flipped = q * np.where(RNG.random(200) < 0.5, -1.0, 1.0)[:, None]
    flipped[0] = q[0]
    fixed = quat.make_continuous(flipped)
    assert_allclose(fixed, q, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", fixed[1:], fixed[:-1]) > 0)


def test_integrate_constant_rate_matches_rotvec_and_keeps_unit_norm() -> None:
    omega = np.array([0.3, -0.5, 1.1])
    q = quat.IDENTITY.copy()
    for _ in range(1000):
        q = quat.integrate(q, omega, 0.002)
    expected = Rotation.from_rotvec(omega * 2.0).as_quat()
    assert abs(np.linalg.norm(q) - 1.0) < 1e-12
    assert quat.angle_between(q, expected) < 1e-9


def test_angular_velocity_of_a_sampled_rotation() -> None:
    t = np.linspace(0, 1, 500)
    omega = np.array([0.0, 0.4, -0.2])
    q = Rotation.from_rotvec(np.outer(t, omega)).as_quat()
    assert_allclose(quat.angular_velocity(q, t)[5:-5], np.tile(omega, (490, 1)), atol=1e-6)


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ([0.0, 0.0, 0.0, 0.0], "expected a non-zero quaternion"),
        ([0.0, 0.0, 1.0], r"expected shape \(\.\.\., 4\)"),
        ([np.nan, 0.0, 0.0, 1.0], "expected finite values"),
    ],
)
def test_as_quaternions_rejects_bad_values(value: list[float], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        quat.as_quaternions(value, "goal")


def test_to_matrix_and_rotate_match_scipy() -> None:
    q = random_quats(10)
    v = RNG.normal(size=(10, 3))
    assert_allclose(quat.to_matrix(q), Rotation.from_quat(q).as_matrix(), atol=1e-12)
    assert_allclose(quat.rotate(q, v), Rotation.from_quat(q).apply(v), atol=1e-12)


def test_from_rpy_matches_scipy_extrinsic_xyz() -> None:
    rpy = RNG.uniform(-3.0, 3.0, size=(20, 3))
    expected = Rotation.from_euler("xyz", rpy).as_quat()
    assert_allclose(quat.angle_between(quat.from_rpy(rpy), expected), 0.0, atol=1e-12)


def test_from_matrix_inverts_to_matrix_with_scipys_sign() -> None:
    q = random_quats(50)
    matrices = quat.to_matrix(q)
    expected = Rotation.from_matrix(matrices).as_quat()
    assert_allclose(quat.from_matrix(matrices), expected, atol=1e-12)
    # A half turn (w = 0) and a trace-0 permutation take the other branches.
    for m in (np.diag([1.0, -1.0, -1.0]), np.array([[0.0, -1, 0], [0, 0, 1], [-1, 0, 0]])):
        assert_allclose(quat.to_matrix(quat.from_matrix(m)), m, atol=1e-15)
        assert_allclose(quat.from_matrix(m), Rotation.from_matrix(m).as_quat(), atol=1e-15)


def test_to_rpy_inverts_from_rpy_and_keeps_the_rotation_in_gimbal_lock() -> None:
    rng = np.random.default_rng(21)
    q = quat.as_quaternions(rng.normal(size=(500, 4)))
    rpy = quat.to_rpy(q)
    assert np.all(np.abs(rpy[:, 1]) <= np.pi / 2)
    assert np.max(quat.angle_between(quat.from_rpy(rpy), q)) < 1e-12
    for pitch in (np.pi / 2, -np.pi / 2):
        locked = quat.from_rpy([0.3, pitch, -0.5])
        # arcsin near 1 keeps half the digits: 1e-8 rad of pitch.
        assert quat.angle_between(quat.from_rpy(quat.to_rpy(locked)), locked) < 1e-7


def test_a_rotation_vector_turns_by_its_length_about_itself() -> None:
    q = quat.from_rotation_vector([0.0, 0.0, 0.6])
    np.testing.assert_allclose(q, quat.from_axis_angle([0.0, 0.0, 1.0], 0.6), atol=1e-15)
    np.testing.assert_allclose(quat.from_rotation_vector(np.zeros(3)), quat.IDENTITY, atol=0)


def test_tilt_is_the_angle_from_upright_whatever_the_yaw() -> None:
    yaw = quat.from_axis_angle([0.0, 0.0, 1.0], np.linspace(-3.0, 3.0, 7))
    tipped = quat.from_axis_angle([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], [0.3, 2.5])
    assert_allclose(quat.tilt(yaw), 0.0, atol=1e-12)
    assert_allclose(quat.tilt(quat.multiply(tipped[:, None], yaw)), [[0.3] * 7, [2.5] * 7])
    assert_allclose(quat.tilt(quat.from_axis_angle([0.0, 1.0, 0.0], 1e-7)), 1e-7, rtol=1e-6)
    assert_allclose(quat.tilt(quat.from_axis_angle([0.0, 1.0, 0.0], np.pi)), np.pi)
