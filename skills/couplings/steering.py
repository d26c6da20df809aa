"""Obstacle steering (Hoffmann et al. 2009) with a distance factor (Pairet et al. RA-L 2019).

A human-like steering law for the object's position: for each obstacle,

    a = gamma * R(r) v * phi * exp(-beta * phi) * exp(-k * d^2)

``v`` the velocity, ``phi`` in [0, pi] the angle between ``v`` and the direction to the obstacle
``o - y``, ``R(r)`` the 90 degree rotation about ``r = (o - y) x v``, and ``d`` the clearance
between the carried object's bounding sphere and the obstacle's sphere (0 when touching).

``R(r) v`` needs no rotation matrix: it is ``(v (D.v) - D |v|^2) / |D x v|`` with ``D = o - y``,
a vector of length ``|v|``, perpendicular to ``v`` and pointing away from the obstacle.

Decisions
---------
* No cutoff behind by default (``max_angle = pi``): Hoffmann's law unchanged, continuous,
  fading as ``phi exp(-beta phi)`` once the obstacle is abeam and vanishing straight behind.
  ``max_angle = pi / 2`` ignores obstacles behind the direction of travel instead, at the cost
  of a step of ``gamma (pi/2) exp(-beta pi/2) exp(-k d^2) |v|`` when one comes abeam. Measured
  on the human-like teacher of :mod:`skills.demos.avoidance` (0.6 m reach in 1 s, 6 cm sphere
  on the line): fitted with the cutoff, the rollout's peak acceleration was 15.8 m/s^2 and its
  jerk 6,100 m/s^3 at the step; without it, 4.0 m/s^2 and 92 m/s^3, the same clearance, and a
  better fit (relative residual 0.38 against 0.48).
* Heading exactly at, or exactly away from, an obstacle's centre (``sin phi < 1e-7``) gives
  zero: ``R`` has no axis there. At ``phi = 0`` the law's ``phi`` factor vanishes too, so it
  stays continuous (any offset breaks the tie); dead behind (``phi = pi``) Hoffmann's law is
  itself discontinuous, and zero is the middle of its two one-sided limits.
* Zero when the speed is below ``min_speed``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from skills.coupling import ZERO_ACCELERATION, AccelerationFloats
from skills.couplings._checks import ZERO3, non_negative, positive, vector
from skills.pose_dmp import PoseFloats, PoseState, PoseTarget
from skills.types import Array

#: Below this ``sin(phi)`` the obstacle is dead ahead or behind: the law has no direction (and
#: ``|D x v|`` from ``|D|^2 |v|^2 - (D.v)^2`` is rounding noise below about 2e-8).
_COLLINEAR = 1e-7


def steering_accelerations(
    positions: Array,
    velocities: Array,
    centres: Array,
    radii: Array,
    gamma: float,
    beta: float,
    k: float,
    max_angle: float = math.pi,
) -> Array:
    """The steering law for many states at once (the pure function behind the class).

    Parameters
    ----------
    positions, velocities : ndarray, shape (N, 3)
        States of the steered point, m and m/s.
    centres : ndarray, shape (M, 3)
        Obstacle centres, same frame, m.
    radii : ndarray, shape (M,)
        Obstacle radii plus the carried object's bounding radius, m.
    gamma : float
        Gain, 1/s.
    beta : float
        Angular decay, 1/rad.
    k : float
        Distance decay, 1/m^2.
    max_angle : float
        Obstacles at ``phi >= max_angle`` (rad) are ignored.

    Returns
    -------
    ndarray, shape (N, 3)
        Accelerations, m/s^2.
    """
    d_obs = centres[None, :, :] - positions[:, None, :]  # (N, M, 3) point to obstacle
    dv = np.einsum("nmk,nk->nm", d_obs, velocities)
    dd = np.einsum("nmk,nmk->nm", d_obs, d_obs)
    vv = np.einsum("nk,nk->n", velocities, velocities)
    cross = np.sqrt(np.maximum(dd * vv[:, None] - dv * dv, 0.0))
    phi = np.arctan2(cross, dv)
    clearance = np.maximum(np.sqrt(dd) - radii, 0.0)
    w = gamma * phi * np.exp(-beta * phi - k * clearance * clearance) / np.maximum(cross, 1e-300)
    w = np.where((phi < max_angle) & (cross > _COLLINEAR * np.sqrt(dd * vv[:, None])), w, 0.0)
    return velocities * np.sum(w * dv, axis=1)[:, None] - vv[:, None] * np.einsum(
        "nm,nmk->nk", w, d_obs
    )


@dataclass(frozen=True, eq=False, init=False)
class ObstacleSteering:
    """Steers the object's position around spherical obstacles (a :class:`CouplingTerm`).

    Parameters
    ----------
    gamma : float
        Gain, 1/s (> 0).
    beta : float
        Angular decay, 1/rad (> 0).
    k : float
        Distance decay, 1/m^2 (>= 0; 0 ignores distance, as Hoffmann et al.).
    centres : array_like, shape (M, 3)
        Obstacle centres in the DMP's frame (world for an absolute skill), m. M may be 0.
    radii : array_like, shape (M,)
        Obstacle radii, m (>= 0).
    object_radius : float
        Bounding radius of the carried object, m (>= 0); 0 steers a point.
    max_angle : float
        Obstacles at ``phi >= max_angle`` are ignored, rad in (0, pi]; pi keeps them all.
    min_speed : float
        Below this speed (m/s) the term is zero.
    """

    gamma: float
    beta: float
    k: float
    centres: Array
    radii: Array
    object_radius: float
    max_angle: float
    min_speed: float
    _reach: Array = field(init=False, repr=False)
    _single: tuple[float, float, float, float] | None = field(init=False, repr=False)

    def __init__(
        self,
        gamma: float,
        beta: float,
        k: float,
        centres: ArrayLike | None = None,
        radii: ArrayLike | None = None,
        object_radius: float = 0.0,
        max_angle: float = math.pi,
        min_speed: float = 1e-6,
    ) -> None:
        set_ = object.__setattr__
        set_(self, "gamma", positive(gamma, "gamma"))
        set_(self, "beta", positive(beta, "beta"))
        set_(self, "k", non_negative(k, "k"))
        set_(self, "object_radius", non_negative(object_radius, "object_radius"))
        set_(self, "min_speed", non_negative(min_speed, "min_speed"))
        angle = float(max_angle)
        if not 0.0 < angle <= math.pi:
            raise ValueError(f"max_angle: expected a value in (0, pi] rad, got {max_angle!r}")
        set_(self, "max_angle", angle)
        c = vector(
            np.reshape(np.asarray(() if centres is None else centres, float), (-1, 3)),
            (-1, 3),
            "centres",
        )
        r = vector(
            np.reshape(np.asarray(() if radii is None else radii, float), (-1,)), (-1,), "radii"
        )
        if r.shape[0] != c.shape[0]:
            raise ValueError(
                f"radii: expected one radius per centre ({c.shape[0]}), got {r.shape[0]}"
            )
        if np.any(r < 0.0):
            raise ValueError(f"radii: expected values >= 0 m, got {r.tolist()}")
        set_(self, "centres", c)
        set_(self, "radii", r)
        reach = r + self.object_radius
        reach.setflags(write=False)
        set_(self, "_reach", reach)
        # One obstacle (the usual case) is steered in floats: its centre and reach as floats.
        set_(self, "_single", (*c[0].tolist(), float(reach[0])) if c.shape[0] == 1 else None)

    def with_obstacles(self, centres: ArrayLike, radii: ArrayLike) -> ObstacleSteering:
        """The same law for another set of obstacles (centres (M, 3) m, radii (M,) m)."""
        return ObstacleSteering(
            self.gamma,
            self.beta,
            self.k,
            centres,
            radii,
            self.object_radius,
            self.max_angle,
            self.min_speed,
        )

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Steering acceleration of the position, m/s^2; the angular part is zero.

        Parameters
        ----------
        state : PoseState
            Uses ``position`` and ``velocity``.
        target : PoseTarget
            Unused.

        Returns
        -------
        linear, angular : ndarray, shape (3,)
        """
        a = self.scalar_acceleration(PoseFloats.of(state), target)
        return np.array(a[:3]), ZERO3.copy()

    def scalar_acceleration(self, pose: PoseFloats, target: PoseTarget) -> AccelerationFloats:
        """:meth:`acceleration` as floats."""
        vx, vy, vz = pose.velocity
        vv = vx * vx + vy * vy + vz * vz
        if vv <= self.min_speed * self.min_speed or self._reach.shape[0] == 0:
            return ZERO_ACCELERATION
        if self._single is not None:
            ax, ay, az = self._one_obstacle(self._single, pose.position, vx, vy, vz, vv)
        else:
            ax, ay, az = self._many_obstacles(pose.position, pose.velocity, vv).tolist()
        return (ax, ay, az, 0.0, 0.0, 0.0)

    def _many_obstacles(self, position: list[float], velocity: list[float], vv: float) -> Array:
        v = np.array(velocity)
        d_obs = self.centres - np.array(position)  # (M, 3) point to obstacle
        dv = d_obs @ v
        dd = np.einsum("mk,mk->m", d_obs, d_obs)
        cross = np.sqrt(np.maximum(dd * vv - dv * dv, 0.0))
        phi = np.arctan2(cross, dv)
        clearance = np.maximum(np.sqrt(dd) - self._reach, 0.0)
        w = np.exp(-self.beta * phi - self.k * clearance * clearance)
        w *= phi
        w /= np.maximum(cross, 1e-300)
        w[(phi >= self.max_angle) | (cross <= _COLLINEAR * np.sqrt(dd * vv))] = 0.0
        w *= self.gamma
        out: Array = v * float(w @ dv) - vv * (w @ d_obs)
        return out

    def _one_obstacle(
        self,
        obstacle: tuple[float, float, float, float],
        position: list[float],
        vx: float,
        vy: float,
        vz: float,
        vv: float,
    ) -> tuple[float, float, float]:
        # One obstacle (centre, reach) in float arithmetic: numpy's per-call overhead would
        # cost ten times the maths on 3-vectors. Same law as the vectorised path.
        ox, oy, oz, reach = obstacle
        px, py, pz = position
        dx, dy, dz = ox - px, oy - py, oz - pz
        dv = dx * vx + dy * vy + dz * vz
        dd = dx * dx + dy * dy + dz * dz
        cross = math.sqrt(max(dd * vv - dv * dv, 0.0))
        phi = math.atan2(cross, dv)
        if phi >= self.max_angle or cross <= _COLLINEAR * math.sqrt(dd * vv):
            return (0.0, 0.0, 0.0)
        clearance = max(math.sqrt(dd) - reach, 0.0)
        w = self.gamma * phi * math.exp(-self.beta * phi - self.k * clearance * clearance) / cross
        a = w * dv
        b = w * vv
        return (a * vx - b * dx, a * vy - b * dy, a * vz - b * dz)
