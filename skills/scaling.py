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

``AMPLITUDE``'s ratio has no bound as a reference displacement goes to nothing: a lift whose
start and goal heights differ by 1.1 mm, sent to a goal 5 cm higher, scales its 10 cm lift by
45 (a 4.6 m arc). :func:`shape_floor` gives the ``min_amplitude`` that keeps such an axis,
whose start-to-goal change is small beside its excursion, unscaled: it carries the motion's
shape, not its displacement.
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


#: An axis whose start-to-goal change is under this share of its excursion in the
#: demonstration carries a shape (a lift, a wave), not a displacement (:func:`shape_floor`).
SHAPE_SHARE = 0.2


def shape_floor(
    path: Array, reference: Array, floor: float, share: float = SHAPE_SHARE
) -> tuple[float, list[int]]:
    """``min_amplitude`` for ``AMPLITUDE`` scaling that leaves a demonstration's shaped axes
    unscaled, and those axes.

    An axis is shaped where its reference change ``|reference[i]|``, at least ``floor``, is
    under ``share`` of its excursion along ``path`` (its samples' range): scaled by a new
    move's change over that small one, its shape would grow without bound. The threshold is
    just above the largest such change, so every shaped axis (and any axis of a smaller
    change) replays its forcing as demonstrated.

    Parameters
    ----------
    path : ndarray, shape (N, D)
        The demonstration's samples (positions, or rotation vectors from its start).
    reference : ndarray, shape (D,)
        Its start-to-goal change.
    floor : float
        The threshold without shaped axes.
    share : float
        :data:`SHAPE_SHARE` by default.
    """
    change = np.abs(np.asarray(reference, dtype=float))
    excursion = np.ptp(np.asarray(path, dtype=float), axis=0)
    shaped = [int(i) for i in np.flatnonzero((change >= floor) & (change < share * excursion))]
    if not shaped:
        return floor, []
    return float(np.nextafter(change[shaped].max(), np.inf)), shaped


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
