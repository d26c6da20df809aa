"""The compiled composition step's kernels (numba), for :mod:`skills.compiled`.

Plain functions on float arrays, compiled by numba when it is installed (the ``fast`` extra)
and left as Python otherwise (:data:`COMPILED` says which; the Python form is only a
reference, far slower than the float path). Each computes the formulas of a float path of the
numpy composer, mostly operation for operation (steering sums its obstacles, and the field its
points, in another order): :func:`skills.pose_dmp.attractor_floats`,
:meth:`skills.pose_dmp.LearntForcing.scalar_acceleration`,
:meth:`skills.couplings.steering.ObstacleSteering.scalar_acceleration`,
:meth:`skills.couplings.potential.PotentialFieldAvoidance.scalar_acceleration`,
:meth:`skills.couplings.grasp.GraspMaintenance.scalar_acceleration`,
:func:`skills.pose_dmp.integrate_floats` and :func:`skills.composer.palm_commands`. The
quaternion arithmetic is :mod:`skills.quaternion`'s scalar functions themselves, compiled.

Layouts (see :mod:`skills.compiled` for how they are packed):

* state ``x``, at least 60 floats: the object's, the left palm's and the right palm's
  :data:`skills.pose_dmp.StateValues` (19 each), then their three phases (a previous step's
  ``out`` will do);
* ``spaces`` (3, 13), per space: ``[attractor?, kp, kd, goal xyz, goal xyzw, tau, alpha_s,
  largest basis size]``;
* ``program`` (T, 3) ints, per term: ``[space, kind, offset into data]``; a term's block of
  ``data`` starts with its weight;
* ``out``, 92 floats: the next state as ``x``, then the commands (palm positions 2 x 3,
  orientations 2 x 4, twists 2 x 6, object twist 6).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from skills import quaternion as quat
from skills.composer import COMMANDS, PHASES, ROW_SIZE
from skills.pose_dmp import STATE_SIZE
from skills.types import Array


def _numba() -> Any:
    try:
        return importlib.import_module("numba")
    except ImportError:  # the fast extra is not installed: keep the reference Python
        return None


_NUMBA = _numba()
#: Whether the kernels are compiled (numba is installed).
COMPILED = _NUMBA is not None


def kernel(fn: Callable[..., Any]) -> Callable[..., Any]:
    """Compile ``fn`` (cached on disk) when numba is installed."""
    if _NUMBA is None:
        return fn
    compiled: Callable[..., Any] = _NUMBA.njit(cache=True, nogil=True)(fn)
    return compiled


#: The layout of a state and of a step's output row: the composer's.
STATE = STATE_SIZE
SIZE = ROW_SIZE
#: Term kinds.
FORCING, BASE_FORCING, STEERING, POTENTIAL, GRASP = 0, 1, 2, 3, 4
#: Where the points of a potential-field block, and the obstacles of a steering block, start
#: (after the weight and the parameters).
POTENTIAL_HEADER = 8
STEERING_HEADER = 7
#: As :data:`skills.couplings.steering._COLLINEAR`.
COLLINEAR = 1e-7


# skills.quaternion's scalar functions, compiled: the kernels share their arithmetic.
rotation_error_q = kernel(quat.rotation_error_scalar)
matrix_q = kernel(quat.matrix_floats)
integrate_q = kernel(quat.integrate_scalar)
multiply_q = kernel(quat.multiply_scalar)


@kernel
def quaternion_at(x: Array, at: int) -> tuple[float, float, float, float]:
    """The quaternion at ``x[at:at + 4]`` as floats."""
    return (x[at], x[at + 1], x[at + 2], x[at + 3])


@kernel
def attractor(x: Array, b: int, sp: Array, acc: Array) -> None:
    """The spring-damper to the goal into ``acc`` (6), the state at ``x[b:]``."""
    kp, kd = sp[1], sp[2]
    e = rotation_error_q((sp[6], sp[7], sp[8], sp[9]), quaternion_at(x, b + 9))
    for i in range(3):
        acc[i] = kp * (sp[3 + i] - x[b + i]) - kd * x[b + 3 + i]
        acc[3 + i] = kp * e[i] - kd * x[b + 13 + i]


@kernel
def activations(s: float, data: Array, table: int, size: int, psi: Array) -> None:
    """Unnormalised basis activations at phase ``s`` into ``psi[:size]``, from the exponent
    table (3, K) at ``data[table:]`` (:attr:`skills.basis.RBFBasis.exponent_table`)."""
    s2 = s * s
    for i in range(size):
        psi[i] = math.exp(
            s2 * data[table + i] + s * data[table + size + i] + data[table + 2 * size + i]
        )


@kernel
def forcing(s: float, data: Array, o: int, psi: Array, base: bool, a: Array) -> None:
    """A learnt forcing term at phase ``s``: block ``[w, K, tau, table offset, W (K, 7)]``,
    with ``psi`` its basis activations at ``s``."""
    size = int(data[o + 1])
    tau = data[o + 2]
    weights = o + 4
    r0 = r1 = r2 = r3 = r4 = r5 = r6 = 0.0
    for i in range(size):
        row = weights + 7 * i
        p = psi[i]
        r0 += p * data[row]
        r1 += p * data[row + 1]
        r2 += p * data[row + 2]
        r3 += p * data[row + 3]
        r4 += p * data[row + 4]
        r5 += p * data[row + 5]
        r6 += p * data[row + 6]
    total = max(r6, 1e-300)
    k = s * (1.0 / (tau * tau)) / total if base else s / (total * tau * tau)
    a[0], a[1], a[2], a[3], a[4], a[5] = r0 * k, r1 * k, r2 * k, r3 * k, r4 * k, r5 * k


@kernel
def steering(x: Array, b: int, data: Array, o: int, a: Array) -> None:
    """Obstacle steering: block ``[w, gamma, beta, k, max_angle, min_speed, M, M x 4]``."""
    gamma, beta, kc, max_angle, min_speed = (
        data[o + 1],
        data[o + 2],
        data[o + 3],
        data[o + 4],
        data[o + 5],
    )
    m = int(data[o + 6])
    vx, vy, vz = x[b + 3], x[b + 4], x[b + 5]
    vv = vx * vx + vy * vy + vz * vz
    a[:] = 0.0
    if vv <= min_speed * min_speed:
        return
    px, py, pz = x[b], x[b + 1], x[b + 2]
    along = 0.0  # sum of w (D.v)
    sx = sy = sz = 0.0  # sum of w D
    for i in range(m):
        c = o + STEERING_HEADER + 4 * i
        dx, dy, dz = data[c] - px, data[c + 1] - py, data[c + 2] - pz
        dv = dx * vx + dy * vy + dz * vz
        dd = dx * dx + dy * dy + dz * dz
        cross = math.sqrt(max(dd * vv - dv * dv, 0.0))
        phi = math.atan2(cross, dv)
        if phi >= max_angle or cross <= COLLINEAR * math.sqrt(dd * vv):
            continue
        clearance = max(math.sqrt(dd) - data[c + 3], 0.0)
        w = gamma * phi * math.exp(-beta * phi - kc * clearance * clearance) / cross
        along += w * dv
        sx += w * dx
        sy += w * dy
        sz += w * dz
    a[0] = along * vx - vv * sx
    a[1] = along * vy - vv * sy
    a[2] = along * vz - vv * sz


@kernel
def world_points(x: Array, b: int, data: Array, o: int) -> Array:
    """A potential field's points in the world (N, 3), from its block and the state at ``b``."""
    n = int(data[o + 6])
    m = matrix_q(quaternion_at(x, b + 9))
    out = np.empty((n, 3))
    for i in range(n):
        p = o + POTENTIAL_HEADER + 3 * i
        for r in range(3):
            out[i, r] = x[b + r] + (
                m[3 * r] * data[p] + m[3 * r + 1] * data[p + 1] + m[3 * r + 2] * data[p + 2]
            )
    return out


