"""Dynamic potential field (Park et al. 2008) on points rigidly attached to the object.

For a point at ``x`` moving with ``v``, with ``c`` the nearest obstacle point, ``r = x - c``,
``p`` the distance and ``n = r / |r|`` (obstacle to point):

    cos(theta) = v . n / |v|        theta: angle between v and the obstacle-to-point vector
    U = lambda (-cos theta)^beta |v| g(p)    if theta in (pi/2, pi] (approaching), else 0
    g(p) = 1/p - 1/p0 for p < p0, else 0    (p0 = inf is Park et al.'s 1/p)

so a point heading straight at the obstacle has ``theta = pi``. The coupling is ``-grad_x U``
with the nearest point held fixed (Park et al.'s point obstacle; exact for point obstacles, a
first-order model for surfaces). With ``C = -cos theta > 0``::

    -grad U = lambda [ beta C^(beta-1) g(p) (v - (v.n) n) / p  +  |v| C^beta n / p^2 ]

The first term turns the velocity away from the obstacle (it is perpendicular to ``n``), the
second pushes along ``n``; head on, it is ``lambda |v| / p^2`` opposite to the velocity.
``p`` is clipped below at ``min_distance`` so contact stays finite. ``lambda`` is in m^2/s.

Mapping to the object (a documented choice)
-------------------------------------------
Points are offsets ``r_i`` in the object frame; in the world ``x_i = y + R(q) r_i`` and
``v_i = v + omega x (R r_i)``. The object gets ``linear = sum_i a_i`` (a sum, not a mean, so
one forearm point near an obstacle is not diluted by the far ones) and
``angular = sum_i (R r_i) x a_i / rho^2``, with ``rho`` a radius of gyration (default the RMS
lever arm): a single point at lever arm ``rho`` pushed tangentially by ``a`` then gets exactly
``a`` of tangential acceleration from the rotation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.couplings._checks import ZERO3, assign, positive
from skills.couplings.distance_queries import (
    DistanceQuery,
    MovingPoints,
    SphereObstacles,
    nearest_spheres_kernel,
    rows_dot,
)
from skills.kernel import kernel, matrix_q, quaternion_at
from skills.program import Kind, Packer
from skills.state import STATE_SIZE, PoseState, PoseTarget
from skills.types import Array

_ZERO = np.array(0.0)
_TINY = np.array(1e-300)


def potential(
    points: Array,
    velocities: Array,
    closest: Array,
    distances: Array,
    gain: float,
    beta: float,
    influence: float = math.inf,
    min_distance: float = 1e-3,
) -> Array:
    """The dynamic potential ``U`` per point (for checks and plots), shape (N,), m^2/s^2.

    Parameters
    ----------
    points, velocities, closest : ndarray, shape (N, 3)
        Positions, velocities and nearest obstacle points, world frame, m and m/s.
    distances : ndarray, shape (N,)
        Distances to the obstacle, m.
    gain, beta, influence, min_distance
        As :class:`PotentialFieldAvoidance`.
    """
    r = outward(points, closest, distances)
    rn = np.linalg.norm(r, axis=1)
    speed = np.linalg.norm(velocities, axis=1)
    c = -np.einsum("nk,nk->n", velocities, r) / np.maximum(rn * speed, 1e-300)
    p = np.maximum(distances, min_distance)
    g = np.where(p < influence, 1.0 / p - 1.0 / influence, 0.0)
    u: Array = gain * np.maximum(c, 0.0) ** beta * speed * g
    return u


def outward(points: Array, closest: Array, distances: Array) -> Array:
    """Each point's offset from its nearest obstacle point, turned to point out of the
    obstacle: ``points - closest`` outside it, the reverse inside (a negative distance), where
    the surface's nearest point lies beyond the point and the offset points in."""
    r: Array = points - closest
    inside = distances < 0.0
    if inside.any():
        r[inside] *= -1.0
    return r


def point_accelerations(
    points: Array,
    velocities: Array,
    closest: Array,
    distances: Array,
    gain: float,
    beta: float,
    influence: float = math.inf,
    min_distance: float = 1e-3,
) -> Array:
    """``-grad_x U`` per point, shape (N, 3), m/s^2 (arguments as :func:`potential`)."""
    r = outward(points, closest, distances)
    alpha, kappa = _coefficients(
        rows_dot(r, r),
        rows_dot(velocities, r),
        rows_dot(velocities, velocities),
        distances,
        beta,
        influence,
        min_distance,
    )
    out: Array = gain * (alpha[:, None] * velocities + kappa[:, None] * r)
    return out


