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
* Obstacles at ``phi >= max_angle`` (default ``pi / 2``: behind the direction of travel) are
  ignored. An obstacle behind cannot be hit by going on; steering from it would only delay
  the return to the goal. The step this makes at ``phi = max_angle`` is
  ``gamma (pi/2) exp(-beta pi/2) |v|``, small for the usual ``beta`` (pass ``max_angle=pi``
  for Hoffmann's law unchanged).
* Heading exactly at an obstacle's centre (``phi = 0``) gives zero: the law has no preferred
  side there, and its ``phi`` factor vanishes. Any offset breaks the tie.
* Zero when the speed is below ``min_speed``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from skills.couplings._checks import ZERO3, non_negative, positive, vector
from skills.pose_dmp import PoseState, PoseTarget
from skills.types import Array

_TINY = 1e-12


def steering_accelerations(
    positions: Array,
    velocities: Array,
    centres: Array,
    radii: Array,
    gamma: float,
    beta: float,
    k: float,
    max_angle: float = math.pi / 2,
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
    w = gamma * phi * np.exp(-beta * phi - k * clearance * clearance) / np.maximum(cross, _TINY)
    w = np.where((phi < max_angle) & (vv[:, None] > _TINY), w, 0.0)
    return velocities * np.sum(w * dv, axis=1)[:, None] - vv[:, None] * np.einsum(
        "nm,nmk->nk", w, d_obs
    )


@dataclass(frozen=True, eq=False)
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
        Obstacles at ``phi >= max_angle`` are ignored, rad in (0, pi].
    min_speed : float
        Below this speed (m/s) the term is zero.
    """

    gamma: float
    beta: float
    k: float
    centres: Array = field(default_factory=lambda: np.zeros((0, 3)))
    radii: Array = field(default_factory=lambda: np.zeros(0))
    object_radius: float = 0.0
    max_angle: float = math.pi / 2
    min_speed: float = 1e-6
    _reach: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "gamma", positive(self.gamma, "gamma"))
        set_(self, "beta", positive(self.beta, "beta"))
        set_(self, "k", non_negative(self.k, "k"))
        set_(self, "object_radius", non_negative(self.object_radius, "object_radius"))
        set_(self, "min_speed", non_negative(self.min_speed, "min_speed"))
        angle = float(self.max_angle)
        if not 0.0 < angle <= math.pi:
            raise ValueError(f"max_angle: expected a value in (0, pi] rad, got {self.max_angle!r}")
        set_(self, "max_angle", angle)
        centres = vector(np.reshape(self.centres, (-1, 3)), (-1, 3), "centres")
        radii = vector(np.reshape(self.radii, (-1,)), (-1,), "radii")
        if radii.shape[0] != centres.shape[0]:
            raise ValueError(
                f"radii: expected one radius per centre ({centres.shape[0]}), got {radii.shape[0]}"
            )
        if np.any(radii < 0.0):
            raise ValueError(f"radii: expected values >= 0 m, got {radii.tolist()}")
        set_(self, "centres", centres)
        set_(self, "radii", radii)
        reach = radii + self.object_radius
        reach.setflags(write=False)
        set_(self, "_reach", reach)

    def with_obstacles(self, centres: ArrayLike, radii: ArrayLike) -> ObstacleSteering:
        """The same law for another set of obstacles (centres (M, 3) m, radii (M,) m)."""
        return replace(self, centres=np.asarray(centres), radii=np.asarray(radii))

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
        v = state.velocity
        vx, vy, vz = v.tolist()
        vv = vx * vx + vy * vy + vz * vz
        m = self._reach.shape[0]
        if vv <= self.min_speed * self.min_speed or m == 0:
            return ZERO3.copy(), ZERO3.copy()
        if m == 1:
            return self._one_obstacle(state.position, vx, vy, vz, vv), ZERO3.copy()
        d_obs = self.centres - state.position  # (M, 3) point to obstacle
        dv = d_obs @ v
        dd = np.einsum("mk,mk->m", d_obs, d_obs)
        cross = np.sqrt(np.maximum(dd * vv - dv * dv, 0.0))
        phi = np.arctan2(cross, dv)
        clearance = np.maximum(np.sqrt(dd) - self._reach, 0.0)
        w = np.exp(-self.beta * phi - self.k * clearance * clearance)
        w *= phi
        w /= np.maximum(cross, _TINY)
        w[phi >= self.max_angle] = 0.0
        w *= self.gamma
        return v * float(w @ dv) - vv * (w @ d_obs), ZERO3.copy()

    def _one_obstacle(self, position: Array, vx: float, vy: float, vz: float, vv: float) -> Array:
        # One obstacle (the usual case) in float arithmetic: numpy's per-call overhead would
        # cost ten times the maths on 3-vectors. Same law as the vectorised path.
        ox, oy, oz = self.centres[0].tolist()
        px, py, pz = position.tolist()
        dx, dy, dz = ox - px, oy - py, oz - pz
        dv = dx * vx + dy * vy + dz * vz
        dd = dx * dx + dy * dy + dz * dz
        cross = math.sqrt(max(dd * vv - dv * dv, 0.0))
        phi = math.atan2(cross, dv)
        if phi >= self.max_angle:
            return ZERO3.copy()
        clearance = max(math.sqrt(dd) - float(self._reach[0]), 0.0)
        w = (
            self.gamma
            * phi
            * math.exp(-self.beta * phi - self.k * clearance * clearance)
            / max(cross, _TINY)
        )
        a = w * dv
        b = w * vv
        return np.array((a * vx - b * dx, a * vy - b * dy, a * vz - b * dz))