@kernel
def nearest_spheres(points: Array, data: Array, at: int, count: int) -> Array:
    """Each point's signed distance to the nearest of ``count`` spheres ``[centre, radius]``
    stored from ``data[at]``, and its closest point: (N, 4), as
    :class:`skills.couplings.potential.SphereObstacles`."""
    n = points.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        best = np.inf
        bx = by = bz = br = bn = cx = cy = cz = 0.0
        for j in range(count):
            c = at + 4 * j
            dx = points[i, 0] - data[c]
            dy = points[i, 1] - data[c + 1]
            dz = points[i, 2] - data[c + 2]
            norm = math.sqrt(dx * dx + dy * dy + dz * dz)
            gap = norm - data[c + 3]
            if gap < best:
                best, bx, by, bz, br, bn = gap, dx, dy, dz, data[c + 3], norm
                cx, cy, cz = data[c], data[c + 1], data[c + 2]
        if count == 0:
            out[i, 0] = np.inf
            out[i, 1] = out[i, 2] = out[i, 3] = np.nan
            continue
        scale = br / max(bn, 1e-12)
        out[i, 0] = best
        out[i, 1] = cx + bx * scale
        out[i, 2] = cy + by * scale
        out[i, 3] = cz + bz * scale
    return out


@kernel
def potential(x: Array, b: int, data: Array, o: int, a: Array) -> None:
    """The dynamic potential field: block
    ``[w, gain, beta, influence, min_distance, 1/rho^2, N, M, points N x 3, ...]``: with
    ``M = -1``, ``[distances N, closest N x 3]`` written by the caller's distance query this
    step; else ``M`` spheres ``[centre, radius]`` queried here."""
    gain, beta, influence, p_min, inv_rho2 = (
        data[o + 1],
        data[o + 2],
        data[o + 3],
        data[o + 4],
        data[o + 5],
    )
    n = int(data[o + 6])
    spheres = int(data[o + 7])
    points = o + POTENTIAL_HEADER
    after = points + 3 * n
    a[:] = 0.0
    if n == 0:
        return
    near = np.empty((n, 4))  # distance, closest point
    if spheres < 0:
        for i in range(n):
            near[i, 0] = data[after + i]
            near[i, 1] = data[after + n + 3 * i]
            near[i, 2] = data[after + n + 3 * i + 1]
            near[i, 3] = data[after + n + 3 * i + 2]
    else:
        near = nearest_spheres(world_points(x, b, data, o), data, after, spheres)
    nearest = near[0, 0]
    for i in range(1, n):
        nearest = min(nearest, near[i, 0])
    if nearest >= influence:
        return
    m = matrix_q(quaternion_at(x, b + 9))
    vx0, vy0, vz0 = x[b + 3], x[b + 4], x[b + 5]
    wx, wy, wz = x[b + 13], x[b + 14], x[b + 15]
    px, py, pz = x[b], x[b + 1], x[b + 2]
    power = beta - 1.0
    inv_p0 = 1.0 / influence
    fx = fy = fz = tx = ty = tz = 0.0
    for i in range(n):
        p = points + 3 * i
        ax = m[0] * data[p] + m[1] * data[p + 1] + m[2] * data[p + 2]  # lever arm R r_i
        ay = m[3] * data[p] + m[4] * data[p + 1] + m[5] * data[p + 2]
        az = m[6] * data[p] + m[7] * data[p + 1] + m[8] * data[p + 2]
        vx = vx0 + (wy * az - wz * ay)
        vy = vy0 + (wz * ax - wx * az)
        vz = vz0 + (wx * ay - wy * ax)
        rx = (px + ax) - near[i, 1]
        ry = (py + ay) - near[i, 2]
        rz = (pz + az) - near[i, 3]
        q = -(vx * rx + vy * ry + vz * rz)
        if q <= 0.0:
            continue
        d = near[i, 0]
        ip = 1.0 / (d if d > p_min else p_min)
        g = ip - inv_p0
        if g <= 0.0:
            continue
        rr = rx * rx + ry * ry + rz * rz
        h = ip * (q / max(math.sqrt(rr * (vx * vx + vy * vy + vz * vz)), 1e-300)) ** power
        alpha = beta * g
        kappa = (alpha + ip) * h * q / max(rr, 1e-300)
        alpha *= h
        ux = alpha * vx + kappa * rx
        uy = alpha * vy + kappa * ry
        uz = alpha * vz + kappa * rz
        fx += ux
        fy += uy
        fz += uz
        tx += ay * uz - az * uy
        ty += az * ux - ax * uz
        tz += ax * uy - ay * ux
    k = gain * inv_rho2
    a[0], a[1], a[2] = gain * fx, gain * fy, gain * fz
    a[3], a[4], a[5] = k * tx, k * ty, k * tz


