"""Unit-quaternion DMPs (Ude et al. 2014; the paper's eq. 3-4).

With ``eta = tau * omega`` (omega the world-frame angular velocity)::

    tau * etadot = alpha * (beta * 2 log(g * conj(q)) - eta) + f(s) + tau^2 * c
    tau * qdot   = 1/2 * eta * q

so ``omegadot = (alpha (beta 2 log(g conj(q)) - tau omega) + f) / tau^2 + c``. Orientation is
advanced with the exponential map, ``q <- exp(dt/2 * omega) * q``, which keeps ``|q| = 1``.
The goal error takes the short way, so ``g`` and ``-g`` are the same goal.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.basis import phase_step
from skills.demonstration import Demonstration
from skills.dmp import (
    DMPParams,
    ForcingTerm,
    _reference_inverse,
    check_demonstrations,
    design_matrix,
    ridge,
)
from skills.scaling import Scaling
from skills.types import Array


@dataclass(frozen=True)
class OrientationState:
    """Full orientation state.

    Attributes
    ----------
    orientation : ndarray, shape (4,)
        Unit quaternion ``(x, y, z, w)``.
    angular_velocity, angular_acceleration : ndarray, shape (3,)
        World frame, rad/s and rad/s^2.
    phase : float
    """

    orientation: Array
    angular_velocity: Array
    angular_acceleration: Array
    phase: float = 1.0

    @staticmethod
    def at_rest(orientation: ArrayLike) -> OrientationState:
        """Zero angular velocity and acceleration at ``orientation``, phase 1."""
        q = quat.as_quaternions(orientation, "orientation")
        return OrientationState(q, np.zeros(3), np.zeros(3), 1.0)


@dataclass(frozen=True)
class OrientationModel:
    """A learnt quaternion DMP.

    Attributes
    ----------
    params : DMPParams
    forcing : ForcingTerm
        Three-dimensional, on the rotation-vector error.
    demo_start, demo_goal : ndarray, shape (4,)
    demo_tau : float
    """

    params: DMPParams
    forcing: ForcingTerm
    demo_start: Array
    demo_goal: Array
    demo_tau: float

    def matrix(self, start: Array, goal: Array) -> Array:
        """Forcing scaling ``(3, 3)`` for a new start and goal orientation."""
        return self.forcing.matrix(quat.rotation_error(goal, start))


def normalised_orientation_targets(
    demo: Demonstration,
    params: DMPParams,
    reference: Array,
    scaling: Scaling,
    min_amplitude: float,
) -> Array:
    """Target forcing ``(N, 3)`` of one demonstration, mapped back to the reference rotation.

    ``f = tau^2 omegadot - alpha (beta 2 log(g conj(q)) - tau omega)``, then ``M^-1`` applied.
    """
    if demo.orientations is None:
        raise ValueError(f"{demo.name}: orientations: expected quaternions, got none")
    tau = demo.duration
    q = demo.orientations
    omega, omegad = demo.orientation_derivatives()
    err = quat.rotation_error(q[-1], q)
    f_target = tau * tau * omegad - params.alpha * (params.beta * err - tau * omega)
    disp = quat.rotation_error(q[-1], q[0])
    m_inv = _reference_inverse(scaling, disp, reference, min_amplitude, demo.name)
    return f_target @ m_inv.T


def orientation_reference(demo: Demonstration) -> Array:
    """Rotation vector ``(3,)`` from a demonstration's first to last orientation."""
    if demo.orientations is None:
        raise ValueError(f"{demo.name}: orientations: expected quaternions, got none")
    return quat.rotation_error(demo.orientations[-1], demo.orientations[0])