def _coefficients(
    rr: Array,
    vr: Array,
    vv: Array,
    distances: Array,
    beta: float,
    influence: float,
    min_distance: float,
) -> tuple[Array, Array]:
    """Per-point ``alpha, kappa`` with ``-grad U = lambda (alpha v + kappa r)``.

    With ``q = -v.r``, ``C = q / (|r| |v|)``, ``h = C^(beta-1) / p``::

        alpha = beta h g(p)        kappa = (q / |r|^2) h (beta g(p) + 1 / p)

    which is the docstring's gradient regrouped (``v.n = -q / |r|``, ``|v| C / |r| = q / |r|^2``)
    so that every operation is one call on N values: this runs every control tick.
    """
    # 0-d array constants: numpy converts a Python float on every call, which costs more
    # than the arithmetic on a few points.
    q = -vr
    c = np.maximum(q, _ZERO)
    c /= np.maximum(np.sqrt(rr * vv), _TINY)
    ip = np.reciprocal(np.maximum(distances, min_distance))
    if math.isfinite(influence):
        g = np.maximum(ip - 1.0 / influence, _ZERO)
        c *= g > _ZERO  # U = 0 beyond the influence: so is its gradient's 1/p^2 part
    else:
        g = ip
    if beta == 2.0:
        h = c * ip
    elif beta == 1.0:  # C^0 = 1 would leak into receding points, where U is flat
        h = np.where(c > _ZERO, ip, _ZERO)
    else:
        h = c ** (beta - 1.0) * ip
    alpha = beta * g
    kappa = alpha + ip
    alpha *= h
    kappa *= h
    kappa *= q
    kappa /= np.maximum(rr, _TINY)
    return alpha, kappa