@kernel
def grasp(x: Array, b: int, data: Array, o: int, a: Array) -> None:
    """Grasp maintenance: block ``[w, ref xyz, ref xyzw, k, d, k_rot, d_rot]``."""
    e = rotation_error_q(quaternion_at(data, o + 4), quaternion_at(x, b + 9))
    k, d, kr, dr = data[o + 8], data[o + 9], data[o + 10], data[o + 11]
    for i in range(3):
        a[i] = k * (data[o + 1 + i] - x[b + i]) - d * x[b + 3 + i]
        a[3 + i] = kr * e[i] - dr * x[b + 13 + i]


@kernel
def integrate(x: Array, b: int, acc: Array, dt: float, out: Array) -> None:
    """Semi-implicit Euler and the exponential map from ``x[b:]`` into ``out[b:]``."""
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


@kernel
def commands(out: Array) -> None:
    """Palm world poses and eq. (5) twists from the new state in ``out``, into ``out[60:]``."""
    m = matrix_q(quaternion_at(out, 9))
    q_obj = quaternion_at(out, 9)
    vx, vy, vz, wx, wy, wz = out[3], out[4], out[5], out[13], out[14], out[15]
    for arm in range(2):
        b = STATE * (1 + arm)
        a0, a1, a2 = out[b], out[b + 1], out[b + 2]
        l0 = m[0] * a0 + m[1] * a1 + m[2] * a2
        l1 = m[3] * a0 + m[4] * a1 + m[5] * a2
        l2 = m[6] * a0 + m[7] * a1 + m[8] * a2
        p = COMMANDS + 3 * arm
        out[p] = out[0] + l0
        out[p + 1] = out[1] + l1
        out[p + 2] = out[2] + l2
        q = COMMANDS + 6 + 4 * arm
        out[q], out[q + 1], out[q + 2], out[q + 3] = multiply_q(q_obj, quaternion_at(out, b + 9))
        b0, b1, b2 = out[b + 3], out[b + 4], out[b + 5]
        c0, c1, c2 = out[b + 13], out[b + 14], out[b + 15]
        t = COMMANDS + 14 + 6 * arm
        out[t] = vx + wy * l2 - wz * l1 + m[0] * b0 + m[1] * b1 + m[2] * b2
        out[t + 1] = vy + wz * l0 - wx * l2 + m[3] * b0 + m[4] * b1 + m[5] * b2
        out[t + 2] = vz + wx * l1 - wy * l0 + m[6] * b0 + m[7] * b1 + m[8] * b2
        out[t + 3] = wx + m[0] * c0 + m[1] * c1 + m[2] * c2
        out[t + 4] = wy + m[3] * c0 + m[4] * c1 + m[5] * c2
        out[t + 5] = wz + m[6] * c0 + m[7] * c1 + m[8] * c2
    t = COMMANDS + 26
    out[t], out[t + 1], out[t + 2] = vx, vy, vz
    out[t + 3], out[t + 4], out[t + 5] = wx, wy, wz


