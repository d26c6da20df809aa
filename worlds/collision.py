"""FCL collision geometry of a :class:`worlds.scene.Scene`, kept in step with PyBullet.

Every robot link (from ``getCollisionShapeData``: iiwa meshes as convex hulls, as PyBullet
collides them; boxes), the table, the objects and the obstacles become FCL collision objects,
each with a bounding sphere for a numpy prefilter. :meth:`CollisionWorld.sync` reads all link
poses (one ``getLinkStates`` call per robot body) and object poses.

Groups name sets of elements: ``"left_arm"``, ``"right_arm"`` (all links of the arm's body,
palm included; of a body that carries both arms, each arm's own links, the rest of the body
with the left arm: :func:`worlds.bodies.arm_link_indices`), ``"table"``, ``"obstacles"`` (the
active ones) and each object by its name. Element names are ``"left_arm/<link>"`` (the palm
link ``"left_arm/palm"``), ``"table"``, the object or obstacle name.

Poses in this module are (position (3,), quaternion (4,) scalar-last) pairs in the world frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import fcl
import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills.kernel import kernel
from skills.vocabulary import Arm
from worlds.collision_geometry import (
    FIXTURES,
    OBSTACLES,
    TABLE,
    arm_group,
    welded_links,
)
from worlds.posed_checks import PosedChecks, TrajectoryCheck

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@kernel
def _sphere_gaps(
    centres: FloatArray, radii: FloatArray, rows_a: IntArray, rows_b: IntArray
) -> FloatArray:
    """(A, B) gaps between the spheres ``rows_a`` and ``rows_b`` of ``centres`` (E, 3) and
    ``radii`` (E,): centre distance less both radii, m (a lower bound of the elements')."""
    gaps = np.empty((rows_a.size, rows_b.size))
    for i in range(rows_a.size):
        a = rows_a[i]
        for j in range(rows_b.size):
            b = rows_b[j]
            dx = centres[a, 0] - centres[b, 0]
            dy = centres[a, 1] - centres[b, 1]
            dz = centres[a, 2] - centres[b, 2]
            gaps[i, j] = math.sqrt(dx * dx + dy * dy + dz * dz) - radii[a] - radii[b]
    return gaps


@kernel
def _nearest_gap(
    centres: FloatArray, radii: FloatArray, rows_a: IntArray, rows_b: IntArray
) -> float:
    """The least of :func:`_sphere_gaps`, m."""
    return _sphere_gaps(centres, radii, rows_a, rows_b).min()


# ---------------------------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class Proximity:
    """Closest approach between two groups.

    Attributes
    ----------
    distance : float
        Minimum distance, m (negative when FCL reports penetration depth).
    point_a, point_b : ndarray
        (3,) closest points on the two groups, world frame, m.
    element_a, element_b : str
        Names of the two elements that are closest.
    """

    distance: float
    point_a: FloatArray
    point_b: FloatArray
    element_a: str
    element_b: str


@dataclass(frozen=True)
class LinkDistances:
    """Distance of each link of one arm to the nearest active obstacle.

    Attributes
    ----------
    links : tuple of str
        Element names, base to palm.
    distances : ndarray
        (L,) distances, m; ``inf`` when no obstacle is active.
    link_points, obstacle_points : ndarray
        (L, 3) closest points on the link and on the obstacle, world frame, m (nan if none).
    """

    links: tuple[str, ...]
    distances: FloatArray
    link_points: FloatArray
    obstacle_points: FloatArray


class CollisionWorld(PosedChecks):
    """FCL mirror of a scene's collision geometry (:mod:`worlds.collision_geometry`), its
    predicted poses checked (:mod:`worlds.posed_checks`), and the queries of the world as it
    stands: contacts, distances between groups and elements, distances of points.

    Parameters
    ----------
    scene : Scene
        The scene to mirror; obstacles follow ``scene.active_obstacles`` at each :meth:`sync`.
    """

    # -- queries -----------------------------------------------------------------------------

    def colliding_pairs(self, groups: Iterable[str] | None = None) -> list[tuple[str, str]]:
        """Element pairs in contact or penetration, between different groups.

        Parameters
        ----------
        groups : iterable of str, optional
            Only these groups; default all (inactive obstacles never count).

        Returns
        -------
        list of (str, str)
            Element name pairs, in element order.
        """
        wanted = set(groups) if groups is not None else set(self.group_names())
        self._place()
        active = set(self._active)
        rows = [
            i
            for i, e in enumerate(self._elements)
            if e.group in wanted and (e.group != OBSTACLES or i in active)
        ]
        centres = self._centres[rows]
        radii = self._radii[rows]
        gaps = np.linalg.norm(centres[:, None] - centres[None], axis=-1) - radii[:, None] - radii
        pairs = []
        for a, b in zip(*np.nonzero(np.triu(gaps <= 0.0, k=1)), strict=True):
            ea, eb = self._elements[rows[a]], self._elements[rows[b]]
            if ea.group == eb.group:
                continue
            objects = self._fcl(rows[a]), self._fcl(rows[b])
            if fcl.collide(*objects, fcl.CollisionRequest(), fcl.CollisionResult()):
                pairs.append((ea.name, eb.name))
        return pairs

    def distance(self, group_a: str, group_b: str) -> Proximity:
        """Minimum distance and closest points between two groups.

        Pairs are visited in order of their bounding-sphere lower bound and the search stops
        once that bound exceeds the best distance found.

        Raises
        ------
        ValueError
            If a group is unknown or empty (no active obstacles).
        """
        found = self.closer_than(group_a, group_b, math.inf)
        assert found is not None
        return found

    def closer_than(self, group_a: str, group_b: str, ceiling: float) -> Proximity | None:
        """:meth:`distance` if it is below ``ceiling`` m, else None.

        A watcher keeping the smallest distance seen asks with that distance: pairs whose
        bounding spheres are farther apart are never handed to FCL, so most control steps
        cost the bounds alone.

        Raises
        ------
        ValueError
            If a group is unknown or empty (no active obstacles).
        """
        rows_a, rows_b = self._rows(group_a), self._rows(group_b)
        if not rows_a or not rows_b:
            raise ValueError(
                f"CollisionWorld.distance: group {group_a if not rows_a else group_b!r} is empty"
            )
        return self._rows_closer_than(rows_a, rows_b, ceiling)

    def elements_distance(self, names: Sequence[str], group: str) -> Proximity:
        """:meth:`distance` from some elements, by name (a forearm's links), to a group.

        Raises
        ------
        ValueError
            If a name is unknown, or ``names`` or the group is empty.
        """
        found = self.elements_closer_than(names, group, math.inf)
        assert found is not None
        return found

    def elements_closer_than(
        self, names: Sequence[str], group: str, ceiling: float
    ) -> Proximity | None:
        """:meth:`elements_distance` if it is below ``ceiling`` m, else None
        (:meth:`closer_than`).

        Raises
        ------
        ValueError
            If a name is unknown, or ``names`` or the group is empty.
        """
        rows_a, rows_b = [self._index(name) for name in names], self._rows(group)
        if not rows_a or not rows_b:
            raise ValueError(
                "CollisionWorld.elements_distance: "
                + ("no elements given" if not rows_a else f"group {group!r} is empty")
            )
        return self._rows_closer_than(rows_a, rows_b, ceiling)

    def object_closer_than(self, name: str, ceiling: float) -> Proximity | None:
        """Task object ``name``'s closest active obstacle, if nearer than ``ceiling`` m
        (:meth:`closer_than`); None too with no obstacle active."""
        if not self._active:
            return None
        rows = self.avoided_rows([name])
        return self._rows_closer_than(rows, list(self._active), ceiling)

    def _rows_closer_than(
        self, rows_a: list[int], rows_b: list[int], ceiling: float
    ) -> Proximity | None:
        """The closest pair of elements ``rows_a`` x ``rows_b`` if nearer than ``ceiling``."""
        a_rows = np.asarray(rows_a, dtype=np.intp)
        b_rows = np.asarray(rows_b, dtype=np.intp)
        if self._read is not None and math.isfinite(ceiling):
            # Not placed since the last sync: screen on the positions read first.
            if _nearest_gap(self._origins(), self._reach, a_rows, b_rows) >= ceiling:
                return None
        self._place()
        bounds = _sphere_gaps(self._centres, self._radii, a_rows, b_rows)
        best: Proximity | None = None
        for flat in np.argsort(bounds, axis=None):
            a, b = np.unravel_index(flat, bounds.shape)
            if bounds[a, b] > (ceiling if best is None else min(best.distance, ceiling)):
                break
            found = self._pair_distance(rows_a[a], rows_b[b])
            if best is None or found.distance < best.distance:
                best = found
        if best is None or best.distance >= ceiling:
            return None
        return best

    def _pair_distance(self, row_a: int, row_b: int) -> Proximity:
        ea, eb = self._elements[row_a], self._elements[row_b]
        result = fcl.DistanceResult()
        d = fcl.distance(self._fcl(row_a), self._fcl(row_b), self._request, result)
        return Proximity(
            float(d),
            np.asarray(result.nearest_points[0], dtype=float),
            np.asarray(result.nearest_points[1], dtype=float),
            ea.name,
            eb.name,
        )

    def link_distances(self, arm: Arm) -> LinkDistances:
        """Distance of every link of ``arm`` to the nearest active obstacle (for avoidance)."""
        rows = self._rows(arm_group(arm))
        self._place()
        n = len(rows)
        distances = np.full(n, np.inf)
        link_points = np.full((n, 3), np.nan)
        obstacle_points = np.full((n, 3), np.nan)
        for k, row in enumerate(rows):
            for obstacle in self._active:
                found = self._pair_distance(row, obstacle)
                if found.distance < distances[k]:
                    distances[k] = found.distance
                    link_points[k] = found.point_a
                    obstacle_points[k] = found.point_b
        return LinkDistances(
            tuple(self._elements[r].name for r in rows), distances, link_points, obstacle_points
        )

    def query(self, points: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Distance from points to the nearest active obstacle.

        Spheres and boxes are solved in closed form (signed: negative inside); other shapes go
        through FCL (0 inside).

        Parameters
        ----------
        points : array_like
            (N, 3) query points, world frame, m.

        Returns
        -------
        distances : ndarray
            (N,) distance to the nearest active obstacle, m; ``inf`` with none active.
        closest_points : ndarray
            (N, 3) closest point on that obstacle's surface, world frame, m (nan with none).
        """
        p = np.asarray(points, dtype=float)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(
                f"CollisionWorld.query: expected points of shape (N, 3), got {p.shape}"
            )
        distances = np.full(len(p), np.inf)
        closest = np.full((len(p), 3), np.nan)
        for row in self._active:
            d, c = self._point_distance(row, p)
            better = d < distances
            distances[better] = d[better]
            closest[better] = c[better]
        return distances, closest

    def _point_distance(self, row: int, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        element = self._elements[row]
        self._place()
        obj = self._fcl(row)
        transform = obj.getTransform()
        rotation, origin = (
            np.asarray(transform.getRotation()),
            np.asarray(transform.getTranslation()),
        )
        geometry = element.geometry
        if isinstance(geometry, fcl.Sphere):
            offset = points - origin
            norm = np.linalg.norm(offset, axis=1)
            direction = offset / np.where(norm > 1e-12, norm, 1.0)[:, None]
            direction[norm <= 1e-12] = (0.0, 0.0, 1.0)
            return norm - geometry.radius, origin + geometry.radius * direction
        if isinstance(geometry, fcl.Box):
            half = 0.5 * np.asarray(geometry.side, dtype=float)
            local = (points - origin) @ rotation
            clamped = np.clip(local, -half, half)
            outside = np.linalg.norm(local - clamped, axis=1)
            inside_gap = np.min(half - np.abs(local), axis=1)
            inside = outside == 0.0
            if np.any(inside):
                # Project inside points onto the nearest face.
                axis = np.argmin(half - np.abs(local[inside]), axis=1)
                face = clamped[inside]
                face[np.arange(len(axis)), axis] = np.copysign(
                    half[axis], local[inside][np.arange(len(axis)), axis]
                )
                clamped[inside] = face
            distances = np.where(inside, -inside_gap, outside)
            return distances, clamped @ rotation.T + origin
        probe = fcl.CollisionObject(fcl.Sphere(1e-6), fcl.Transform())
        distances = np.empty(len(points))
        closest = np.empty((len(points), 3))
        for k, point in enumerate(points):
            probe.setTransform(fcl.Transform(point))
            result = fcl.DistanceResult()
            distances[k] = max(fcl.distance(probe, obj, self._request, result), 0.0)
            closest[k] = result.nearest_points[1]
        return distances, closest


__all__ = [
    "FIXTURES",
    "OBSTACLES",
    "TABLE",
    "CollisionWorld",
    "LinkDistances",
    "Proximity",
    "TrajectoryCheck",
    "arm_group",
    "welded_links",
]