@dataclass(frozen=True, eq=False, init=False)
class PotentialFieldAvoidance:
    """Pushes the object away when any of its attached points approaches an obstacle.

    Parameters
    ----------
    query : DistanceQuery
        ``query(points (N, 3)) -> (distances (N,), closest_points (N, 3))`` in the world
        frame, m: the nearest obstacle point per query point (e.g. from FCL).
    points_object : array_like, shape (N, 3)
        Points in the object frame {O}, m (object corners, arm-link points). N may be 0.
    gain : float
        ``lambda``, m^2/s (> 0).
    beta : float
        Exponent on ``-cos theta`` (>= 1 keeps the acceleration finite at theta = pi/2).
    influence : float
        ``p0``, m: beyond it a point is ignored (> 0; inf for Park et al.'s plain ``1/p``).
    min_distance : float
        Distances are clipped below at this, m (> 0).
    gyration_radius : float or None
        ``rho``, m, for the angular mapping; None uses the RMS of the offsets' norms.
    """

    query: DistanceQuery
    points_object: Array
    gain: float
    beta: float
    influence: float
    min_distance: float
    gyration_radius: float | None

    def __init__(
        self,
        query: DistanceQuery,
        points_object: ArrayLike,
        gain: float = 0.05,
        beta: float = 2.0,
        influence: float = 0.3,
        min_distance: float = 1e-3,
        gyration_radius: float | None = None,
    ) -> None:
        assign(
            self,
            query=query,
            points_object=points_object,
            gain=gain,
            beta=beta,
            influence=influence,
            min_distance=min_distance,
            gyration_radius=gyration_radius,
        )
        self.__post_init__()

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "gain", positive(self.gain, "gain"))
        beta = float(self.beta)
        if not (math.isfinite(beta) and beta >= 1.0):
            raise ValueError(f"beta: expected a finite number >= 1, got {self.beta!r}")
        set_(self, "beta", beta)
        influence = float(self.influence)
        if not influence > 0.0:
            raise ValueError(
                f"influence: expected a distance > 0 m (or inf), got {self.influence!r}"
            )
        set_(self, "influence", influence)
        set_(self, "min_distance", positive(self.min_distance, "min_distance"))
        if self.gyration_radius is not None:
            set_(self, "gyration_radius", positive(self.gyration_radius, "gyration_radius"))
        if not callable(self.query):
            raise ValueError(
                f"query: expected a callable points -> (distances, closest), got {self.query!r}"
            )
        self._set_points(self.points_object)

    def _set_points(self, points_object: ArrayLike) -> None:
        pts = np.array(points_object, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3:
            if pts.size != 0:
                raise ValueError(f"points_object: expected shape (N, 3), got {pts.shape}")
            pts = np.zeros((0, 3))
        if not np.all(np.isfinite(pts)):
            raise ValueError("points_object: expected finite values, got NaN or inf")
        pts.setflags(write=False)
        object.__setattr__(self, "points_object", pts)

    def with_points(self, points_object: ArrayLike) -> PotentialFieldAvoidance:
        """The same field on other points (N, 3) in the object frame, m."""
        return replace(self, points_object=np.asarray(points_object, dtype=float))

    def with_query(self, query: DistanceQuery) -> PotentialFieldAvoidance:
        """The same field against other obstacles."""
        return replace(self, query=query)

    def inverse_gyration2(self, points_object: Array) -> float:
        """``1 / rho^2`` for the angular mapping of ``points_object`` (N, 3) (0 for none)."""
        if self.gyration_radius is not None:
            rho2 = self.gyration_radius**2
        else:
            n = points_object.shape[0]
            rho2 = float(np.einsum("nk,nk->", points_object, points_object)) / n if n else 0.0
        return 1.0 / rho2 if rho2 > 1e-12 else 0.0

    def world_points(self, state: PoseState) -> tuple[Array, Array, Array]:
        """Lever arms ``R r_i``, positions and velocities of the points, each (N, 3), world."""
        lever = self.points_object @ quat.to_matrix(state.orientation).T
        velocities = state.velocity + np.cross(state.angular_velocity, lever)
        return lever, state.position + lever, velocities

    def point_accelerations(self, state: PoseState) -> Array:
        """``-grad U`` of every point, (N, 3), world frame, m/s^2."""
        _, x, v = self.world_points(state)
        distances, closest = self.query(x)
        return point_accelerations(
            x, v, closest, distances, self.gain, self.beta, self.influence, self.min_distance
        )

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Linear (m/s^2) and angular (rad/s^2) push on the object, world frame.

        The numpy reference, on :attr:`points_object` (compositions run
        :func:`potential_kernel`, with the query's moving points too).

        Parameters
        ----------
        state : PoseState
            The object's pose and twist in the world.
        target : PoseTarget
            Unused.

        Returns
        -------
        linear, angular : ndarray, shape (3,)
        """
        if self.points_object.shape[0] == 0:
            return ZERO3.copy(), ZERO3.copy()
        lever, x, v = self.world_points(state)
        distances, closest = self.query(x)
        if np.min(distances) >= self.influence:
            return ZERO3.copy(), ZERO3.copy()
        a = self.gain * (
            point_accelerations(
                x, v, closest, distances, 1.0, self.beta, self.influence, self.min_distance
            )
        )
        return a.sum(axis=0), self.inverse_gyration2(self.points_object) * np.cross(lever, a).sum(
            axis=0
        )

    def pack(self, packer: Packer, weight: float) -> None:
        """A POTENTIAL block ``[w, gain, beta, influence, min_distance, 1/rho^2, N, M,
        points N x 3, ...]``: ``M`` spheres ``[centre, radius]`` when the query is
        :class:`SphereObstacles` (answered in the kernel), else ``M = -1`` and
        ``[distances N, closest N x 3]``, which a hook writes from the query before each step.
        The query's moving points, if any, follow the attached ones; a refresher writes them
        before each closed-loop step, and once now, at the start state.
        """
        moving = self.query.moving_points if isinstance(self.query, MovingPoints) else None
        fixed = self.points_object.shape[0]
        n = fixed + (np.asarray(moving()).reshape(-1, 3).shape[0] if moving else 0)
        spheres = self.query.packed() if isinstance(self.query, SphereObstacles) else None
        head = [weight, self.gain, self.beta, self.influence, self.min_distance]
        inv_rho2 = self.inverse_gyration2(self.points_object)
        points = self.points_object.ravel().tolist() + [0.0] * (3 * (n - fixed))
        if spheres is not None:
            tail = [float(len(spheres) // 4), *points, *spheres]
        else:
            tail = [-1.0, *points, *([0.0] * (4 * n))]
        at = packer.add(Kind.POTENTIAL, [*head, inv_rho2, float(n), *tail])
        b = STATE_SIZE * packer.space
        first = at + POTENTIAL_HEADER
        if moving is not None:
            packer.refreshers.append(self._refresher(moving, b, first, fixed, n, at + 5))
        if spheres is None:
            packer.hooks.append(_query_hook(self.query, b, at, n))

    def _refresher(
        self, moving: Callable[[], Array], b: int, first: int, fixed: int, n: int, rho_at: int
    ) -> Callable[[Array, Array], None]:
        def refresh(x: Array, data: Array) -> None:
            now = np.asarray(moving(), dtype=float).reshape(-1, 3)
            if now.shape[0] != n - fixed:
                raise ValueError(
                    f"moving_points: expected {n - fixed} points, as when the field was "
                    f"packed, got {now.shape[0]}"
                )
            to_world = quat.to_matrix(x[b + 9 : b + 13])
            data[first + 3 * fixed : first + 3 * n] = ((now - x[b : b + 3]) @ to_world).ravel()
            data[rho_at] = self.inverse_gyration2(data[first : first + 3 * n].reshape(n, 3))

        return refresh


#: Where a potential block's points start (after the weight and the parameters).
POTENTIAL_HEADER = 8


def _query_hook(query: DistanceQuery, b: int, at: int, n: int) -> Callable[[Array, Array], None]:
    """Write the query's answer for the field's world points at the step's state."""
    after = at + POTENTIAL_HEADER + 3 * n

    def answer(x: Array, data: Array) -> None:
        distances, closest = query(world_points_kernel(x, b, data, at))
        d = np.asarray(distances, dtype=float)
        c = np.asarray(closest, dtype=float)
        if d.shape != (n,) or c.shape != (n, 3):
            raise ValueError(
                f"query: expected distances ({n},) and closest points ({n}, 3), got "
                f"{d.shape} and {c.shape}"
            )
        data[after : after + n] = d
        data[after + n : after + 4 * n] = c.ravel()

    return answer


@kernel
def world_points_kernel(x: Array, b: int, data: Array, o: int) -> Array:
    """A potential block's points in the world (N, 3), from the state at ``x[b:]``."""
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
def potential_kernel(x: Array, b: int, data: Array, o: int, a: Array) -> None:
    """:meth:`PotentialFieldAvoidance.acceleration` of the object state at ``x[b:]`` from its
    block at ``data[o:]`` (see :meth:`PotentialFieldAvoidance.pack`), into ``a`` (6)."""
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
    near: Array = np.empty((n, 4))  # distance, closest point
    if spheres < 0:
        for i in range(n):
            near[i, 0] = data[after + i]
            near[i, 1] = data[after + n + 3 * i]
            near[i, 2] = data[after + n + 3 * i + 1]
            near[i, 3] = data[after + n + 3 * i + 2]
    else:
        near = nearest_spheres_kernel(world_points_kernel(x, b, data, o), data, after, spheres)
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
        d = near[i, 0]
        out = -1.0 if d < 0.0 else 1.0  # inside, the surface's nearest point lies beyond
        rx = out * ((px + ax) - near[i, 1])
        ry = out * ((py + ay) - near[i, 2])
        rz = out * ((pz + az) - near[i, 3])
        q = -(vx * rx + vy * ry + vz * rz)
        if q <= 0.0:
            continue  # receding or sliding past: U is flat
        ip = 1.0 / (d if d > p_min else p_min)
        g = ip - inv_p0
        if g <= 0.0:
            continue  # at or beyond the influence distance
        rr = rx * rx + ry * ry + rz * rz
        h = ip * (q / max(math.sqrt(rr * (vx * vx + vy * vy + vz * vz)), 1e-300)) ** power
        alpha = beta * g
        kappa = (alpha + ip) * h * q / max(rr, 1e-300)
        alpha *= h
        ux = alpha * vx + kappa * rx  # this point's -grad U / lambda
        uy = alpha * vy + kappa * ry
        uz = alpha * vz + kappa * rz
        fx += ux
        fy += uy
        fz += uz
        tx += ay * uz - az * uy  # lever arm x push
        ty += az * ux - ax * uz
        tz += ax * uy - ay * ux
    k = gain * inv_rho2
    a[0], a[1], a[2] = gain * fx, gain * fy, gain * fz
    a[3], a[4], a[5] = k * tx, k * ty, k * tz