@kernel
def step(
    x: Array,
    spaces: Array,
    program: Array,
    data: Array,
    extra: Array,
    dt: float,
    out: Array,
) -> None:
    """One composition step: every space's accelerations, integration, phases, commands.

    ``extra`` (3, 6) holds the summed accelerations of terms without a kernel, evaluated by
    the caller at the same state.
    """
    acc = np.zeros((3, 6))
    for sp in range(3):
        if spaces[sp, 0] != 0.0:
            attractor(x, STATE * sp, spaces[sp], acc[sp])
    a = np.empty(6)
    psi = np.empty(int(spaces[0, 12]))
    psi_table, psi_phase = -1, 0.0  # terms on one basis at one phase share its activations
    for t in range(program.shape[0]):
        sp, kind, o = program[t, 0], program[t, 1], program[t, 2]
        b = STATE * sp
        if kind == FORCING or kind == BASE_FORCING:
            s = x[PHASES + sp]
            table = int(data[o + 3])
            if table != psi_table or s != psi_phase:
                activations(s, data, table, int(data[o + 1]), psi)
                psi_table, psi_phase = table, s
            forcing(s, data, o, psi, kind == BASE_FORCING, a)
        elif kind == STEERING:
            steering(x, b, data, o, a)
        elif kind == POTENTIAL:
            potential(x, b, data, o, a)
        else:
            grasp(x, b, data, o, a)
        w = data[o]
        for i in range(6):
            acc[sp, i] += w * a[i]
    for sp in range(3):
        for i in range(6):
            acc[sp, i] += extra[sp, i]
        integrate(x, STATE * sp, acc[sp], dt, out)
        out[PHASES + sp] = x[PHASES + sp] * math.exp(-spaces[sp, 11] * dt / spaces[sp, 10])
    commands(out)


@kernel
def rollout(
    x: Array,
    spaces: Array,
    program: Array,
    data: Array,
    extra: Array,
    dt: float,
    out: Array,
) -> None:
    """``out.shape[0]`` steps open loop from ``x``: row ``i`` of ``out`` (N, 92) is step ``i``'s
    ``out``. Only for terms that all have kernels (``extra`` is constant)."""
    step(x, spaces, program, data, extra, dt, out[0])
    for i in range(1, out.shape[0]):
        step(out[i - 1], spaces, program, data, extra, dt, out[i])
