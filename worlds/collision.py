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
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from skills.kernel import kernel, matrix_q, quaternion_at
from skills.types import Array
from skills.vocabulary import Arm
from worlds.fcl_shapes import pybullet_geometry, shape_geometry
from worlds.fixture_spec import WALL_NAMES
from worlds.scene import Scene
from worlds.spec import ShapeSpec

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

TABLE = "table"
OBSTACLES = "obstacles"
#: Group of the fixtures' walls (always present; ``"<fixture>/<wall>"`` elements).
FIXTURES = "fixtures"


def arm_group(arm: Arm) -> str:
    """Group name of an arm's links: ``"left_arm"`` or ``"right_arm"``."""
    return f"{Arm(arm).value}_arm"


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
# Geometry helpers


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


@dataclass(frozen=True)
class TrajectoryCheck:
    """Result of checking predicted palm (and held-object) poses against the obstacles.

    Attributes
    ----------
    collides : ndarray
        (N,) True where some palm or the held object is within ``margin`` of an obstacle.
    first_collision : int
        Index of the first such waypoint, -1 if none.
    """

    collides: NDArray[np.bool_]
    first_collision: int

    @property
    def collision_free(self) -> bool:
        """No waypoint collides."""
        return self.first_collision < 0


# ---------------------------------------------------------------------------------------------
# The collision world


@dataclass
class _Element:
    name: str
    group: str
    obj: fcl.CollisionObject
    geometry: fcl.CollisionGeometry
    centre_local: FloatArray  # (3,) bounding-sphere centre in the shape frame
    radius: float


#: Per robot body: its id, its elements' link indices (-1 the base), its moving links, the
#: elements' rows, and their shape frames in their links (positions (L, 3), rotations (L, 3, 3)).
_LinkTrack = tuple[int, list[int], list[int], list[int], FloatArray, Array]


