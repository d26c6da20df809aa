"""A synthetic human-like teacher turning an object about a world axis (the vertical, or the
horizontal axis through two palms holding it)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.couplings._checks import non_negative, positive, vector
from skills.demos._smooth import min_jerk, tremor
from skills.types import Array


def rotation_demo(
    angle: float = np.pi / 2,
    start_yaw: float = 0.0,
    position: ArrayLike = (0.5, 0.0, 0.8),
    duration: float = 2.0,
    n_samples: int = 400,
    noise: float = 0.005,
    rng: np.random.Generator | None = None,
    axis: int = 2,
) -> tuple[Array, Array, Array]:
    """Turn by ``angle`` about world axis ``axis`` with a minimum-jerk angle profile, at a
    fixed position.

    Parameters
    ----------
    angle : float
        Turn, rad (signed; non-zero).
    start_yaw : float
        Initial angle about the turn's axis, rad.
    position : array_like, shape (3,)
        Where the object is held, m.
    duration : float
        s.
    n_samples : int
        At least 20.
    noise : float
        Standard deviation of a smooth wobble, rad, on the turn and on tilts about the two
        other axes; it fades out at both ends so the demonstration starts and ends at rest.
    rng : numpy.random.Generator, optional
        Source of the wobble; None uses seed 0.
    axis : int
        The world axis turned about: 0 (x), 1 (y: a box held on its y faces at yaw 0 turns
        about the palms' axis) or 2 (z, the vertical).

    Returns
    -------
    t : ndarray, shape (N,)
        s, from 0.
    positions : ndarray, shape (N, 3)
        Constant, m.
    orientations : ndarray, shape (N, 4)
        Unit quaternions ``(x, y, z, w)``, world frame.
    """
    a = float(angle)
    if not (np.isfinite(a) and a != 0.0):
        raise ValueError(f"angle: expected a finite non-zero turn in rad, got {angle!r}")
    y = vector(position, (3,), "position")
    tau = positive(duration, "duration")
    sigma = non_negative(noise, "noise")
    if int(n_samples) < 20:
        raise ValueError(f"n_samples: expected at least 20, got {n_samples!r}")
    n = int(n_samples)
    gen = rng if rng is not None else np.random.default_rng(0)
    t = np.linspace(0.0, tau, n)
    wobble = tremor(n, 3, sigma, max(n // 40, 1), gen)
    if axis not in (0, 1, 2):
        raise ValueError(f"axis: expected 0, 1 or 2 (world x, y, z), got {axis!r}")
    angle_t = float(start_yaw) + a * min_jerk(t / tau) + wobble[:, axis]
    turn = quat.from_axis_angle(np.eye(3)[axis], angle_t)
    # The wobble on the two other axes tilts the turning object a little.
    tilts = wobble.copy()
    tilts[:, axis] = 0.0
    tilt = quat.exp(0.5 * tilts)
    return t, np.tile(y, (n, 1)), quat.multiply(tilt, turn)
