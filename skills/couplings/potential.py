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
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.coupling import ZERO_ACCELERATION, AccelerationFloats
from skills.couplings._checks import ZERO3, assign, positive, vector
from skills.pose_dmp import PoseFloats, PoseState, PoseTarget
from skills.types import Array

_ZERO = np.array(0.0)
_TINY = np.array(1e-300)

#: ``query(points (N, 3)) -> (distances (N,), closest_points (N, 3))``, world frame, m.
DistanceQuery = Callable[[Array], tuple[Array, Array]]


@dataclass(frozen=True, eq=False, init=False)
class SphereObstacles:
    """A :data:`DistanceQuery` to spheres in closed form: each point's nearest sphere.

    Signed, negative inside a sphere (as :meth:`worlds.collision.CollisionWorld.query` gives
    for spheres); with no spheres every distance is ``inf`` and every closest point NaN. The
    compiled composition step (:mod:`skills.compiled`) evaluates it inside its kernel.

    Parameters
    ----------
    centres : array_like, shape (M, 3)
        World frame, m.
    radii : array_like, shape (M,)
        m (>= 0).
    """

    centres: Array
    radii: Array

    def __init__(self, centres: ArrayLike, radii: ArrayLike) -> None:
        c = vector(np.reshape(np.asarray(centres, dtype=float), (-1, 3)), (-1, 3), "centres")
        r = vector(np.reshape(np.asarray(radii, dtype=float), (-1,)), (-1,), "radii")
        if r.shape[0] != c.shape[0]:
            raise ValueError(
                f"radii: expected one radius per centre ({c.shape[0]}), got {r.shape[0]}"
            )
        if np.any(r < 0.0):
            raise ValueError(f"radii: expected values >= 0 m, got {r.tolist()}")
        assign(self, centres=c, radii=r)

    def __call__(self, points: Array) -> tuple[Array, Array]:
        """Distances (N,) from ``points`` (N, 3) to the nearest sphere, and closest points."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        if self.radii.shape[0] == 0:
            return np.full(len(p), np.inf), np.full(p.shape, np.nan)
        if self.radii.shape[0] == 1:  # the usual case, in a third of the calls
            centre, radius = self.centres[0], self.radii[0]
            diff1 = p - centre
            norm1 = np.sqrt(_dot(diff1, diff1))
            scale1 = radius / np.maximum(norm1, 1e-12)
            return norm1 - radius, centre + diff1 * scale1[:, None]
        diff = p[:, None, :] - self.centres  # (N, M, 3), sphere centre to point
        norm = np.sqrt(np.einsum("nmk,nmk->nm", diff, diff))
        gaps = norm - self.radii
        rows = np.arange(len(p))
        j = np.argmin(gaps, axis=1)  # the first of equals, as the kernel
        d = diff[rows, j]
        scale = self.radii[j] / np.maximum(norm[rows, j], 1e-12)
        return gaps[rows, j], self.centres[j] + d * scale[:, None]


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
    r = points - closest
    rn = np.linalg.norm(r, axis=1)
    speed = np.linalg.norm(velocities, axis=1)
    c = -np.einsum("nk,nk->n", velocities, r) / np.maximum(rn * speed, 1e-300)
    p = np.maximum(distances, min_distance)
    g = np.where(p < influence, 1.0 / p - 1.0 / influence, 0.0)
    u: Array = gain * np.maximum(c, 0.0) ** beta * speed * g
    return u


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
    r = points - closest
    alpha, kappa = _coefficients(
        _dot(r, r),
        _dot(velocities, r),
        _dot(velocities, velocities),
        distances,
        beta,
        influence,
        min_distance,
    )
    out: Array = gain * (alpha[:, None] * velocities + kappa[:, None] * r)
    return out


def _einsum_dot(a: Array, b: Array) -> Array:
    """Row-wise dot products of (N, 3) arrays, shape (N,)."""
    return np.einsum("nk,nk->n", a, b)


# numpy >= 2 has vecdot, a ufunc several times cheaper than einsum on a few rows.
_dot: Callable[[Array, Array], Array] = getattr(np, "vecdot", _einsum_dot)


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
    _inv_rho2: float = field(init=False, repr=False)
    _points_h: Array = field(init=False, repr=False)

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
        # The per-tick part of construction (arm-link points move every control tick), kept
        # to a few numpy calls: numpy's reductions cost more than the maths on 8 points.
        pts = np.array(points_object, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3:
            if pts.size != 0:
                raise ValueError(f"points_object: expected shape (N, 3), got {pts.shape}")
            pts = np.zeros((0, 3))
        n = pts.shape[0]
        total = sum(_dot(pts, pts).tolist())  # NaN or inf anywhere makes it non-finite
        if not math.isfinite(total):
            raise ValueError("points_object: expected finite values, got NaN or inf")
        pts.setflags(write=False)
        homogeneous = np.empty((n, 4))
        homogeneous[:, :3] = pts
        homogeneous[:, 3] = 1.0
        rho2 = total / n if n else 0.0
        if self.gyration_radius is not None:
            rho2 = self.gyration_radius**2
        set_ = object.__setattr__
        set_(self, "points_object", pts)
        set_(self, "_points_h", homogeneous)
        set_(self, "_inv_rho2", 1.0 / rho2 if rho2 > 1e-12 else 0.0)

    def with_points(self, points_object: ArrayLike) -> PotentialFieldAvoidance:
        """The same field on other points (N, 3) in the object frame, m (cheap: every tick)."""
        out = object.__new__(PotentialFieldAvoidance)
        out.__dict__.update(self.__dict__)  # copy.copy's reduce protocol costs 5x more
        out._set_points(points_object)
        return out

    def with_query(self, query: DistanceQuery) -> PotentialFieldAvoidance:
        """The same field against other obstacles."""
        return replace(self, query=query)

    def world_points(self, state: PoseState) -> tuple[Array, Array, Array]:
        """Lever arms ``R r_i``, positions and velocities of the points, each (N, 3), world."""
        both = self._world(PoseFloats.of(state))
        return both[:, :3], both[:, 7:], both[:, 4:7]

    def _world(self, pose: PoseFloats) -> Array:
        # One product [r_i, 1] @ T gives [R r_i, 1, v + omega x R r_i, y + R r_i], (N, 10):
        # the column of ones later turns the torque product into the force sum as well.
        m00, m01, m02, m10, m11, m12, m20, m21, m22 = quat.matrix_floats(pose.orientation)
        wx, wy, wz = pose.angular_velocity
        vx, vy, vz = pose.velocity
        px, py, pz = pose.position
        return self._points_h @ np.array(
            (
                m00,
                m10,
                m20,
                0.0,
                wy * m20 - wz * m10,
                wz * m00 - wx * m20,
                wx * m10 - wy * m00,
                m00,
                m10,
                m20,
                m01,
                m11,
                m21,
                0.0,
                wy * m21 - wz * m11,
                wz * m01 - wx * m21,
                wx * m11 - wy * m01,
                m01,
                m11,
                m21,
                m02,
                m12,
                m22,
                0.0,
                wy * m22 - wz * m12,
                wz * m02 - wx * m22,
                wx * m12 - wy * m02,
                m02,
                m12,
                m22,
                0.0,
                0.0,
                0.0,
                1.0,
                vx,
                vy,
                vz,
                px,
                py,
                pz,
            )
        ).reshape(4, 10)

    def point_accelerations(self, state: PoseState) -> Array:
        """``-grad U`` of every point, (N, 3), world frame, m/s^2."""
        _, x, v = self.world_points(state)
        distances, closest = self.query(x)
        return point_accelerations(
            x, v, closest, distances, self.gain, self.beta, self.influence, self.min_distance
        )

    def acceleration(self, state: PoseState, target: PoseTarget) -> tuple[Array, Array]:
        """Linear (m/s^2) and angular (rad/s^2) push on the object, world frame.

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
        both = self._world(PoseFloats.of(state))
        v = both[:, 4:7]
        distances, closest = self.query(both[:, 7:])
        r = both[:, 7:] - closest
        vr = _dot(v, r)
        # Python's min on a few floats is cheaper than numpy's reduction machinery.
        if min(distances.tolist()) >= self.influence or min(vr.tolist()) >= 0.0:
            return ZERO3.copy(), ZERO3.copy()  # nothing near or nothing approaching: the usual case
        alpha, kappa = _coefficients(
            _dot(r, r), vr, _dot(v, v), distances, self.beta, self.influence, self.min_distance
        )
        a = alpha[:, None] * v
        a += kappa[:, None] * r
        # rows 0-2: sum_n arm_i a_j (the torque is its antisymmetric part); row 3: sum_n a_j
        m = (both[:, :4].T @ a).ravel().tolist()
        lam = self.gain
        k = lam * self._inv_rho2
        return np.array((lam * m[9], lam * m[10], lam * m[11])), np.array(
            (k * (m[5] - m[7]), k * (m[6] - m[2]), k * (m[1] - m[3]))
        )

    def scalar_acceleration(self, pose: PoseFloats, target: PoseTarget) -> AccelerationFloats:
        """:meth:`acceleration` as floats, summed one point at a time.

        The world points and the distance query stay one vectorised pass; the per-point
        coefficients and sums are floats: for the handful of link points a composition
        carries, numpy's per-call cost over the twenty-odd operations of
        :func:`_coefficients` exceeds the whole per-point arithmetic. Same formula: with
        ``q = -v.r > 0``, ``C = q / (|r| |v|)``, ``h = C^(beta-1) / p``, the point's push is
        ``alpha v + kappa r`` with ``alpha = beta h g(p)`` and
        ``kappa = (q / |r|^2) h (beta g(p) + 1 / p)``.
        """
        if self.points_object.shape[0] == 0:
            return ZERO_ACCELERATION
        both = self._world(pose)
        distances, closest = self.query(both[:, 7:])
        dist = distances.tolist()
        if min(dist) >= self.influence:
            return ZERO_ACCELERATION  # nothing near: the usual case
        beta, power, p_min = self.beta, self.beta - 1.0, self.min_distance
        inv_p0 = 1.0 / self.influence  # 0 for Park et al.'s plain 1/p
        fx = fy = fz = tx = ty = tz = 0.0
        for (ax, ay, az, _, vx, vy, vz, x, y, z), (cx, cy, cz), d in zip(
            both.tolist(), closest.tolist(), dist, strict=True
        ):
            rx, ry, rz = x - cx, y - cy, z - cz
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
        lam = self.gain
        k = lam * self._inv_rho2
        return (lam * fx, lam * fy, lam * fz, k * tx, k * ty, k * tz)