@kernel
def _moving_poses(
    frame_p: FloatArray,
    frame_q: FloatArray,
    local_p: FloatArray,
    local_r: FloatArray,
    centre_local: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Moving elements' world poses (links, objects) from their frames, read: positions (K, 3),
    rotations (K, 3, 3) and bounding-sphere centres (K, 3), for frames at ``frame_p`` (K, 3)
    turned by ``frame_q`` (K, 4) and shapes at ``local_p`` (K, 3), ``local_r`` (K, 3, 3) in
    them, sphere centres at ``centre_local`` (K, 3) in the shapes."""
    k = frame_p.shape[0]
    positions = np.empty((k, 3))
    rotations = np.empty((k, 3, 3))
    centres = np.empty((k, 3))
    for e in range(k):
        m = matrix_q(quaternion_at(frame_q[e], 0))
        for i in range(3):
            positions[e, i] = (
                m[3 * i] * local_p[e, 0]
                + m[3 * i + 1] * local_p[e, 1]
                + m[3 * i + 2] * local_p[e, 2]
            ) + frame_p[e, i]
            for j in range(3):
                rotations[e, i, j] = (
                    m[3 * i] * local_r[e, 0, j]
                    + m[3 * i + 1] * local_r[e, 1, j]
                    + m[3 * i + 2] * local_r[e, 2, j]
                )
        for i in range(3):
            centres[e, i] = (
                rotations[e, i, 0] * centre_local[e, 0]
                + rotations[e, i, 1] * centre_local[e, 1]
                + rotations[e, i, 2] * centre_local[e, 2]
            ) + positions[e, i]
    return positions, rotations, centres


class CollisionWorld:
    """FCL mirror of a scene's collision geometry.

    Parameters
    ----------
    scene : Scene
        The scene to mirror; obstacles follow ``scene.active_obstacles`` at each :meth:`sync`.
    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        c = scene.client
        self._elements: list[_Element] = []
        self._rows_by_name: dict[str, int] = {}
        # Robot links, per body (_LinkTrack).
        self._link_tracks: list[_LinkTrack] = []
        # What the last sync read from PyBullet, made into element poses at the first query.
        # (frame positions, frame quaternions) as flat lists: per link track, its moving links'
        # then its base's, then each task object's (see _pick and _moving_rows).
        self._read: tuple[list[Any], list[Any]] | None = None
        # Each arm's link names, by link index (as its elements are named).
        self._link_names: dict[Arm, dict[int, str]] = {}
        for arm in (Arm.LEFT, Arm.RIGHT):
            spec = scene.robot.arms[arm]
            body = scene.robot_ids[spec.body]
            group = arm_group(arm)
            links: list[int] = []
            rows: list[int] = []
            local_p: list[FloatArray] = []
            local_q: list[FloatArray] = []
            own = scene.arm_links[arm]  # None: the whole body is the arm's
            for link in range(-1, pb.getNumJoints(body, physicsClientId=c)):
                if own is not None and link not in own:
                    continue
                if link < 0:
                    link_name = "base"
                elif link == spec.palm_link:
                    link_name = "palm"  # whatever the URDF calls it
                else:
                    link_name = pb.getJointInfo(body, link, physicsClientId=c)[12].decode()
                self._link_names.setdefault(arm, {})[link] = link_name
                shapes = pb.getCollisionShapeData(body, link, physicsClientId=c)
                for k, data in enumerate(shapes):
                    geometry, centre, radius = pybullet_geometry(data)
                    suffix = f"#{k}" if len(shapes) > 1 else ""
                    rows.append(len(self._elements))
                    links.append(link)
                    local_p.append(np.asarray(data[5], dtype=float))
                    local_q.append(np.asarray(data[6], dtype=float))
                    self._add(f"{group}/{link_name}{suffix}", group, geometry, centre, radius)
            moving = [link for link in links if link >= 0]
            local_r = quat.to_matrix(np.array(local_q))  # constant: converted once
            self._link_tracks.append((body, links, moving, rows, np.array(local_p), local_r))

        table = scene.spec.table
        geometry, centre, radius = shape_geometry(ShapeSpec.box(table.size))
        self._add(TABLE, TABLE, geometry, centre, radius)
        fixed = [
            (
                len(self._elements) - 1,
                np.array(
                    [table.position[0], table.position[1], table.position[2] - table.size[2] / 2]
                ),
            )
        ]
        self._objects: dict[str, int] = {}
        for obj in scene.spec.objects:
            geometry, centre, radius = shape_geometry(obj.shape)
            self._objects[obj.name] = len(self._elements)
            self._add(obj.name, obj.name, geometry, centre, radius)
        self._obstacles: dict[str, int] = {}
        for obstacle in scene.spec.obstacles:
            geometry, centre, radius = shape_geometry(obstacle.shape)
            self._obstacles[obstacle.name] = len(self._elements)
            self._add(obstacle.name, OBSTACLES, geometry, centre, radius)
            fixed.append((len(self._elements) - 1, np.asarray(obstacle.position, float)))
        turned: list[tuple[int, FloatArray, FloatArray]] = []
        for fixture in scene.spec.fixtures:
            rotation = np.asarray(
                quat.to_matrix(np.asarray(fixture.quaternion, dtype=float)), dtype=np.float64
            )
            for (centre, half), wall in zip(
                zip(*fixture.walls(), strict=True), WALL_NAMES, strict=True
            ):
                geometry, local, radius = shape_geometry(ShapeSpec.box(2.0 * half))
                self._add(f"{fixture.name}/{wall}", FIXTURES, geometry, local, radius)
                position = np.asarray(fixture.position, float) + rotation @ centre
                turned.append((len(self._elements) - 1, position, rotation))
        # Every element's pose, world frame, as the last sync read it: the bounding spheres'
        # centres (E, 3) at once, for the screens; each FCL transform is set from the rotation
        # (E, 3, 3) and position (E, 3) when a query first needs it (``_stale``).
        count = len(self._elements)
        self._radii = np.array([e.radius for e in self._elements])
        self._centres_local = np.array([e.centre_local for e in self._elements])
        # How far each element reaches from its frame's origin (a link's, an object's centre;
        # the bounding-sphere centre of a static element): a screen that needs only the
        # positions a sync read, not the rotations (see _reach_bounds).
        self._reach = self._radii.copy()
        self._origins_read: object = None  # the sync read _origins_cache was made from
        self._origins_cache = np.zeros((len(self._elements), 3))
        for _, _, _, rows, shape_p, shape_r in self._link_tracks:
            centres_in_link = shape_p + (shape_r @ self._centres_local[rows][:, :, None])[:, :, 0]
            self._reach[rows] += np.linalg.norm(centres_in_link, axis=-1)
        for row in self._objects.values():
            self._reach[row] += float(np.linalg.norm(self._centres_local[row]))
        # The elements a sync moves (links, then objects): their rows, their frames' places in
        # a sync's flat read, and their shapes' poses in their frames.
        pick: list[int] = []
        moving_rows: list[int] = []
        in_frame_p: list[FloatArray] = []
        in_frame_r: list[Array] = []
        read = 0
        for _, links, moving, rows, track_p, track_r in self._link_tracks:
            ordinal = iter(range(read, read + len(moving)))
            pick += [next(ordinal) if link >= 0 else read + len(moving) for link in links]
            moving_rows += rows
            in_frame_p += list(track_p)
            in_frame_r += list(track_r)
            read += len(moving) + 1
        for row in self._objects.values():
            pick.append(read)
            moving_rows.append(row)
            in_frame_p.append(np.zeros(3))
            in_frame_r.append(np.eye(3))
            read += 1
        self._pick = np.array(pick, dtype=np.intp)
        self._moving_rows = np.array(moving_rows, dtype=np.intp)
        self._moving_in_frame_p = np.array(in_frame_p).reshape(-1, 3)
        self._moving_in_frame_r = np.array(in_frame_r, dtype=np.float64).reshape(-1, 3, 3)
        self._moving_centres = self._centres_local[self._moving_rows]
        self._centres = self._centres_local.copy()
        self._rotations = np.tile(np.eye(3), (count, 1, 1))
        self._positions = np.zeros((count, 3))
        self._stale = np.zeros(count, dtype=bool)
        for row, position in fixed:
            self._set_poses(np.array([row]), position[None], np.eye(3)[None])
        for row, position, rotation in turned:
            self._set_poses(np.array([row]), position[None], rotation[None])
        self._palm_rows = {
            arm: self._index(f"{arm_group(arm)}/palm") for arm in (Arm.LEFT, Arm.RIGHT)
        }
        self._request = fcl.DistanceRequest(enable_nearest_points=True, enable_signed_distance=True)
        # Each group's rows in element order (fixed once built; the obstacles' follow _active).
        self._group_rows: dict[str, tuple[int, ...]] = {}
        for i, element in enumerate(self._elements):
            if element.group != OBSTACLES:
                self._group_rows[element.group] = (*self._group_rows.get(element.group, ()), i)
        self.sync()

    # -- building ----------------------------------------------------------------------------

    def _add(
        self,
        name: str,
        group: str,
        geometry: fcl.CollisionGeometry,
        centre: FloatArray,
        radius: float,
    ) -> None:
        obj = fcl.CollisionObject(geometry, fcl.Transform())
        self._rows_by_name.setdefault(name, len(self._elements))
        self._elements.append(_Element(name, group, obj, geometry, centre, radius))

    def _index(self, name: str) -> int:
        # The watcher looks the forearms' elements up every control step: by a mapping.
        try:
            return self._rows_by_name[name]
        except KeyError:
            raise ValueError(f"CollisionWorld: expected an element named {name!r}") from None

    def _set_poses(
        self,
        rows: IntArray,
        positions: FloatArray,
        rotations: Array,
        centres: FloatArray | None = None,
    ) -> None:
        """Pose elements ``rows`` (K,): positions (K, 3) and rotations (K, 3, 3), world frame;
        their bounding spheres' centres (K, 3) computed here unless given."""
        # The FCL transforms wait for the first query of each element (see _fcl): most syncs
        # are followed by a few pair queries, or none, not by one of every element.
        self._rotations[rows] = rotations
        self._positions[rows] = positions
        self._stale[rows] = True
        if centres is None:
            centres = (rotations @ self._centres_local[rows][:, :, None])[:, :, 0] + positions
        self._centres[rows] = centres

    def _fcl(self, row: int) -> fcl.CollisionObject:
        """The FCL object of element ``row``, at its pose of the last sync."""
        element = self._elements[row]
        if self._stale[row]:
            element.obj.setTransform(fcl.Transform(self._rotations[row], self._positions[row]))
            self._stale[row] = False
        return element.obj

    def _place(self) -> None:
        """Pose the elements as the last :meth:`sync` read them (once, at the first query)."""
        if self._read is None:
            return
        positions_read, quaternions_read = self._read
        self._read = None
        poses = _moving_poses(
            np.array(positions_read)[self._pick],
            np.array(quaternions_read)[self._pick],
            self._moving_in_frame_p,
            self._moving_in_frame_r,
            self._moving_centres,
        )
        self._set_poses(self._moving_rows, *poses)

    def _origins(self) -> FloatArray:
        """Per element, (E, 3): its frame's origin as the last sync read it (links, objects)
        or its bounding-sphere centre (static elements); each element lies within
        ``_reach`` of it. Reads positions alone, before :meth:`_place`."""
        assert self._read is not None
        if self._origins_read is self._read:
            return self._origins_cache  # the watcher asks for several groups per sync
        origins = self._centres.copy()  # static elements' are right already
        origins[self._moving_rows] = np.array(self._read[0])[self._pick]
        self._origins_read, self._origins_cache = self._read, origins
        return origins

    @property
    def element_names(self) -> tuple[str, ...]:
        """Names of all elements, robot links first."""
        return tuple(e.name for e in self._elements)

    def group_names(self) -> tuple[str, ...]:
        """Names of all groups."""
        return tuple(dict.fromkeys(e.group for e in self._elements))

    def check_attached_links(
        self,
        palm_positions: ArrayLike,
        palm_quaternions: ArrayLike,
        distal_links: int = 4,
        margin: float | ArrayLike = 0.0,
    ) -> NDArray[np.bool_]:
        """Check each arm's last ``distal_links`` links carried along predicted palm poses.

        Without inverse kinematics for every waypoint, the forearm and wrist are taken to move
        rigidly with the palm: each starts where it is now (after :meth:`sync`) and follows the
        palm's predicted motion from the first waypoint. Over one carry that holds for the
        links nearest the palm, the ones that hit obstacles beside the object; a
        bounding-sphere test screens before FCL.

        Parameters
        ----------
        palm_positions : array_like
            (N, 2, 3) left and right palm positions, world frame, m.
        palm_quaternions : array_like
            (N, 2, 4) left and right palm orientations, scalar-last.
        distal_links : int
            How many links before the palm to carry (the iiwa's forearm and wrist are 4).
        margin : float or array_like
            Clearance below which a waypoint counts as colliding, m: one for all, or (N,) one
            per waypoint.

        Returns
        -------
        ndarray
            (N,) True where a carried link is within ``margin`` of an active obstacle, or, for
            a link that starts nearer than ``margin``, nearer than it starts (see
            :func:`_start_allowance`).
        """
        positions = np.asarray(palm_positions, dtype=float)
        quaternions = np.asarray(palm_quaternions, dtype=float)
        n = positions.shape[0]
        collides = np.zeros(n, dtype=bool)
        if not self._active or n == 0:
            return collides
        margins = np.broadcast_to(np.asarray(margin, dtype=float), (n,))
        self._place()
        palm_r = quat.to_matrix(quaternions)  # (N, 2, 3, 3)
        for a, arm in enumerate((Arm.LEFT, Arm.RIGHT)):
            rows = self._rows(arm_group(arm))
            # The palm's predicted motion from the first waypoint, start2waypoint (N, 3, 3):
            # links move with it from where they are now. (Placing them by the palm's pose now
            # would shift them by the gap between the palm and its first command, which a
            # squeezing or slipped grip makes centimetres.)
            start2waypoint = palm_r[:, a] @ palm_r[0, a].T
            links = [r for r in rows if r != self._palm_rows[arm]][-distal_links:]
            for row in links:
                link = self._fcl(row)
                offset = np.asarray(link.getTranslation(), dtype=float) - positions[0, a]
                rot = start2waypoint @ np.asarray(link.getRotation(), dtype=float)
                pos = start2waypoint @ offset + positions[:, a]
                self._check_posed(row, rot, pos, margins, collides)
        return collides

    def _check_posed(
        self,
        row: int,
        rotations: FloatArray,
        positions: FloatArray,
        margins: FloatArray,
        collides: NDArray[np.bool_],
        avoided: Sequence[int] = (),
        avoid_margin: float = 0.0,
        obstacles: bool = True,
    ) -> None:
        """Mark in ``collides`` (N,) the waypoints where element ``row``, posed at ``rotations``
        (N, 3, 3) and ``positions`` (N, 3), comes within ``margins`` (N,) of an active
        obstacle (unless not ``obstacles``), or nearer than it starts
        (:func:`_start_allowance`), or within ``avoid_margin`` of an object in ``avoided``
        (rows) that it does not touch at the start (:func:`_object_allowance`); bounding
        spheres screen before FCL. Needs :meth:`_place` done."""
        element = self._elements[row]
        active = self._active if obstacles else []
        against = [*active, *avoided]
        o_centre = self._centres[against]
        o_radius = self._radii[against]
        limits = np.empty((len(margins), len(against)))
        limits[:, : len(active)] = margins[:, None]
        limits[:, len(active) :] = avoid_margin
        centres = np.einsum("nij,j->ni", rotations, element.centre_local) + positions
        gaps = np.linalg.norm(centres[:, None] - o_centre, axis=-1) - element.radius - o_radius
        probe = fcl.CollisionObject(element.geometry, fcl.Transform())
        allowed: dict[int, float | None] = {}
        for w, o in np.argwhere(gaps <= limits):
            if collides[w]:
                continue
            other = self._fcl(against[o])
            if o not in allowed:
                start = _start_allowance(probe, rotations[0], positions[0], other)
                allowed[o] = _object_allowance(start) if o >= len(active) else start
            asked = allowed[o]
            if asked is None:
                continue
            collides[w] = _hit(probe, rotations[w], positions[w], other, min(limits[w, o], asked))

    def _track(self, arm: Arm) -> _LinkTrack:
        """``arm``'s link track (they are built left, then right)."""
        return self._link_tracks[(Arm.LEFT, Arm.RIGHT).index(Arm(arm))]

    def arm_moving_links(self, arm: Arm) -> tuple[int, ...]:
        """Link indices, on ``arm``'s body, of the arm's elements that move, palm excluded
        (on a body that carries both arms, the left arm's include the trunk's)."""
        _, links, _, rows, _, _ = self._track(arm)
        palm = self._palm_rows[Arm(arm)]
        return tuple(
            dict.fromkeys(k for k, r in zip(links, rows, strict=True) if k >= 0 and r != palm)
        )

    def check_link_frames(
        self,
        arm: Arm,
        links: Sequence[int],
        frame_positions: ArrayLike,
        frame_quaternions: ArrayLike,
        margin: float | ArrayLike = 0.0,
        avoid: Sequence[str] = (),
        avoid_margin: float = 0.0,
        obstacles: bool = True,
    ) -> NDArray[np.bool_]:
        """Check ``arm``'s elements on ``links`` posed by predicted link frames.

        Parameters
        ----------
        arm : Arm
        links : sequence of int
            (L,) link indices on the arm's body (:meth:`arm_moving_links`).
        frame_positions : array_like
            (N, L, 3) the links' frames (PyBullet's ``getLinkState`` first two), world, m.
        frame_quaternions : array_like
            (N, L, 4) scalar-last.
        margin : float or array_like
            Clearance below which a waypoint counts as colliding, m: one, or (N,).
        avoid : sequence of str
            Objects to keep ``avoid_margin`` m clear of too, where they lie.
        obstacles : bool
            Check against the active obstacles (else against ``avoid`` alone).

        Returns
        -------
        ndarray
            (N,) True where an element is within ``margin`` of an active obstacle, or, for
            one that starts nearer, nearer than it starts (:func:`_start_allowance`); or of
            an avoided object (:func:`_object_allowance`).
        """
        p = np.asarray(frame_positions, dtype=float)
        r = quat.to_matrix(np.asarray(frame_quaternions, dtype=float))  # (N, L, 3, 3)
        n = p.shape[0]
        collides = np.zeros(n, dtype=bool)
        avoided = self.avoided_rows(avoid)
        if not ((obstacles and self._active) or avoided) or n == 0:
            return collides
        margins = np.broadcast_to(np.asarray(margin, dtype=float), (n,))
        self._place()
        column = {link: k for k, link in enumerate(links)}
        _, track_links, _, rows, local_p, local_r = self._track(arm)
        for i, (link, row) in enumerate(zip(track_links, rows, strict=True)):
            k = column.get(link)
            if k is None:
                continue
            rot = r[:, k] @ local_r[i]
            pos = np.einsum("nij,j->ni", r[:, k], local_p[i]) + p[:, k]
            self._check_posed(row, rot, pos, margins, collides, avoided, avoid_margin, obstacles)
        return collides

    def avoided_rows(self, names: Sequence[str]) -> list[int]:
        """Rows of the task objects named (path checks keep clear of them where they lie)."""
        unknown = sorted(set(names) - set(self._objects))
        if unknown:
            raise ValueError(
                f"CollisionWorld: expected objects in {sorted(self._objects)}, got {unknown}"
            )
        return [self._objects[name] for name in names]

    def welded_spheres(
        self, arm: Arm, palm_position: ArrayLike, palm_quaternion: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Bounding spheres of ``arm``'s elements on links welded to its palm, palm apart.

        A link is welded to the palm when a chain of fixed joints joins them (the iCub's hand,
        the iiwa's flange): while the palms hold an object, it moves rigidly with it. Centres
        (K, 3) in the frame of the palm posed at ``palm_position`` (3,) and
        ``palm_quaternion`` (4,) (the palm as the last :meth:`sync` read it), radii (K,), m.
        """
        body, links, _, rows, _, _ = self._track(arm)
        palm_row = self._palm_rows[Arm(arm)]
        welded = welded_links(body, self.scene.robot.arms[Arm(arm)].palm_link, self.scene.client)
        chosen = [r for k, r in zip(links, rows, strict=True) if k in welded and r != palm_row]
        self._place()
        rotation = quat.to_matrix(np.asarray(palm_quaternion, dtype=float))
        centres = (self._centres[chosen] - np.asarray(palm_position, dtype=float)) @ rotation
        return np.asarray(centres, dtype=float).reshape(-1, 3), self._radii[chosen].copy()

    def arm_links(self, arm: Arm) -> tuple[str, ...]:
        """Element names of an arm, base to palm."""
        group = arm_group(arm)
        return tuple(e.name for e in self._elements if e.group == group)

    # -- keeping in step ---------------------------------------------------------------------

    def sync(self) -> None:
        """Read link, object and obstacle poses from PyBullet (one getLinkStates per body).

        The poses read are turned into FCL transforms when a query first needs them, with the
        same arithmetic: a sync that no query follows costs the reads alone.
        """
        c = self.scene.client
        positions: list[Any] = []
        quaternions: list[Any] = []
        for body, _, moving, _, _, _ in self._link_tracks:
            for state in pb.getLinkStates(
                body, moving, computeForwardKinematics=1, physicsClientId=c
            ):
                positions.append(state[0])
                quaternions.append(state[1])
            position, quaternion = pb.getBasePositionAndOrientation(body, physicsClientId=c)
            positions.append(position)
            quaternions.append(quaternion)
        for name in self._objects:
            position, quaternion = pb.getBasePositionAndOrientation(
                self.scene.object_ids[name], physicsClientId=c
            )
            positions.append(position)
            quaternions.append(quaternion)
        self._read = (positions, quaternions)
        self._active = [self._obstacles[name] for name in sorted(self.scene.active_obstacles)]

    @contextmanager
    def obstacles_present(self, names: Iterable[str]) -> Iterator[None]:
        """Within it, the queries see exactly the obstacles ``names`` (where the world file
        stands them), whichever the physics has present: a move's obstacles asked about
        before the move, with nothing moved in the physics. After it, those :meth:`sync` read.

        Raises
        ------
        ValueError
            If a name is not an obstacle of the scene.
        """
        wanted = sorted(set(names))
        unknown = [n for n in wanted if n not in self._obstacles]
        if unknown:
            raise ValueError(
                f"obstacles_present: expected names in {sorted(self._obstacles)}, got {unknown}"
            )
        saved = self._active
        self._active = [self._obstacles[n] for n in wanted]
        try:
            yield
        finally:
            self._active = saved

    def obstacles_active(self) -> bool:
        """Whether the queries see any obstacle now."""
        return bool(self._active)

    def link_name(self, arm: Arm, link: int) -> str:
        """The name of link ``link`` of ``arm``'s body, as its elements are named ("palm" for
        the palm, "base" for -1)."""
        return self._link_names[Arm(arm)][link]

    def active_obstacle_names(self) -> tuple[str, ...]:
        """The obstacles the queries see now, by name."""
        rows = set(self._active)
        return tuple(name for name, row in self._obstacles.items() if row in rows)

    # -- queries -----------------------------------------------------------------------------

    def _rows(self, group: str) -> list[int]:
        if group == OBSTACLES:
            return list(self._active)
        rows = self._group_rows.get(group)
        if rows is None:
            raise ValueError(
                f"CollisionWorld: expected a group in {list(self.group_names())}, got {group!r}"
            )
        return list(rows)

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

    def check_trajectory(
        self,
        palm_positions: ArrayLike,
        palm_quaternions: ArrayLike,
        object_name: str | None = None,
        object_positions: ArrayLike | None = None,
        object_quaternions: ArrayLike | None = None,
        margin: float = 0.0,
        avoid: Sequence[str] = (),
        avoid_margin: float = 0.0,
    ) -> TrajectoryCheck:
        """Check predicted palm (and held-object) poses against the active obstacles, and
        against the task objects in ``avoid`` where they lie now.

        A numpy bounding-sphere test drops every (waypoint, body, obstacle) triple that cannot be
        within ``margin``; FCL checks the rest.

        Parameters
        ----------
        palm_positions : array_like
            (N, 2, 3) left and right palm positions, world frame, m.
        palm_quaternions : array_like
            (N, 2, 4) left and right palm orientations, scalar-last.
        object_name : str, optional
            The held object, checked with the poses below.
        object_positions : array_like, optional
            (N, 3) held object positions, world frame, m.
        object_quaternions : array_like, optional
            (N, 4) held object orientations, scalar-last.
        margin : float
            Clearance below which a waypoint counts as colliding, m.
        avoid : sequence of str
            Objects that rest where they are (not the held one): a palm or the held object
            that does not touch one at the first waypoint must keep ``avoid_margin`` from it,
            or as much as it starts with (:func:`_object_allowance`); one touching it at the
            start (palms that have just let it go) is free of it.
        avoid_margin : float
            Clearance from those objects, m (0: not touching them).

        Returns
        -------
        TrajectoryCheck
        """
        positions = np.asarray(palm_positions, dtype=float)
        quaternions = np.asarray(palm_quaternions, dtype=float)
        if positions.ndim != 3 or positions.shape[1:] != (2, 3):
            raise ValueError(
                "check_trajectory: expected palm_positions of shape (N, 2, 3), "
                f"got {positions.shape}"
            )
        n = len(positions)
        if quaternions.shape != (n, 2, 4):
            raise ValueError(
                f"check_trajectory: expected palm_quaternions of shape {(n, 2, 4)}, "
                f"got {quaternions.shape}"
            )
        rows = [self._palm_rows[Arm.LEFT], self._palm_rows[Arm.RIGHT]]
        body_p = [positions[:, 0], positions[:, 1]]
        body_q = [quaternions[:, 0], quaternions[:, 1]]
        if object_name is not None:
            if object_positions is None or object_quaternions is None:
                raise ValueError("check_trajectory: expected object poses with object_name")
            if object_name not in self._objects:
                raise ValueError(
                    f"check_trajectory: expected an object in {sorted(self._objects)}, "
                    f"got {object_name!r}"
                )
            op = np.asarray(object_positions, dtype=float)
            oq = np.asarray(object_quaternions, dtype=float)
            if op.shape != (n, 3) or oq.shape != (n, 4):
                raise ValueError(
                    f"check_trajectory: expected object poses of shapes {(n, 3)} and {(n, 4)}, "
                    f"got {op.shape} and {oq.shape}"
                )
            rows.append(self._objects[object_name])
            body_p.append(op)
            body_q.append(oq)
        collides = np.zeros(n, dtype=bool)
        avoided = self.avoided_rows([a for a in avoid if a != object_name])
        against = [*self._active, *avoided]
        if against and n:
            self._place()
            obstacles = [self._fcl(r) for r in against]
            o_centre = self._centres[against]
            o_radius = self._radii[against]
            p_all = np.stack(body_p, axis=1)  # (N, B, 3)
            r_all = quat.to_matrix(np.stack(body_q, axis=1))  # (N, B, 3, 3)
            local = np.array([self._elements[r].centre_local for r in rows])
            radius = np.array([self._elements[r].radius for r in rows])
            centres = np.einsum("nbij,bj->nbi", r_all, local) + p_all
            gaps = (
                np.linalg.norm(centres[:, :, None] - o_centre, axis=-1) - radius[:, None] - o_radius
            )
            limits = np.array([margin] * len(self._active) + [avoid_margin] * len(avoided))
            candidates = np.argwhere(gaps <= limits)  # (K, 3): waypoint, body, obstacle
            probes = [
                fcl.CollisionObject(self._elements[r].geometry, fcl.Transform()) for r in rows
            ]
            allowed: dict[tuple[int, int], float | None] = {}
            for w, b, o in candidates:
                if collides[w]:
                    continue
                asked = margin
                if o >= len(self._active):
                    if (b, o) not in allowed:
                        start = _start_allowance(probes[b], r_all[0, b], p_all[0, b], obstacles[o])
                        allowed[b, o] = _object_allowance(start)
                    free = allowed[b, o]
                    if free is None:
                        continue
                    asked = min(free, avoid_margin)
                collides[w] = _hit(probes[b], r_all[w, b], p_all[w, b], obstacles[o], asked)
        hits = np.flatnonzero(collides)
        return TrajectoryCheck(collides, int(hits[0]) if len(hits) else -1)


__all__ = [
    "OBSTACLES",
    "TABLE",
    "CollisionWorld",
    "LinkDistances",
    "Proximity",
    "TrajectoryCheck",
    "arm_group",
]


#: How much nearer than it is now a link already inside the margin may be carried, m: the
#: prediction's own numerical slack, not a licence to approach.
START_SLACK_M = 0.002


def _start_allowance(
    probe: Any,
    rotation: NDArray[np.float64],
    position: NDArray[np.float64],
    obstacle: Any,
) -> float:
    """The most clearance a path can ask of a carried link from one obstacle: its distance at
    the path's first waypoint (posed at ``rotation``, ``position``) less :data:`START_SLACK_M`.
    The robot is where it is: a path may keep or widen the gap it starts with, never narrow
    it, and a link touching at the start is refused at once."""
    probe.setTransform(fcl.Transform(rotation, position))
    start = float(fcl.distance(probe, obstacle, fcl.DistanceRequest()))
    return max(start - START_SLACK_M, 0.0)


def _object_allowance(start: float) -> float | None:
    """The most clearance a path can ask of an element from a resting object, given its
    :func:`_start_allowance` there: None, free of it, when the element starts touching it
    (palms that have just let it go); else that start clearance, so that an element that
    starts nearer than the margin may keep or widen its gap, never narrow it."""
    if start <= 0.0:
        return None
    return start


def _hit(
    probe: Any,
    rotation: NDArray[np.float64],
    position: NDArray[np.float64],
    obstacle: Any,
    margin: float,
) -> bool:
    """Whether ``probe`` posed at ``rotation`` (3, 3) and ``position`` (3,), world frame, comes
    within ``margin`` m of ``obstacle`` (touches it, for a margin of 0): FCL's exact answer."""
    probe.setTransform(fcl.Transform(rotation, position))
    if margin > 0.0:
        return bool(fcl.distance(probe, obstacle, fcl.DistanceRequest()) < margin)
    return bool(fcl.collide(probe, obstacle, fcl.CollisionRequest(), fcl.CollisionResult()))


def welded_links(body: int, link: int, client: int) -> frozenset[int]:
    """Links of ``body`` joined to ``link`` by chains of fixed joints (``link`` included; -1
    is the base)."""
    parent: dict[int, tuple[int, bool]] = {}
    for j in range(pb.getNumJoints(body, physicsClientId=client)):
        info = pb.getJointInfo(body, j, physicsClientId=client)
        parent[j] = (int(info[16]), int(info[2]) == pb.JOINT_FIXED)
    welded = {link}
    grown = True
    while grown:
        grown = False
        for child, (up, fixed) in parent.items():
            if fixed and (child in welded) != (up in welded):
                welded |= {child, up}
                grown = True
    return frozenset(welded)
