"""A synthetic human-like teacher that moves around a spherical obstacle.

The teacher does not use the steering law it will be fitted with: its path is the discrete
minimum-jerk motion (least summed squared third differences) from rest at the start to rest at
the goal that passes through a via-point beside the obstacle, at the obstacle's radius plus a
clearance, placed perpendicular to the start-goal line where the straight motion would have
reached the obstacle (Flash and Hogan's via-point model of human reaching). A seeded,
smooth tremor that fades out at both ends makes it look recorded.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import linalg

from skills.couplings._checks import non_negative, positive, unit_vector, vector
from skills.demos._smooth import min_jerk, tremor
from skills.types import Array

#: Rest at each end: the first and last three samples coincide (zero velocity and acceleration).
_REST = 3


def _min_jerk_through(
    start: Array, goal: Array, n: int, via: Array | None, via_index: int
) -> Array:
    """Discrete minimum-jerk positions (n, 3) from rest to rest, optionally through ``via``."""
    jerk = np.diff(np.eye(n), 3, axis=0)  # (n - 3, n) third differences
    rows = [*range(_REST), *range(n - _REST, n)]
    values = [start] * _REST + [goal] * _REST
    if via is not None:
        rows.append(via_index)
        values.append(via)
    a = np.zeros((len(rows), n))
    a[np.arange(len(rows)), rows] = 1.0
    kkt = np.block([[jerk.T @ jerk, a.T], [a, np.zeros((len(rows), len(rows)))]])
    rhs = np.vstack((np.zeros((n, 3)), np.array(values)))
    return linalg.solve(kkt, rhs, assume_a="sym")[:n]


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
    via = None
    via_index = 0
    if centre is not None:
        o = vector(centre, (3,), "obstacle_centre")
        axis = (g - y0) / length
        progress = float(np.clip((o - y0) @ axis / length, 0.1, 0.9))
        # The straight min-jerk motion reaches the obstacle's projection at this sample.
        via_index = int(np.searchsorted(min_jerk(np.linspace(0.0, 1.0, n)), progress))
        via_index = int(np.clip(via_index, _REST + 1, n - _REST - 2))
        lateral = (y0 + progress * length * axis) - o
        lateral -= (lateral @ axis) * axis
        if np.linalg.norm(lateral) < 1e-6:
            lateral = np.array(unit_vector((0.0, 0.0, 1.0) if side is None else side, "side"))
            lateral -= (lateral @ axis) * axis
            if np.linalg.norm(lateral) < 1e-6:  # side along the line: any perpendicular
                lateral = np.cross(axis, np.eye(3)[int(np.argmin(np.abs(axis)))])
        via = o + (radius + clearance) * lateral / np.linalg.norm(lateral)
        via = via + gen.normal(0.0, noise, 3)
    positions = _min_jerk_through(y0, g, n, via, via_index)
    positions += tremor(n, 3, noise, max(n // 40, 1), gen)
    orientations = np.tile(np.array((0.0, 0.0, 0.0, 1.0)), (n, 1))
    return t, positions, orientations