def fit_orientation(
    demos: Demonstration | Sequence[Demonstration],
    params: DMPParams | None = None,
    scaling: Scaling = Scaling.AMPLITUDE,
    min_amplitude: float = 1e-2,
) -> OrientationModel:
    """Learn a quaternion DMP from one or more demonstrations with orientations.

    Parameters
    ----------
    demos : Demonstration or sequence of Demonstration
    params : DMPParams, optional
    scaling : Scaling
        ``AMPLITUDE`` is Ude et al.'s ``diag(2 log(g conj(q0)))`` relative to the demo.
    min_amplitude : float
        Rotation (rad) below which an axis does not scale.
    """
    p = params or DMPParams()
    demo_list = [demos] if isinstance(demos, Demonstration) else list(demos)
    check_demonstrations(demo_list, p.n_basis)
    first = demo_list[0]
    reference = orientation_reference(first)
    basis = p.basis()
    xs, fs = [], []
    for d in demo_list:
        _, x = design_matrix(d.t, d.duration, basis, p.alpha_s)
        xs.append(x)
        fs.append(normalised_orientation_targets(d, p, reference, scaling, min_amplitude))
    weights = ridge(xs, fs, p.regularisation)
    forcing = ForcingTerm(weights, basis, reference, scaling, min_amplitude)
    assert first.orientations is not None
    return OrientationModel(
        p, forcing, first.orientations[0].copy(), first.orientations[-1].copy(), first.duration
    )


def orientation_acceleration(
    q: Array, omega: Array, goal: Array, tau: float, forcing: Array, alpha: float, beta: float
) -> Array:
    """Angular acceleration ``(3,)`` of the transformation system, without coupling."""
    err = quat.rotation_error(goal, q)
    return (alpha * (beta * err - tau * omega) + forcing) / (tau * tau)


def orientation_step(
    state: OrientationState,
    model: OrientationModel,
    goal: Array,
    matrix: Array,
    tau: float,
    dt: float,
    coupling: Array | None = None,
) -> OrientationState:
    """Advance a quaternion DMP by ``dt`` from ``state`` (closed loop: state may be measured)."""
    p = model.params
    f = model.forcing.value(state.phase, matrix)
    wd = orientation_acceleration(
        state.orientation, state.angular_velocity, goal, tau, f, p.alpha, p.beta
    )
    if coupling is not None:
        wd = wd + coupling
    w = state.angular_velocity + wd * dt
    q = quat.integrate(state.orientation, w, dt)
    return OrientationState(q, w, wd, phase_step(state.phase, dt, tau, p.alpha_s))


def integrate_orientation(
    q0: Array,
    omega0: Array,
    goal: Array,
    forcing: Array,
    coupling: Array | None,
    alpha: float,
    beta: float,
    tau: float,
    dt: float,
) -> tuple[Array, Array, Array]:
    """Open-loop integration of the quaternion DMP over precomputed forcing.

    The orientation dynamics are non-linear, so this loops over steps, but in scalar
    floats: numpy's per-call overhead would dominate 4-vector arithmetic.

    Parameters
    ----------
    q0 : ndarray, shape (4,)
    omega0 : ndarray, shape (3,)
    goal : ndarray, shape (4,)
    forcing : ndarray, shape (N, 3)
        ``f(s_k)`` for each step (not yet divided by ``tau^2``).
    coupling : ndarray, shape (N, 3), optional
        Extra accelerations per step, rad/s^2.
    alpha, beta, tau, dt : float

    Returns
    -------
    orientations, angular velocities, angular accelerations :
        ndarray, shapes (N + 1, 4), (N + 1, 3), (N, 3)
    """
    n = forcing.shape[0]
    drive = forcing / (tau * tau)
    if coupling is not None:
        drive = drive + coupling
    drive_l = drive.tolist()
    kp = alpha * beta / (tau * tau)
    kd = alpha / tau
    g = tuple(float(v) for v in goal)
    q = tuple(float(v) for v in q0)
    wx, wy, wz = (float(v) for v in omega0)
    qs = [q]
    ws = [(wx, wy, wz)]
    acc = []
    for k in range(n):
        ex, ey, ez = quat.rotation_error_scalar(g, q)  # type: ignore[arg-type]
        dx, dy, dz = drive_l[k]
        ax = kp * ex - kd * wx + dx
        ay = kp * ey - kd * wy + dy
        az = kp * ez - kd * wz + dz
        wx += ax * dt
        wy += ay * dt
        wz += az * dt
        q = quat.integrate_scalar(q, (wx, wy, wz), dt)  # type: ignore[arg-type]
        qs.append(q)
        ws.append((wx, wy, wz))
        acc.append((ax, ay, az))
    return np.array(qs), np.array(ws), np.array(acc).reshape(n, 3)
