"""How a learnt forcing term adapts to a new start and goal.

The forcing term is stored relative to a reference displacement ``g_ref - y0_ref`` (the first
demonstration's) and mapped to a new displacement ``g - y0`` by a matrix ``M`` with
``M(g_ref - y0_ref) = I``:

- ``AMPLITUDE``: ``M = diag((g - y0) / (g_ref - y0_ref))``, which is Ijspeert et al.'s
  ``s (g - y0)`` scaling written with the reference folded into the weights. A dimension whose
  reference displacement is below ``min_amplitude`` keeps its forcing unscaled, because the
  ratio is undefined there (a pick-and-place whose start and goal share a height still lifts).
- ``ROTATION_Z``: the first two dimensions are rotated and scaled so the reference horizontal
  displacement maps onto the new one; the others are unscaled. For motions on a horizontal
  surface, where "up" must stay up whatever the direction of travel.
- ``NONE``: ``M = I``; the forcing term is replayed as demonstrated.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np

from skills.types import Array


class Scaling(StrEnum):
    """Spatial scaling of the forcing term to new starts and goals."""

    NONE = "none"
    AMPLITUDE = "amplitude"
    ROTATION_Z = "rotation_z"


def scaling_matrix(
    mode: Scaling, displacement: Array, reference: Array, min_amplitude: float = 1e-3
) -> Array:
    """Matrix ``M`` mapping the reference forcing onto a new displacement.

    Parameters
    ----------
    mode : Scaling
    displacement : ndarray, shape (D,)
        New ``g - y0``.
    reference : ndarray, shape (D,)
        ``g_ref - y0_ref`` the weights were learnt for.
    min_amplitude : float
        Below this a reference displacement counts as zero.

    Returns
    -------
    ndarray, shape (D, D)
    """
    d = displacement.shape[0]
    if mode is Scaling.NONE:
        return np.eye(d)
    if mode is Scaling.AMPLITUDE:
        usable = np.abs(reference) >= min_amplitude
        ratio = np.where(usable, displacement / np.where(usable, reference, 1.0), 1.0)
        return np.diag(ratio)
    if mode is Scaling.ROTATION_Z:
        if d < 2:
            raise ValueError(f"scaling: rotation_z needs at least 2 dimensions, got {d}")
        m = np.eye(d)
        ref_norm = float(np.hypot(reference[0], reference[1]))
        if ref_norm < min_amplitude:
            return m
        # Complex division gives the rotation-and-scale taking ref_xy to new_xy.
        z = complex(displacement[0], displacement[1]) / complex(reference[0], reference[1])
        m[0, 0], m[0, 1] = z.real, -z.imag
        m[1, 0], m[1, 1] = z.imag, z.real
        return m
    raise ValueError(f"scaling: expected one of {[s.value for s in Scaling]}, got {mode!r}")
