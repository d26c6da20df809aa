"""The palm impedance law: its pure linearisation, compiled body by body (its values, the
commands, states and gains it works with, are :mod:`worlds.impedance_values`).

Each palm is pulled to a target pose by a task-space spring-damper; gravity is compensated with
PyBullet's inverse dynamics; a rest-posture spring acts in the Jacobian null space; a repulsive
torque keeps the joints off their limits; torques are clipped to the joint limits. PyBullet's
velocity motors are switched off and the torques go out with TORQUE_CONTROL
(:class:`worlds.control.DualArmImpedanceController`, which reads PyBullet; this module does not).

The law is an affine map of the joint state of one body, re-linearised every ``refresh_every``
physics steps around the configuration ``q0`` (palm poses ``x0``, Jacobian ``J``, gravity torque
``g``, inertia ``M``)::

    tau(q, qd) = g + G (a + a_rate * t + B q + C qd) + tau_limits(q)
    B = -(J^T K J + k_n P W),   C = -(J^T D J + d_n P W + d_j I),
    P = I - J^T (J J^T + l^2 I)^-1 J
    a = J^T K (e0 + J q0) + J^T D xd* + k_n P W q_rest,   a_rate = J^T K xd*,
    G = M (M - dt C)^-1

A body may carry several palms (its *tasks*): ``J`` stacks their 6-row Jacobians over all the
body's joints, ``K`` and ``D`` are block-diagonal, and ``e0``, ``xd*`` stack their pose errors and
twists. Joints that move several palms (a humanoid's torso) so get the sum of every palm's
spring and damper torques, the posture acts in the null space of all palms at once and the
implicit damping step ``G`` uses the body's whole inertia: the law is coupled over all joints.
``W`` weighs the posture spring per joint (1 on an arm; a torso is held upright more firmly).

with ``e0`` the pose error of the target against ``x0`` (position; rotation vector of
``target * palm^-1``), ``xd*`` the feed-forward twist, ``t`` the time since the target was set,
``K, D`` the 6 x 6 stiffness and damping. ``G`` makes the damping implicit, which keeps the
light wrist stable at 240 Hz. Between re-linearisations the spring and damper still act on the
measured joint state at every physics step (the pose error is linearised through ``J``); a new
target acts at once without re-linearising. With ``refresh_every=1`` this is the plain law.

Quaternions are scalar-last (x, y, z, w); twists are (linear, angular) in the world frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills.kernel import kernel, quaternion_at, rotation_error_q
from worlds.impedance_values import (
    GainArrays,
)

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------------------------
# Pure law (vectorised over arms)


@dataclass(frozen=True)
class AffineTorqueLaw:
    """``tau = a + a_rate * elapsed + B q + C qd`` for ``k`` bodies, valid near its
    linearisation.

    Attributes
    ----------
    a, a_rate : ndarray
        (k, n) constant torque (N m) and its rate from the moving targets (N m/s).
    b, c : ndarray
        (k, n, n) joint stiffness (N m/rad) and damping (N m s/rad).
    """

    a: FloatArray
    a_rate: FloatArray
    b: FloatArray
    c: FloatArray


@dataclass(frozen=True)
class ImpedanceTerms:
    """The target-independent part of the linearised law of ``k`` bodies with ``t`` palms.

    With the pose errors ``e`` (6t,) of the targets against ``palm_position``/
    ``palm_quaternion`` and the target twists ``xd*`` (6t,), palm by palm:
    ``a = a_base + error_gain e + twist_gain xd*`` and ``a_rate = error_gain xd*`` (see
    :func:`affine_law`).

    Attributes
    ----------
    a_base : ndarray
        (k, n) gravity, posture and linearisation-offset torque, N m.
    error_gain, twist_gain : ndarray
        (k, n, 6t) torque per unit pose error (N m per m or rad) and per unit twist.
    b, c : ndarray
        (k, n, n) joint stiffness (N m/rad) and damping (N m s/rad).
    palm_position : ndarray
        (k, t, 3) palm positions at the linearisation point, world frame, m.
    palm_quaternion : ndarray
        (k, t, 4) palm orientations at the linearisation point, scalar-last.
    """

    a_base: FloatArray
    error_gain: FloatArray
    twist_gain: FloatArray
    b: FloatArray
    c: FloatArray
    palm_position: FloatArray
    palm_quaternion: FloatArray


@kernel
def _terms_kernel(
    jacobian: FloatArray,
    q: FloatArray,
    rest_posture: FloatArray,
    stiffness: FloatArray,
    damping: FloatArray,
    null_stiffness: FloatArray,
    null_damping: FloatArray,
    joint_damping: FloatArray,
    posture_weight: FloatArray,
    mass_matrix: FloatArray,
    dt: float,
    pinv_damping: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """:func:`impedance_terms`' arithmetic, body by body, compiled (the module doc's formulas).

    Returns ``a_base`` (gravity not yet added), ``error_gain``, ``twist_gain``, ``b``, ``c``;
    ``dt`` 0 leaves the damping explicit (``mass_matrix`` then unread).
    """
    k, m, n = jacobian.shape
    eye_n = np.eye(n)
    eye_m = np.eye(m)
    a_base = np.empty((k, n))
    error_gain = np.empty((k, n, m))
    twist_gain = np.empty((k, n, m))
    b = np.empty((k, n, n))
    c = np.empty((k, n, n))
    for j in range(k):
        jac = np.ascontiguousarray(jacobian[j])
        jt = np.ascontiguousarray(jac.T)
        jt_k = jt * stiffness[j]
        jt_d = jt * damping[j]
        # P = I - J^T (J J^T + l^2 I)^-1 J: symmetric, removes every palm's directions.
        projector = eye_n - jt @ np.linalg.solve(jac @ jt + (pinv_damping**2) * eye_m, jac)
        # The posture torque P W (q_rest - q): a joint-space spring, weighed per joint.
        posture = projector * posture_weight[j]
        rest = posture_weight[j] * rest_posture[j]
        bj = -(jt_k @ jac + null_stiffness[j] * posture)
        cj = -(jt_d @ jac + null_damping[j] * posture + joint_damping[j] * eye_n)
        aj = jt_k @ (jac @ q[j]) + null_stiffness[j] * (projector @ rest)
        if dt > 0.0:
            # G X = M (M - dt C)^-1 X, every term in one solve.
            stacked = np.empty((n, 2 * n + 2 * m + 1))
            stacked[:, :n] = bj
            stacked[:, n : 2 * n] = cj
            stacked[:, 2 * n : 2 * n + m] = jt_k
            stacked[:, 2 * n + m : 2 * n + 2 * m] = jt_d
            stacked[:, 2 * n + 2 * m] = aj
            mass = np.ascontiguousarray(mass_matrix[j])
            stacked = mass @ np.linalg.solve(mass - dt * cj, stacked)
            bj = stacked[:, :n]
            cj = stacked[:, n : 2 * n]
            jt_k = stacked[:, 2 * n : 2 * n + m]
            jt_d = stacked[:, 2 * n + m : 2 * n + 2 * m]
            aj = stacked[:, 2 * n + 2 * m]
        a_base[j] = aj
        error_gain[j] = jt_k
        twist_gain[j] = jt_d
        b[j] = bj
        c[j] = cj
    return a_base, error_gain, twist_gain, b, c


def impedance_terms(
    jacobian: FloatArray,
    palm_position: FloatArray,
    palm_quaternion: FloatArray,
    q: FloatArray,
    gravity_torque: FloatArray,
    gains: GainArrays,
    rest_posture: FloatArray,
    mass_matrix: FloatArray | None = None,
    dt: float = 0.0,
    pinv_damping: float = 1e-3,
) -> ImpedanceTerms:
    """Linearise the palm impedance law of ``k`` bodies around their configurations ``q``.

    Each body has ``n`` joints and ``t`` palms; a joint may move several palms (its columns of
    the stacked Jacobian are then non-zero in several palms' rows), and its torque is the sum
    of what each palm asks of it.

    With ``mass_matrix`` and ``dt`` the damping is made implicit: the control torque (all but
    gravity) is multiplied by ``G = M (M + dt D_q)^-1``, ``D_q = -C`` the joint damping matrix
    over all the body's joints. This gives the joint velocity one implicit Euler step of the
    damper would give, which keeps the light wrist joints stable at 240 Hz (explicit damping
    diverges once ``dt D_q / M > 2``; the iiwa's last joint with a palm has about 0.002 kg m^2).

    Parameters
    ----------
    jacobian : ndarray
        (k, 6t, n) palm Jacobians stacked palm by palm (linear rows first), world frame.
    palm_position : ndarray
        (k, t, 3) palm positions at ``q``, world frame, m.
    palm_quaternion : ndarray
        (k, t, 4) palm orientations at ``q``, scalar-last.
    q : ndarray
        (k, n) joint positions, rad.
    gravity_torque : ndarray
        (k, n) torques holding the bodies still against gravity at ``q``, N m.
    gains : GainArrays
        Spring, damper and posture gains of the ``k`` bodies.
    rest_posture : ndarray
        (k, n) null-space posture targets, rad.
    mass_matrix : ndarray, optional
        (k, n, n) joint-space inertia at ``q``, kg m^2.
    dt : float
        Physics time step, s; used with ``mass_matrix``.
    pinv_damping : float
        Damping of the pseudo-inverse behind the null-space projector.

    Returns
    -------
    ImpedanceTerms
    """
    k, n = q.shape
    implicit = mass_matrix is not None and dt > 0.0
    a_base, error_gain, twist_gain, b, c = _terms_kernel(
        np.ascontiguousarray(jacobian, dtype=float),
        np.ascontiguousarray(q, dtype=float),
        np.ascontiguousarray(rest_posture, dtype=float),
        np.ascontiguousarray(gains.stiffness, dtype=float),
        np.ascontiguousarray(gains.damping, dtype=float),
        np.ascontiguousarray(gains.null_stiffness, dtype=float),
        np.ascontiguousarray(gains.null_damping, dtype=float),
        np.ascontiguousarray(gains.joint_damping, dtype=float),
        np.ones((k, n))
        if gains.posture_weight is None
        else np.ascontiguousarray(gains.posture_weight, dtype=float),
        np.ascontiguousarray(mass_matrix, dtype=float) if implicit else np.empty((k, n, n)),
        float(dt) if implicit else 0.0,
        float(pinv_damping),
    )
    return ImpedanceTerms(
        a_base=a_base + gravity_torque,
        error_gain=error_gain,
        twist_gain=twist_gain,
        b=b,
        c=c,
        palm_position=palm_position,
        palm_quaternion=palm_quaternion,
    )


def limit_posture(
    q: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    rest: FloatArray,
    weight: FloatArray,
    band: FloatArray,
    band_weight: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """Posture weights and targets that also pull joints out of a band inside their limits.

    A joint ``d`` deep into a band of width ``b`` gets a second posture spring towards the
    band's edge, of weight ``band_weight * d / b``; the two springs on one joint are one of
    summed weight towards their weighted mean, so the law (:func:`impedance_terms`) takes them
    as its posture ``W`` and ``q_rest``. Re-evaluated at each linearisation.

    Parameters
    ----------
    q, lower, upper : ndarray
        (..., n) joint positions and limits, rad.
    rest, weight : ndarray
        (..., n) posture targets (rad) and weights.
    band, band_weight : ndarray
        (..., n) band widths (rad; 0: none) and the band springs' weights at the limits.

    Returns
    -------
    weight, rest : ndarray
        (..., n) each.
    """
    edge = np.minimum(np.maximum(q, lower + band), upper - band)
    depth = np.abs(edge - q)
    extra = np.where(band > 0.0, band_weight * depth / np.where(band > 0.0, band, 1.0), 0.0)
    total = weight + extra
    return total, np.where(
        total > 0.0, (weight * rest + extra * edge) / np.where(total > 0.0, total, 1.0), rest
    )


def _by_palm(x: ArrayLike, k: int, width: int) -> FloatArray:
    """``x`` as (k, t, width) floats, contiguous: ``k`` bodies' ``t`` palms (one palm a body
    may come as (k, width))."""
    if (
        isinstance(x, np.ndarray)
        and x.dtype == np.float64
        and x.ndim == 3
        and x.shape[0] == k
        and x.shape[2] == width
        and x.flags.c_contiguous
    ):
        return x  # already so (the controller's every call): no copy, no reshape
    return np.ascontiguousarray(np.reshape(x, (k, -1, width)), dtype=float)


@kernel
def _affine_kernel(
    a_base: FloatArray,
    error_gain: FloatArray,
    twist_gain: FloatArray,
    palm_position: FloatArray,
    palm_quaternion: FloatArray,
    target_position: FloatArray,
    target_quaternion: FloatArray,
    target_twist: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """:func:`affine_law`'s ``a`` and ``a_rate``, compiled: the pose errors (position; rotation
    vector of ``target * palm^-1``) and twists stacked palm by palm through the gains."""
    k, t = target_position.shape[0], target_position.shape[1]
    n = a_base.shape[1]
    a = np.empty((k, n))
    a_rate = np.empty((k, n))
    error = np.empty(6 * t)
    twist = np.empty(6 * t)
    for j in range(k):
        for s in range(t):
            for axis in range(3):
                error[6 * s + axis] = target_position[j, s, axis] - palm_position[j, s, axis]
            rx, ry, rz = rotation_error_q(
                quaternion_at(target_quaternion[j, s], 0), quaternion_at(palm_quaternion[j, s], 0)
            )
            error[6 * s + 3] = rx
            error[6 * s + 4] = ry
            error[6 * s + 5] = rz
            for axis in range(6):
                twist[6 * s + axis] = target_twist[j, s, axis]
        gain = np.ascontiguousarray(error_gain[j])
        a_rate[j] = gain @ twist
        a[j] = a_base[j] + gain @ error + np.ascontiguousarray(twist_gain[j]) @ twist
    return a, a_rate


def affine_law(
    terms: ImpedanceTerms,
    target_position: FloatArray,
    target_quaternion: FloatArray,
    target_twist: FloatArray,
) -> AffineTorqueLaw:
    """Complete linearised terms with the targets of ``k`` bodies' ``t`` palms.

    Parameters
    ----------
    terms : ImpedanceTerms
        From :func:`impedance_terms`.
    target_position : ndarray
        (k, t, 3) spring anchors (squeeze offset included), world frame, m.
    target_quaternion : ndarray
        (k, t, 4) target orientations, scalar-last.
    target_twist : ndarray
        (k, t, 6) feed-forward twists (m/s, rad/s), world frame.

    Returns
    -------
    AffineTorqueLaw
    """
    k = len(terms.a_base)
    a, a_rate = _affine_kernel(
        np.ascontiguousarray(terms.a_base, dtype=float),
        np.ascontiguousarray(terms.error_gain, dtype=float),
        np.ascontiguousarray(terms.twist_gain, dtype=float),
        _by_palm(terms.palm_position, k, 3),
        _by_palm(terms.palm_quaternion, k, 4),
        _by_palm(target_position, k, 3),
        _by_palm(target_quaternion, k, 4),
        _by_palm(target_twist, k, 6),
    )
    return AffineTorqueLaw(a=a, a_rate=a_rate, b=terms.b, c=terms.c)


__all__ = [
    "AffineTorqueLaw",
    "ImpedanceTerms",
    "affine_law",
    "impedance_terms",
    "limit_posture",
]
