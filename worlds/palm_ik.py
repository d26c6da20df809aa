"""Inverse kinematics of several palms on one body whose joints they share (iCub's torso).

PyBullet's ``calculateInverseKinematics`` solves one end-effector at a time over all of a body's
joints: solving one palm after the other moves the shared joints under the first. Here every
palm of the body is solved at once by damped least squares, weighed so that the shared joints
move only as much as the palms need (:attr:`worlds.robots.SharedJointsSpec.posture_weight`),
with a null-space pull towards the rest posture and the joint limits kept.

:func:`dls_step` is the pure step; :func:`solve_palms` runs it on a PyBullet body.
Poses are (position (3,), quaternion (4,) scalar-last) pairs in the world frame.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pybullet as pb
from numpy.typing import NDArray

from skills import quaternion as quat
from skills.kernel import kernel, quaternion_at, rotation_error_q

FloatArray = NDArray[np.float64]


@kernel
def dls_step(
    jacobian: FloatArray,
    error: FloatArray,
    q: FloatArray,
    rest: FloatArray,
    cost: FloatArray,
    damping: float = 1e-2,
    posture_gain: float = 0.1,
    max_step: float = 0.2,
) -> FloatArray:
    """One weighted damped-least-squares step towards the palm targets, rad, (n,).

    ``dq = W^-1 J^T (J W^-1 J^T + l^2 I)^-1 e + (I - J^+ J) g (q_rest - q)``, scaled down so that
    no joint moves more than ``max_step``.

    Parameters
    ----------
    jacobian : ndarray
        (m, n) stacked palm Jacobians, world frame.
    error : ndarray
        (m,) stacked pose errors (position m, rotation vector rad).
    q, rest : ndarray
        (n,) joint positions and rest posture, rad.
    cost : ndarray
        (n,) how much each joint's motion costs (W's diagonal), > 0.
    damping : float
        ``l``, the damping of the pseudo-inverse.
    posture_gain : float
        ``g``, the fraction of the posture error taken per step.
    max_step : float
        Largest joint motion per step, rad.
    """
    inverse_cost = 1.0 / cost
    jw = jacobian * inverse_cost  # J W^-1
    gram = jw @ np.ascontiguousarray(jacobian.T) + damping**2 * np.eye(jacobian.shape[0])
    pinv = np.ascontiguousarray(jw.T) @ np.linalg.inv(gram)  # W^-1 J^T (J W^-1 J^T + l^2 I)^-1
    dq = pinv @ error
    dq += (np.eye(q.size) - pinv @ jacobian) @ (posture_gain * (rest - q))
    largest = np.max(np.abs(dq))
    if largest > max_step:
        dq *= max_step / largest
    return dq


def solve_palms(
    client: int,
    body: int,
    joints: Sequence[int],
    palm_links: Sequence[int],
    palm2world: Sequence[tuple[FloatArray, FloatArray]],
    q0: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    rest: FloatArray,
    cost: FloatArray,
    iterations: int = 300,
    tolerance: float = 1e-5,
) -> FloatArray:
    """Joint positions (n,) that put every palm of ``body`` at its pose, rad.

    The body is left in the solution. Joints are kept within ``[lower, upper]``; a pose out of
    reach ends at the closest the damped step gets to it.

    Parameters
    ----------
    client : int
        PyBullet client.
    body : int
        Body id; ``joints`` must be all its movable joints.
    joints : sequence of int
        (n,) the body's movable joint indices, in order.
    palm_links : sequence of int
        (t,) the palms' link indices.
    palm2world : sequence of (ndarray, ndarray)
        (t,) palm target poses, world frame.
    q0, lower, upper, rest, cost : ndarray
        (n,) start, limits, rest posture (rad) and motion cost per joint (:func:`dls_step`).
    iterations : int
        Most steps.
    tolerance : float
        Stop once every error component is below this (m, rad).
    """
    _, base_q = pb.getBasePositionAndOrientation(body, physicsClientId=client)
    base2world = np.asarray(quat.to_matrix(base_q), dtype=np.float64)
    n = len(joints)
    zeros = [0.0] * n
    still = [[0.0]] * n
    target_positions = np.array([p for p, _ in palm2world], dtype=float).reshape(-1, 3)
    target_quaternions = np.array([r for _, r in palm2world], dtype=float).reshape(-1, 4)
    q = np.clip(np.asarray(q0, dtype=float), lower, upper)
    for _ in range(iterations):
        q_list = q.tolist()
        pb.resetJointStatesMultiDof(
            body, joints, [[v] for v in q_list], still, physicsClientId=client
        )
        states = [
            pb.getLinkState(body, link, computeForwardKinematics=1, physicsClientId=client)
            for link in palm_links
        ]
        jacobian = np.array(
            [
                pb.calculateJacobian(
                    body, link, [0.0, 0.0, 0.0], q_list, zeros, zeros, physicsClientId=client
                )
                for link in palm_links
            ]
        ).reshape(-1, n)
        done, q_next = _iterate(
            target_positions,
            target_quaternions,
            np.array([s[4] for s in states]),
            np.array([s[5] for s in states]),
            jacobian,
            base2world,
            q,
            rest,
            cost,
            lower,
            upper,
            tolerance,
        )
        if done:
            break
        q = q_next
    pb.resetJointStatesMultiDof(
        body, joints, [[v] for v in q.tolist()], still, physicsClientId=client
    )
    return q


@kernel
def _iterate(
    target_positions: FloatArray,
    target_quaternions: FloatArray,
    positions: FloatArray,
    quaternions: FloatArray,
    jacobian: FloatArray,
    base2world: FloatArray,
    q: FloatArray,
    rest: FloatArray,
    cost: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    tolerance: float,
) -> tuple[bool, FloatArray]:
    """One step of :func:`solve_palms`, compiled: the palms' stacked pose errors (position,
    then rotation vector, per palm) at the pose read, and, unless every component is below
    ``tolerance`` (then ``(True, q)``), ``(False, q + dls_step(...))`` within the limits.
    ``jacobian`` (6t, n) is PyBullet's, in the base frame; it is turned into the world's."""
    t = target_positions.shape[0]
    error = np.empty(6 * t)
    for k in range(t):
        for a in range(3):
            error[6 * k + a] = target_positions[k, a] - positions[k, a]
        goal = quaternion_at(target_quaternions[k], 0)
        now = quaternion_at(quaternions[k], 0)
        rx, ry, rz = rotation_error_q(goal, now)
        error[6 * k + 3] = rx
        error[6 * k + 4] = ry
        error[6 * k + 5] = rz
    if np.max(np.abs(error)) < tolerance:
        return True, q
    world = np.empty_like(jacobian)
    for block in range(2 * t):
        rows = slice(3 * block, 3 * block + 3)
        world[rows] = base2world @ jacobian[rows]
    step = dls_step(world, error, q, rest, cost)
    return False, np.minimum(np.maximum(q + step, lower), upper)


__all__ = ["dls_step", "solve_palms"]
