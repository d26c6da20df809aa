"""The FCL collision geometry of a :class:`worlds.scene.Scene`, kept in step with PyBullet.

Every robot link (from ``getCollisionShapeData``: iiwa meshes as convex hulls, as PyBullet
collides them; boxes), the table, the objects and the obstacles become FCL collision objects,
each with a bounding sphere for a numpy prefilter. :meth:`CollisionGeometry.sync` reads all
link poses (one ``getLinkStates`` call per robot body) and object poses; the elements are posed
from that read when a query first needs them.

Groups name sets of elements: ``"left_arm"``, ``"right_arm"`` (all links of the arm's body,
palm included; of a body that carries both arms, each arm's own links, the rest of the body
with the left arm: :func:`worlds.bodies.arm_link_indices`), ``"table"``, ``"obstacles"`` (the
active ones) and each object by its name. Element names are ``"left_arm/<link>"`` (the palm
link ``"left_arm/palm"``), ``"table"``, the object or obstacle name.

The queries live above it: predicted poses checked in :mod:`worlds.posed_checks`, the world as
it stands in :mod:`worlds.collision` (:class:`worlds.collision.CollisionWorld`, the class to
use). Poses are (position (3,), quaternion (4,) scalar-last) pairs in the world frame.
"""

from __future__ import annotations

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


class CollisionGeometry:
    """FCL mirror of a scene's collision geometry: its elements, groups and poses.

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

    def _rows(self, group: str) -> list[int]:
        if group == OBSTACLES:
            return list(self._active)
        rows = self._group_rows.get(group)
        if rows is None:
            raise ValueError(
                f"CollisionWorld: expected a group in {list(self.group_names())}, got {group!r}"
            )
        return list(rows)


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


__all__ = [
    "FIXTURES",
    "OBSTACLES",
    "TABLE",
    "CollisionGeometry",
    "arm_group",
    "welded_links",
]
