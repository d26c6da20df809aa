"""Distance queries a potential field asks (:mod:`skills.couplings.potential`): the protocol,
one with points of its own that move with the world (the arms' links), and spheres in closed
form, with the kernel the compiled step answers them with.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from skills.couplings._checks import assign, vector
from skills.kernel import kernel
from skills.types import Array

#: ``query(points (N, 3)) -> (distances (N,), closest_points (N, 3))``, world frame, m.
DistanceQuery = Callable[[Array], tuple[Array, Array]]


def _einsum_dot(a: Array, b: Array) -> Array:
    """Row-wise dot products of (N, 3) arrays, shape (N,)."""
    return np.einsum("nk,nk->n", a, b)


#: Row-wise dot products of (N, 3) arrays, shape (N,): numpy >= 2 has vecdot, a ufunc several
#: times cheaper than einsum on a few rows.
rows_dot: Callable[[Array, Array], Array] = getattr(np, "vecdot", _einsum_dot)


@runtime_checkable
class MovingPoints(Protocol):
    """A distance query that also names points of its own that move with the world.

    A field on such a query avoids with these points as well as its attached ones: the
    arms' links, which bend as the palms move. Before each closed-loop step the composition
    reads them again (in the world frame) and carries them with the object for that step; an
    open-loop prediction carries them from where they were when it started.
    """

    def __call__(self, points: Array) -> tuple[Array, Array]:
        """Distances and closest points, as :data:`DistanceQuery`."""
        ...

    def moving_points(self) -> Array:
        """The points now, (M, 3), world frame, m."""
        ...


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

    def packed(self) -> list[float]:
        """``[centre, radius]`` per sphere, for the kernel that answers this query itself."""
        return np.hstack((self.centres, self.radii[:, None])).ravel().tolist()

    def __call__(self, points: Array) -> tuple[Array, Array]:
        """Distances (N,) from ``points`` (N, 3) to the nearest sphere, and closest points."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        if self.radii.shape[0] == 0:
            return np.full(len(p), np.inf), np.full(p.shape, np.nan)
        if self.radii.shape[0] == 1:  # the usual case, in a third of the calls
            centre, radius = self.centres[0], self.radii[0]
            diff1 = p - centre
            norm1 = np.sqrt(rows_dot(diff1, diff1))
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


@kernel
def nearest_spheres_kernel(points: Array, data: Array, at: int, count: int) -> Array:
    """:meth:`SphereObstacles.__call__` on the ``count`` spheres ``[centre, radius]`` stored
    from ``data[at]``: per point, distance and closest point, (N, 4)."""
    n = points.shape[0]
    out = np.empty((n, 4))
    for i in range(n):
        best = np.inf
        bx = by = bz = br = bn = cx = cy = cz = 0.0
        for j in range(count):
            c = at + 4 * j
            dx = points[i, 0] - data[c]
            dy = points[i, 1] - data[c + 1]
            dz = points[i, 2] - data[c + 2]
            norm = math.sqrt(dx * dx + dy * dy + dz * dz)
            gap = norm - data[c + 3]
            if gap < best:
                best, bx, by, bz, br, bn = gap, dx, dy, dz, data[c + 3], norm
                cx, cy, cz = data[c], data[c + 1], data[c + 2]
        if count == 0:
            out[i, 0] = np.inf
            out[i, 1] = out[i, 2] = out[i, 3] = np.nan
            continue
        scale = br / max(bn, 1e-12)
        out[i, 0] = best
        out[i, 1] = cx + bx * scale
        out[i, 2] = cy + by * scale
        out[i, 3] = cz + bz * scale
    return out


__all__ = [
    "DistanceQuery",
    "MovingPoints",
    "SphereObstacles",
    "nearest_spheres_kernel",
    "rows_dot",
]
