"""Shared pieces of the synthetic teachers: minimum-jerk profiles and smooth tremor."""

from __future__ import annotations

import numpy as np

from skills.types import Array


def min_jerk(u: Array) -> Array:
    """Minimum-jerk profile from 0 to 1 over ``u`` in [0, 1] (rest at both ends)."""
    return u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)


def rest_window(u: Array) -> Array:
    """``(4 u (1 - u))^3``: 1 mid-way, 0 with zero slope and curvature at both ends."""
    return (4.0 * u * (1.0 - u)) ** 3


def tremor(n: int, dims: int, amplitude: float, smoothing: int, rng: np.random.Generator) -> Array:
    """Smooth random wobble ``(n, dims)`` of about ``amplitude`` std, zero at rest at both ends.

    Low-pass filtered white noise (a Gaussian of ``smoothing`` samples), so it has bounded
    accelerations like a hand's, faded out by :func:`rest_window`.
    """
    if amplitude == 0.0:
        return np.zeros((n, dims))
    # Here: skills.demos.io (a run reads its demonstrations) need not import scipy.ndimage.
    from scipy.ndimage import gaussian_filter1d

    raw = gaussian_filter1d(rng.standard_normal((n, dims)), smoothing, axis=0, mode="nearest")
    raw *= amplitude / max(float(np.std(raw)), 1e-12)
    return raw * rest_window(np.linspace(0.0, 1.0, n))[:, None]
