"""Demonstrations: time-stamped samples of a position and, optionally, an orientation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skills import quaternion as quat
from skills.types import Array

#: Second-order finite differences need at least three samples.
MIN_SAMPLES = 3
#: How far a recorded quaternion's norm may be from 1 (rounding in a CSV export): more is
#: not a unit quaternion (a scaled one, or angles written into its fields), refused.
UNIT_NORM_TOLERANCE = 0.01


@dataclass(frozen=True)
class Demonstration:
    """One demonstration, validated.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Strictly increasing time stamps, s.
    positions : ndarray, shape (N, D)
        Positions, m (or any unit for a generic DMP).
    orientations : ndarray, shape (N, 4) or None
        Unit quaternions ``(x, y, z, w)``, made sign-continuous.
    name : str
        Where it came from, for provenance and error messages.
    """

    t: Array
    positions: Array
    orientations: Array | None = None
    name: str = "demo"

    @staticmethod
    def create(
        t: ArrayLike,
        positions: ArrayLike,
        orientations: ArrayLike | None = None,
        name: str = "demo",
    ) -> Demonstration:
        """Validate and build a demonstration.

        Raises
        ------
        ValueError
            On mismatched lengths, non-increasing time, NaN or inf, quaternions whose norm
            is not 1 (within :data:`UNIT_NORM_TOLERANCE`) or fewer than three samples. The
            message names the argument.
        """
        t_arr = np.asarray(t, dtype=float)
        if t_arr.ndim != 1:
            raise ValueError(
                f"{name}: t: expected a 1-D array of time stamps, got shape {t_arr.shape}"
            )
        n = t_arr.shape[0]
        if n < MIN_SAMPLES:
            raise ValueError(
                f"{name}: t: expected at least {MIN_SAMPLES} samples for velocities and "
                f"accelerations, got {n}"
            )
        if not np.all(np.isfinite(t_arr)):
            i = int(np.flatnonzero(~np.isfinite(t_arr))[0])
            raise ValueError(f"{name}: t: expected finite time stamps, got t[{i}]={t_arr[i]}")
        dt = np.diff(t_arr)
        if np.any(dt <= 0.0):
            i = int(np.flatnonzero(dt <= 0.0)[0]) + 1
            raise ValueError(
                f"{name}: t: expected times strictly increasing, "
                f"got t[{i}]={t_arr[i]} <= t[{i - 1}]={t_arr[i - 1]}"
            )
        y = np.asarray(positions, dtype=float)
        if y.ndim == 1:
            y = y[:, None]
        if y.ndim != 2 or y.shape[0] != n:
            raise ValueError(
                f"{name}: positions: expected shape ({n}, D) to match t, got {np.shape(positions)}"
            )
        if not np.all(np.isfinite(y)):
            i, j = (int(k) for k in np.argwhere(~np.isfinite(y))[0])
            axis = "xyz"[j] if y.shape[1] <= 3 else f"dimension {j}"
            raise ValueError(
                f"{name}: positions: expected finite values, got {y[i, j]} at [{i}, {j}] "
                f"(sample {i}, {axis})"
            )
        q: Array | None = None
        if orientations is not None:
            q_raw = np.asarray(orientations, dtype=float)
            if q_raw.ndim != 2 or q_raw.shape != (n, 4):
                raise ValueError(
                    f"{name}: orientations: expected shape ({n}, 4) scalar-last (x, y, z, w) "
                    f"to match t, got {q_raw.shape}"
                )
            if not np.all(np.isfinite(q_raw)):
                i, j = (int(k) for k in np.argwhere(~np.isfinite(q_raw))[0])
                raise ValueError(
                    f"{name}: orientations: expected finite values, got {q_raw[i, j]} at "
                    f"[{i}, {j}] (sample {i}, {'xyzw'[j]})"
                )
            norms = np.linalg.norm(q_raw, axis=1)
            off = np.abs(norms - 1.0) > UNIT_NORM_TOLERANCE
            if np.any(off):
                i = int(np.flatnonzero(off)[0])
                raise ValueError(
                    f"{name}: orientations: expected unit quaternions (norm 1 within "
                    f"{UNIT_NORM_TOLERANCE:g}), got norm {norms[i]:.4g} at sample {i} "
                    f"({int(off.sum())} of {n} samples off): scalar-last (x, y, z, w), not "
                    "angles"
                )
            q = quat.make_continuous(quat.as_quaternions(q_raw, f"{name}: orientations"))
        return Demonstration(t=t_arr, positions=y, orientations=q, name=name)

    @property
    def n_samples(self) -> int:
        """Number of samples ``N``."""
        return int(self.t.shape[0])

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]``, s."""
        return float(self.t[-1] - self.t[0])

    def position_derivatives(self) -> tuple[Array, Array]:
        """Velocity and acceleration ``(N, D)`` by second-order finite differences."""
        yd = np.gradient(self.positions, self.t, axis=0, edge_order=2)
        ydd = np.gradient(yd, self.t, axis=0, edge_order=2)
        return yd, ydd

    def orientation_derivatives(self) -> tuple[Array, Array]:
        """World-frame angular velocity and acceleration ``(N, 3)``, rad/s and rad/s^2."""
        if self.orientations is None:
            raise ValueError(
                f"{self.name}: orientations: expected a demonstration with orientations"
            )
        omega = quat.angular_velocity(self.orientations, self.t)
        omegad = np.gradient(omega, self.t, axis=0, edge_order=2)
        return omega, omegad
