"""Unit-quaternion maths, scalar-last ``(x, y, z, w)`` as scipy and PyBullet use.

Every function broadcasts over leading axes: a quaternion array has shape ``(..., 4)``
and a rotation vector ``(..., 3)``. ``log`` and ``exp`` follow Ude et al. (2014):
``log(q)`` is half the rotation vector of ``q``, so ``2 * log(g * conj(q))`` is the
rotation vector that takes ``q`` to ``g`` (in the world frame).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from skills.types import Array

IDENTITY: Array = np.array([0.0, 0.0, 0.0, 1.0])
_SMALL = 1e-12


def as_quaternions(q: ArrayLike, name: str = "quaternion") -> Array:
    """Coerce to float quaternions ``(..., 4)`` and normalise them.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Scalar-last quaternions, not necessarily unit.
    name : str
        Argument name used in error messages.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions.

    Raises
    ------
    ValueError
        If the last axis is not 4, a value is not finite, or a norm is (near) zero.
    """
    arr = np.asarray(q, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 4:
        raise ValueError(
            f"{name}: expected shape (..., 4) scalar-last (x, y, z, w), got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: expected finite values, got NaN or inf")
    norms = np.linalg.norm(arr, axis=-1, keepdims=True)
    if np.any(norms < 1e-9):
        bad = int(np.argmin(norms.reshape(-1)))
        raise ValueError(f"{name}: expected a non-zero quaternion, got norm 0 at index {bad}")
    return arr / norms


# Each component of ``p * q`` is ``((pw q_i +- px q_j) +- py q_k) +- pz q_l``
# (:func:`multiply_scalar`): per term (rows) and component (columns), the component of ``q``
# and the term's sign. Gathered like this a batch is a handful of numpy calls, each component
# computed with the same operations in the same order as the scalar formula (same bits).
_P_TERMS = np.array([[3] * 4, [0] * 4, [1] * 4, [2] * 4])
_Q_TERMS = np.array([[0, 1, 2, 3], [3, 2, 1, 0], [2, 3, 0, 1], [1, 0, 3, 2]])
_TERM_SIGNS = np.array(
    [[1.0, 1.0, 1.0, 1.0], [1.0, -1.0, 1.0, -1.0], [1.0, 1.0, -1.0, -1.0], [-1.0, 1.0, 1.0, -1.0]]
)


def multiply(p: ArrayLike, q: ArrayLike) -> Array:
    """Hamilton product ``p * q`` of scalar-last quaternions, shape ``(..., 4)``."""
    a = np.asarray(p, dtype=float)
    b = np.asarray(q, dtype=float)
    if a.ndim == 1 and b.ndim == 1:
        # One pair: Python floats do the same IEEE arithmetic without numpy's per-call cost.
        ax, ay, az, aw = a.tolist()
        bx, by, bz, bw = b.tolist()
        return np.array(multiply_scalar((ax, ay, az, aw), (bx, by, bz, bw)))
    # a - b is a + (-b) in IEEE arithmetic: the signed sum is the formula's difference.
    t = a[..., _P_TERMS] * b[..., _Q_TERMS] * _TERM_SIGNS  # (..., term, component)
    return ((t[..., 0, :] + t[..., 1, :]) + t[..., 2, :]) + t[..., 3, :]


def conjugate(q: ArrayLike) -> Array:
    """Conjugate ``(-x, -y, -z, w)``; the inverse of a unit quaternion."""
    c = np.array(q, dtype=float, copy=True)
    c[..., :3] *= -1.0
    return c


def log(q: ArrayLike) -> Array:
    """Quaternion logarithm of unit quaternions, ``(..., 4) -> (..., 3)``.

    Returns ``theta/2 * axis`` for ``q = (sin(theta/2) axis, cos(theta/2))``; zero for the
    identity. No sign canonicalisation is applied: ``log(-q)`` is the long way round.
    """
    arr = np.asarray(q, dtype=float)
    v = arr[..., :3]
    # np.clip and np.linalg.norm(v, axis=-1) without their Python wrappers: the same ufuncs.
    w = np.minimum(np.maximum(arr[..., 3], -1.0), 1.0)
    vnorm = np.sqrt(np.add.reduce(v * v, axis=-1))
    angle = np.arctan2(vnorm, w)
    # angle / vnorm -> 1 as vnorm -> 0 (w -> 1); the series keeps it smooth near identity.
    scale = np.where(vnorm > _SMALL, angle / np.maximum(vnorm, _SMALL), 1.0)
    return v * scale[..., None]


def exp(r: ArrayLike) -> Array:
    """Quaternion exponential, ``(..., 3) -> (..., 4)``: inverse of :func:`log`."""
    arr = np.asarray(r, dtype=float)
    n = np.linalg.norm(arr, axis=-1)
    # sin(n)/n -> 1 - n^2/6 near zero
    sinc = np.where(n > 1e-8, np.sin(n) / np.maximum(n, 1e-300), 1.0 - n * n / 6.0)
    out = np.empty((*arr.shape[:-1], 4))
    out[..., :3] = arr * sinc[..., None]
    out[..., 3] = np.cos(n)
    return out


def canonical(q: ArrayLike) -> Array:
    """The representative with ``w >= 0`` (same rotation, shortest-path log)."""
    arr = np.asarray(q, dtype=float)
    return np.where(arr[..., 3:4] < 0.0, -arr, arr)


#: Conjugation as a product: negates the vector part (each -1 an exact negation).
_CONJUGATE = np.array([-1.0, -1.0, -1.0, 1.0])


def rotation_error(goal: ArrayLike, q: ArrayLike) -> Array:
    """Rotation vector ``2 log(goal * conj(q))`` taking ``q`` to ``goal`` the short way.

    The short way is chosen by canonicalising the error quaternion, so ``goal`` and
    ``-goal`` give the same result.

    Returns
    -------
    ndarray, shape (..., 3)
        Rotation vector in the world frame, radians, norm in [0, pi].
    """
    # q's conjugate as a product with (-1, -1, -1, 1): the same negations as conjugate().
    return 2.0 * log(canonical(multiply(goal, np.asarray(q, dtype=float) * _CONJUGATE)))


def make_continuous(q: ArrayLike) -> Array:
    """Flip signs along a sequence so consecutive quaternions have a positive dot product.

    Parameters
    ----------
    q : array_like, shape (N, 4)
        A time series of unit quaternions (a demonstration).

    Returns
    -------
    ndarray, shape (N, 4)
        The same rotations with no sign jumps (the first sample's sign is kept).
    """
    arr = np.asarray(q, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"quaternions: expected shape (N, 4), got {arr.shape}")
    dots = np.einsum("ij,ij->i", arr[1:], arr[:-1])
    # Each negative dot flips the sign of everything after it: a cumulative parity.
    flips = np.concatenate(([1.0], np.cumprod(np.where(dots < 0.0, -1.0, 1.0))))
    return arr * flips[:, None]


def integrate(q: ArrayLike, omega: ArrayLike, dt: float) -> Array:
    """Advance orientation by a world-frame angular velocity over ``dt``.

    ``q(t + dt) = exp(dt/2 * omega) * q(t)``: the exponential map keeps the norm at one.

    Parameters
    ----------
    q : array_like, shape (..., 4)
    omega : array_like, shape (..., 3)
        Angular velocity in the world frame, rad/s.
    dt : float
        Time step, s.
    """
    return multiply(exp(0.5 * dt * np.asarray(omega, dtype=float)), q)


def angular_velocity(q: ArrayLike, t: ArrayLike) -> Array:
    """World-frame angular velocity of a sampled orientation trajectory.

    Uses second-order finite differences of the (sign-continuous) quaternions:
    ``omega = 2 * qdot * conj(q)``, valid for non-uniform time stamps.

    Parameters
    ----------
    q : array_like, shape (N, 4)
    t : array_like, shape (N,)
        Strictly increasing time stamps, s.

    Returns
    -------
    ndarray, shape (N, 3)
        rad/s, world frame.
    """
    qc = make_continuous(q)
    qdot = np.gradient(qc, np.asarray(t, dtype=float), axis=0)
    return 2.0 * multiply(qdot, conjugate(qc))[:, :3]


# Each entry of the rotation matrix is ``2 (a b +- c d)``, a diagonal one ``1 - 2 (a b + c d)``
# (:func:`matrix_floats`): per entry, row-major, the components ``a, b, c, d`` and the sign of
# the second product. Gathered like this a batch is a handful of numpy calls, and every entry
# is computed with the same operations in the same order as the scalar formula (same bits).
_FACTORS = np.array(
    [
        [1, 0, 0, 0, 0, 1, 0, 1, 0],
        [1, 1, 2, 1, 0, 2, 2, 2, 0],
        [2, 2, 1, 2, 2, 0, 1, 0, 1],
        [2, 3, 3, 3, 2, 3, 3, 3, 1],
    ]
)
_SECOND_SIGN = np.array([1.0, -1.0, 1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0])
_DIAGONAL = np.array([0, 4, 8])


def to_matrix(q: ArrayLike) -> Array:
    """Rotation matrices ``(..., 3, 3)`` from unit quaternions ``(..., 4)``."""
    arr = np.asarray(q, dtype=float)
    if arr.ndim == 1:
        # One rotation: Python floats do the same IEEE arithmetic without numpy's per-call cost.
        x, y, z, w = arr.tolist()
        return np.array(matrix_floats((x, y, z, w))).reshape(3, 3)
    f = arr[..., _FACTORS]  # (..., 4, 9)
    # a - b is a + (-b) in IEEE arithmetic: the signed sum is the formula's difference.
    m = 2 * (f[..., 0, :] * f[..., 1, :] + f[..., 2, :] * f[..., 3, :] * _SECOND_SIGN)
    m[..., _DIAGONAL] = 1 - m[..., _DIAGONAL]
    return m.reshape(*arr.shape[:-1], 3, 3)


def rotate(q: ArrayLike, v: ArrayLike) -> Array:
    """Rotate vectors ``(..., 3)`` by unit quaternions ``(..., 4)``."""
    arr = np.asarray(q, dtype=float)
    vec = np.asarray(v, dtype=float)
    u = arr[..., :3]
    w = arr[..., 3:4]
    t = 2.0 * np.cross(u, vec)
    return vec + w * t + np.cross(u, t)


def tilt(q: ArrayLike) -> Array:
    """Angle (rad, in [0, pi]) between the z axis that unit quaternions ``(..., 4)`` turn world z
    into and world z: how far a body is tipped from upright, whatever its yaw. Shape ``(...)``."""
    z = rotate(q, np.array([0.0, 0.0, 1.0]))
    # atan2 keeps full precision near upright, where arccos of z's height loses half the digits.
    return np.arctan2(np.hypot(z[..., 0], z[..., 1]), z[..., 2])


def z_axis_angle(p: ArrayLike, q: ArrayLike) -> Array:
    """Angle (rad, in [0, pi]) between the z axes orientations ``p`` and ``q`` turn world z
    into: how far apart they are for a body symmetric about its own z (a cylinder), whose
    turns about that axis leave it as it was."""
    a = rotate(p, np.array([0.0, 0.0, 1.0]))
    b = rotate(q, np.array([0.0, 0.0, 1.0]))
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def from_axis_angle(axis: ArrayLike, angle: ArrayLike) -> Array:
    """Quaternions ``(..., 4)`` for rotations of ``angle`` rad about unit ``axis`` ``(..., 3)``."""
    ax = np.asarray(axis, dtype=float)
    ax = ax / np.linalg.norm(ax, axis=-1, keepdims=True)
    half = 0.5 * np.asarray(angle, dtype=float)
    return np.concatenate((ax * np.sin(half)[..., None], np.cos(half)[..., None]), axis=-1)


def angle_between(p: ArrayLike, q: ArrayLike) -> Array:
    """Rotation angle (rad, in [0, pi]) between orientations, sign-independent."""
    rel = multiply(p, conjugate(q))
    # atan2 keeps full precision near zero, where arccos of a dot product loses half the digits.
    return 2.0 * np.arctan2(np.linalg.norm(rel[..., :3], axis=-1), np.abs(rel[..., 3]))


# Scalar versions for per-step loops, where numpy's call overhead dominates 4-vector maths.
Quat = tuple[float, float, float, float]
Vec3 = tuple[float, float, float]


def as_tuple(q: Array) -> Quat:
    """One quaternion (4,) as a float tuple, for the scalar functions below."""
    x, y, z, w = q.tolist()
    return (x, y, z, w)


def rotation_error_scalar(goal: Quat, q: Quat) -> Vec3:
    """:func:`rotation_error` for one pair of quaternions given as float tuples."""
    gx, gy, gz, gw = goal
    qx, qy, qz, qw = q
    # g * conj(q), then the short way (w >= 0)
    ex = -gw * qx + gx * qw - gy * qz + gz * qy
    ey = -gw * qy + gx * qz + gy * qw - gz * qx
    ez = -gw * qz - gx * qy + gy * qx + gz * qw
    ew = gw * qw + gx * qx + gy * qy + gz * qz
    if ew < 0.0:
        ex, ey, ez, ew = -ex, -ey, -ez, -ew
    vn = math.sqrt(ex * ex + ey * ey + ez * ez)
    sc = 2.0 * math.atan2(vn, ew) / vn if vn > _SMALL else 2.0
    return ex * sc, ey * sc, ez * sc


def integrate_scalar(q: Quat, omega: Vec3, dt: float) -> Quat:
    """:func:`integrate` for one quaternion and angular velocity given as float tuples."""
    wx, wy, wz = omega
    half = 0.5 * dt
    rn = half * math.sqrt(wx * wx + wy * wy + wz * wz)
    sn = math.sin(rn) / rn * half if rn > 1e-8 else half
    ax, ay, az, aw = wx * sn, wy * sn, wz * sn, math.cos(rn)
    bx, by, bz, bw = q
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def matrix_floats(q: Quat) -> tuple[float, ...]:
    """Rotation matrix entries of one quaternion given as floats, row-major (9 floats).

    For per-tick code on a single rotation, where numpy's per-call cost exceeds the arithmetic.
    """
    x, y, z, w = q
    return (
        1 - 2 * (y * y + z * z),
        2 * (x * y - z * w),
        2 * (x * z + y * w),
        2 * (x * y + z * w),
        1 - 2 * (x * x + z * z),
        2 * (y * z - x * w),
        2 * (x * z - y * w),
        2 * (y * z + x * w),
        1 - 2 * (x * x + y * y),
    )


def multiply_scalar(a: Quat, b: Quat) -> Quat:
    """Hamilton product ``a * b`` of two quaternions given as floats."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def from_rpy(rpy: ArrayLike) -> Array:
    """Quaternions ``(..., 4)`` of extrinsic x-y-z angles ``(roll, pitch, yaw)`` ``(..., 3)``, rad.

    Rotations about the fixed x, then y, then z axes (the URDF and PyBullet convention):
    ``q = q_z(yaw) * q_y(pitch) * q_x(roll)``.
    """
    half = 0.5 * np.asarray(rpy, dtype=float)
    cr, cp, cy = np.cos(half[..., 0]), np.cos(half[..., 1]), np.cos(half[..., 2])
    sr, sp, sy = np.sin(half[..., 0]), np.sin(half[..., 1]), np.sin(half[..., 2])
    return np.stack(
        (
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ),
        axis=-1,
    )


def to_rpy(q: ArrayLike) -> Array:
    """Extrinsic x-y-z angles ``(roll, pitch, yaw)`` ``(..., 3)``, rad, of quaternions
    ``(..., 4)``: the inverse of :func:`from_rpy`, pitch in [-pi/2, pi/2].

    At pitch +-pi/2 (gimbal lock) roll and yaw are not separate; roll takes their sum and yaw
    is 0, which gives the same rotation.
    """
    arr = np.asarray(q, dtype=float)
    x, y, z, w = arr[..., 0], arr[..., 1], arr[..., 2], arr[..., 3]
    sin_pitch = np.clip(2.0 * (w * y - z * x), -1.0, 1.0)
    pitch = np.arcsin(sin_pitch)
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    locked = np.abs(sin_pitch) > 1.0 - 1e-12
    # In gimbal lock only roll -/+ yaw is defined: put it all in roll.
    both = 2.0 * np.arctan2(x, w) * np.sign(sin_pitch)
    roll = np.where(locked, np.sign(sin_pitch) * both, roll)
    yaw = np.where(locked, 0.0, yaw)
    return np.stack((roll, pitch, yaw), axis=-1)


def from_rotation_vector(v: ArrayLike) -> Array:
    """Quaternions ``(..., 4)`` of rotation vectors ``(..., 3)`` (axis times angle, rad)."""
    return exp(0.5 * np.asarray(v, dtype=float))


def from_matrix(m: ArrayLike) -> Array:
    """Unit quaternions ``(..., 4)`` of rotation matrices ``(..., 3, 3)``.

    Shepperd's method: each quaternion is read from its largest of ``x, y, z, w`` (the first
    on a tie), so no division is by a small number. The sign is the one that branch gives,
    as scipy's ``Rotation.from_matrix`` does; :func:`canonical` picks ``w >= 0``.
    """
    r = np.asarray(m, dtype=float)
    if r.shape[-2:] != (3, 3):
        raise ValueError(f"from_matrix: expected shape (..., 3, 3), got {r.shape}")
    r00, r11, r22 = r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]
    # Four times the squares of w, x, y, z; the largest picks the branch.
    squares = np.stack(
        (1 + r00 - r11 - r22, 1 - r00 + r11 - r22, 1 - r00 - r11 + r22, 1 + r00 + r11 + r22),
        axis=-1,
    )
    best = np.argmax(squares, axis=-1)
    s = 2.0 * np.sqrt(np.maximum(np.take_along_axis(squares, best[..., None], -1)[..., 0], 0.0))
    yz = r[..., 1, 2] + r[..., 2, 1]
    xz = r[..., 0, 2] + r[..., 2, 0]
    xy = r[..., 0, 1] + r[..., 1, 0]
    wx = r[..., 2, 1] - r[..., 1, 2]
    wy = r[..., 0, 2] - r[..., 2, 0]
    wz = r[..., 1, 0] - r[..., 0, 1]
    candidates = np.stack(
        (
            np.stack((s * s / 4, xy, xz, wx), axis=-1),
            np.stack((xy, s * s / 4, yz, wy), axis=-1),
            np.stack((xz, yz, s * s / 4, wz), axis=-1),
            np.stack((wx, wy, wz, s * s / 4), axis=-1),
        ),
        axis=-2,
    )
    q = np.take_along_axis(candidates, best[..., None, None], -2)[..., 0, :] / s[..., None]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)
