"""Predicted poses checked against the collision geometry: palm and held-object paths, arm
links posed by predicted link frames, and distal links carried with the palms.

:class:`PosedChecks` adds these checks to :class:`worlds.collision_geometry.CollisionGeometry`;
:class:`worlds.collision.CollisionWorld` is the class to use. Each check screens with the
elements' bounding spheres before FCL, and holds a path to the clearance it starts with where it
starts nearer than asked (:func:`_start_allowance`, :func:`_object_allowance`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from skills.vocabulary import Arm
from worlds.collision_geometry import CollisionGeometry, arm_group

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class TrajectoryCheck:
    """Result of checking predicted palm (and held-object) poses against the obstacles.

    Attributes
    ----------
    collides : ndarray
        (N,) True where some palm or the held object is within ``margin`` of an obstacle.
    first_collision : int
        Index of the first such waypoint, -1 if none.
    first_pair : tuple of str, optional
        What is near what there: ("the left palm" or "the right palm" or the held object's
        name, the obstacle's or resting object's name); None if no waypoint collides.
    """

    collides: NDArray[np.bool_]
    first_collision: int
    first_pair: tuple[str, str] | None = None

    @property
    def collision_free(self) -> bool:
        """No waypoint collides."""
        return self.first_collision < 0


class PosedChecks(CollisionGeometry):
    """Checks of predicted poses against the active obstacles (and resting objects)."""

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
        from_start: bool = True,
    ) -> None:
        """Mark in ``collides`` (N,) the waypoints where element ``row``, posed at ``rotations``
        (N, 3, 3) and ``positions`` (N, 3), comes within ``margins`` (N,) of an active
        obstacle (unless not ``obstacles``), or nearer than it starts
        (:func:`_start_allowance`), or within ``avoid_margin`` of an object in ``avoided``
        (rows) that it does not touch at the start (:func:`_object_allowance`); without
        ``from_start``, the margins asked as they are, whatever the first pose touches (poses
        that are not a way from it). Bounding spheres screen before FCL. Needs :meth:`_place`
        done."""
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
            if not from_start:
                allowed[o] = math.inf
            elif o not in allowed:
                start = _start_allowance(probe, rotations[0], positions[0], other)
                allowed[o] = _object_allowance(start) if o >= len(active) else start
            asked = allowed[o]
            if asked is None:
                continue
            collides[w] = _hit(probe, rotations[w], positions[w], other, min(limits[w, o], asked))

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
        from_start: bool = True,
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
        from_start : bool
            The frames are a way from the first: an element that starts nearer than a margin
            is asked only not to come nearer. False: each frame asked the margins as they are.

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
            self._check_posed(
                row, rot, pos, margins, collides, avoided, avoid_margin, obstacles, from_start
            )
        return collides

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
        first_pair: tuple[str, str] | None = None
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
                if collides[w] and first_pair is None:  # candidates come waypoint by waypoint
                    near = ("the left palm", "the right palm", object_name)[b]
                    first_pair = (str(near), self._elements[against[o]].name)
        hits = np.flatnonzero(collides)
        return TrajectoryCheck(collides, int(hits[0]) if len(hits) else -1, first_pair)


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


__all__ = ["START_SLACK_M", "PosedChecks", "TrajectoryCheck"]
