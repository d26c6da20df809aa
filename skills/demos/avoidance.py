"""A synthetic human-like teacher that moves around a spherical obstacle.

The teacher does not use the steering law it will be fitted with: its path is the
minimum-jerk motion from rest at the start to rest at the goal through a via-point beside the
obstacle (Flash and Hogan's via-point model of human reaching), at the obstacle's radius plus a
clearance, placed perpendicular to the start-goal line where, and when, the straight motion
would have reached the obstacle. A seeded,
smooth tremor that fades out at both ends makes it look recorded.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skills.couplings._checks import non_negative, positive, unit_vector, vector
from skills.demos._smooth import min_jerk, tremor
from skills.types import Array


def _derivative_row(u: float, order: int) -> Array:
    """``d^order/du^order [1, u, ..., u^5]`` at ``u``, shape (6,)."""
    k = np.arange(6)
    falling = np.ones(6)
    for i in range(order):  # k (k-1) ... (k-order+1), zero where k < order
        falling *= k - i
    return falling * np.where(k >= order, float(u) ** np.maximum(k - order, 0), 0.0)


def _min_jerk_through(
    start: Array, goal: Array, u: Array, via: Array | None, u_via: float
) -> Array:
    """Minimum-jerk positions (N, 3) at normalised times ``u``, rest to rest, through ``via``.

    Without a via-point it is the quintic of Flash and Hogan. With one it is their via-point
    solution: two quintics meeting at ``u_via``, equal in position, velocity, acceleration,
    jerk and snap there (only the fifth derivative jumps), solved as one 12 x 12 system.
    """
    if via is None:
        return start + np.outer(min_jerk(u), goal - start)
    z6 = np.zeros(6)
    rows, rhs = [], []
    for d in range(3):  # rest at both ends
        rows += [np.r_[_derivative_row(0.0, d), z6], np.r_[z6, _derivative_row(1.0, d)]]
        rhs += [start if d == 0 else np.zeros(3), goal if d == 0 else np.zeros(3)]
    rows += [np.r_[_derivative_row(u_via, 0), z6], np.r_[z6, _derivative_row(u_via, 0)]]
    rhs += [via, via]
    for d in range(1, 5):
        rows.append(np.r_[_derivative_row(u_via, d), -_derivative_row(u_via, d)])
        rhs.append(np.zeros(3))
    # Here: skills.demos.io (a run reads its demonstrations) need not import scipy.linalg.
    from scipy import linalg

    coef = linalg.solve(np.array(rows), np.array(rhs))  # (12, 3)
    powers = u[:, None] ** np.arange(6)
    return np.where((u <= u_via)[:, None], powers @ coef[:6], powers @ coef[6:])


def straight_demo(
    start: ArrayLike,
    goal: ArrayLike,
    duration: float = 2.0,
    n_samples: int = 400,
    noise: float = 5e-4,
    rng: np.random.Generator | None = None,
) -> tuple[Array, Array, Array]:
    """The same teacher with no obstacle: the base motion an avoidance is learnt against.

    Parameters
    ----------
    start, goal : array_like, shape (3,)
        m.
    duration : float
        s.
    n_samples : int
        At least 20.
    noise : float
        Standard deviation of the smooth tremor, m.
    rng : numpy.random.Generator, optional
        Source of the tremor; None uses seed 0.

    Returns
    -------
    t : ndarray, shape (N,)
        s, from 0.
    positions : ndarray, shape (N, 3)
        m; at rest at both ends.
    orientations : ndarray, shape (N, 4)
        Identity quaternions ``(x, y, z, w)``.
    """
    return _demo(start, goal, None, 0.0, 0.0, None, duration, n_samples, noise, rng)


def avoidance_demo(
    start: ArrayLike,
    goal: ArrayLike,
    obstacle_centre: ArrayLike,
    obstacle_radius: float,
    clearance: float = 0.05,
    side: ArrayLike | None = None,
    duration: float = 2.0,
    n_samples: int = 400,
    noise: float = 5e-4,
    rng: np.random.Generator | None = None,
) -> tuple[Array, Array, Array]:
    """A demonstration that bends around a spherical obstacle.

    Parameters
    ----------
    start, goal : array_like, shape (3,)
        m.
    obstacle_centre : array_like, shape (3,)
        m.
    obstacle_radius : float
        m (> 0).
    clearance : float
        Distance kept from the obstacle's surface at the via-point, m (>= 0).
    side : array_like, shape (3,), optional
        Direction to pass on when the obstacle sits on the start-goal line; default world +z
        (over the top, as the paper's iCub did).
    duration, n_samples, noise, rng
        As :func:`straight_demo`; the tremor also jitters the via-point by ``noise``.

    Returns
    -------
    t, positions, orientations
        As :func:`straight_demo`.
    """
    return _demo(
        start,
        goal,
        obstacle_centre,
        positive(obstacle_radius, "obstacle_radius"),
        non_negative(clearance, "clearance"),
        side,
        duration,
        n_samples,
        noise,
        rng,
    )


def _demo(
    start: ArrayLike,
    goal: ArrayLike,
    centre: ArrayLike | None,
    radius: float,
    clearance: float,
    side: ArrayLike | None,
    duration: float,
    n_samples: int,
    noise: float,
    rng: np.random.Generator | None,
) -> tuple[Array, Array, Array]:
    y0 = vector(start, (3,), "start")
    g = vector(goal, (3,), "goal")
    length = float(np.linalg.norm(g - y0))
    if length < 1e-6:
        raise ValueError(f"goal: expected a goal away from the start, got {length:.3g} m apart")
    tau = positive(duration, "duration")
    noise = non_negative(noise, "noise")
    if int(n_samples) < 20:
        raise ValueError(f"n_samples: expected at least 20, got {n_samples!r}")
    n = int(n_samples)
    gen = rng if rng is not None else np.random.default_rng(0)
    t = np.linspace(0.0, tau, n)
    u = t / tau
    via = None
    u_via = 0.5
    if centre is not None:
        o = vector(centre, (3,), "obstacle_centre")
        axis = (g - y0) / length
        progress = float(np.clip((o - y0) @ axis / length, 0.1, 0.9))
        # When the straight min-jerk motion reaches the obstacle's projection.
        fine = np.linspace(0.0, 1.0, 2001)
        u_via = float(np.interp(progress, min_jerk(fine), fine))
        lateral = (y0 + progress * length * axis) - o
        lateral -= (lateral @ axis) * axis
        if np.linalg.norm(lateral) < 1e-6:
            lateral = np.array(unit_vector((0.0, 0.0, 1.0) if side is None else side, "side"))
            lateral -= (lateral @ axis) * axis
            if np.linalg.norm(lateral) < 1e-6:  # side along the line: any perpendicular
                lateral = np.cross(axis, np.eye(3)[int(np.argmin(np.abs(axis)))])
        via = o + (radius + clearance) * lateral / np.linalg.norm(lateral)
        via = via + gen.normal(0.0, noise, 3)
    positions = _min_jerk_through(y0, g, u, via, u_via)
    positions += tremor(n, 3, noise, max(n // 40, 1), gen)
    orientations = np.tile(np.array((0.0, 0.0, 0.0, 1.0)), (n, 1))
    return t, positions, orientations
