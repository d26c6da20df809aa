"""The transformation system every pose DMP shares: its attractor and its integration.

Attractor (Ijspeert et al. 2013; Ude et al. 2014 for orientation), per unit mass::

    a = alpha (beta (g - y) - tau v) / tau^2
    alpha_rot = alpha (beta 2 log(g conj(q)) - tau omega) / tau^2

Integration over a step ``dt``: semi-implicit Euler for the position and the angular
velocity, the exponential map for the quaternion (so it stays unit), the exact solution for
the phase. Each has one numpy reference (what the tests and the pure DMP functions use) and
one kernel (what the composition interpreter runs), compared within 1e-12 by the tests.
"""

from __future__ import annotations

import numpy as np

from skills import quaternion as quat
from skills.basis import phase_step
from skills.kernel import integrate_q, kernel, quaternion_at, rotation_error_q
from skills.state import PoseState, PoseTarget
from skills.types import Array


def attractor(
    state: PoseState, alpha: float, beta: float, target: PoseTarget
) -> tuple[Array, Array]:
    """The spring-damper towards the goal: linear (3,) m/s^2 and angular (3,) rad/s^2."""
    tau = target.tau
    kp = alpha * beta / (tau * tau)
    kd = alpha / tau
    error = quat.rotation_error(target.goal_orientation, state.orientation)
    return (
        kp * (target.goal_position - state.position) - kd * state.velocity,
        kp * error - kd * state.angular_velocity,
    )


def integrate(
    state: PoseState, linear: Array, angular: Array, dt: float, tau: float, alpha_s: float
) -> PoseState:
    """The state ``dt`` later under the accelerations ``linear``, ``angular`` (3,) each."""
    v = state.velocity + linear * dt
    w = state.angular_velocity + angular * dt
    return PoseState(
        state.position + v * dt,
        v,
        np.array(linear, dtype=float),
        quat.integrate(state.orientation, w, dt),
        w,
        np.array(angular, dtype=float),
        phase_step(state.phase, dt, tau, alpha_s),
    )


@kernel
def attractor_kernel(x: Array, b: int, space: Array, acc: Array) -> None:
    """:func:`attractor` into ``acc`` (6), the state at ``x[b:]``; ``space`` is the space's row
    of the interpreter (``[attractor?, kp, kd, goal xyz, goal xyzw, ...]``)."""
    kp, kd = space[1], space[2]
    e = rotation_error_q((space[6], space[7], space[8], space[9]), quaternion_at(x, b + 9))
    for i in range(3):
        acc[i] = kp * (space[3 + i] - x[b + i]) - kd * x[b + 3 + i]
        acc[3 + i] = kp * e[i] - kd * x[b + 13 + i]


@kernel
def integrate_kernel(x: Array, b: int, acc: Array, dt: float, out: Array) -> None:
    """:func:`integrate` of the state at ``x[b:]`` into ``out[b:]`` (the phase apart)."""
    for i in range(3):
        v = x[b + 3 + i] + acc[i] * dt
        out[b + i] = x[b + i] + v * dt
        out[b + 3 + i] = v
        out[b + 6 + i] = acc[i]
        out[b + 13 + i] = x[b + 13 + i] + acc[3 + i] * dt
        out[b + 16 + i] = acc[3 + i]
    omega = (out[b + 13], out[b + 14], out[b + 15])
    out[b + 9], out[b + 10], out[b + 11], out[b + 12] = integrate_q(
        quaternion_at(x, b + 9), omega, dt
    )


#: :func:`skills.basis.phase_step`, compiled.
phase_kernel = kernel(phase_step)
