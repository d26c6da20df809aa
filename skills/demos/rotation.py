"""A synthetic human-like teacher turning an object about the world vertical axis."""

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
) -> tuple[Array, Array, Array]:
    """Turn by ``angle`` about world z with a minimum-jerk angle profile, at a fixed position.

    Parameters
    ----------
    angle : float
        Turn, rad (signed; non-zero).
    start_yaw : float
        Initial yaw about world z, rad.
    position : array_like, shape (3,)
        Where the object is held, m.
    duration : float
        s.
    n_samples : int
        At least 20.
    noise : float
        Standard deviation of a smooth wobble, rad, on yaw and on tilts about x and y; it
        fades out at both ends so the demonstration starts and ends at rest.
    rng : numpy.random.Generator, optional
        Source of the wobble; None uses seed 0.

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
    yaw = float(start_yaw) + a * min_jerk(t / tau) + wobble[:, 2]
    turn = quat.from_axis_angle(np.array((0.0, 0.0, 1.0)), yaw)
    tilt = quat.exp(0.5 * np.column_stack((wobble[:, 0], wobble[:, 1], np.zeros(n))))
    return t, np.tile(y, (n, 1)), quat.multiply(tilt, turn)
