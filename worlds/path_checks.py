"""The simulated world's predictions of paths, checked against what they could touch.

A path is the palms' poses over time (and a held object's): :meth:`PathChecks.check` asks the
FCL mirror (:class:`worlds.collision.CollisionWorld`) whether the palms, the held object and
the arms' links come within a margin of the active obstacles, or touch the objects where they
rest. The links are posed by inverse kinematics of the palms' path on a kinematic copy of the
robot (:class:`worlds.arm_prediction.ArmPredictor`), and asked more clearance the further the
palms go (:func:`forearm_doubt`), as the controller's motion swings an elbow off the
solution. The same machinery answers whether the robot can hold an object at a place clear of
a move's obstacles (:meth:`PathChecks.holds_clear`, for
:func:`worlds.turn_choice.turn_places`) and what of it touches an obstacle in a hold
(:meth:`PathChecks.hold_touches`, for :mod:`worlds.obstacle_holds`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from functools import partial
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from planner.port import PathCheck
from skills.turns import Hold
from skills.types import Array
from skills.vocabulary import ARMS, Arm
from worlds.arm_prediction import (
    WAYPOINT_ITERATIONS,
    WAYPOINT_TOLERANCE,
    ArmPredictor,
    LinkFrames,
)
from worlds.collision import CollisionWorld
from worlds.scene import Scene
from worlds.trays import riders
from worlds.turn_choice import hold_poses

#: Extra clearance asked of predicted arm-link poses (solved for the palms' path, not run
#: through the controller), m: the most, for a long carry.
FOREARM_MARGIN_M = 0.03
#: How fast that extra clearance grows with the palms' travel from the path's start, m per m.
#: The prediction misses how the controller's motion swings the elbow off the solution, which
#: grows with how far the palms have gone (turns counted at :data:`FOREARM_LEVER_M` per
#: radian); a short correction near an obstacle is not held to a long carry's doubt.
FOREARM_DOUBT_PER_M = 0.2
#: Lever that converts a palm's turn into travel for that doubt, m per rad (a forearm's length).
FOREARM_LEVER_M = 0.3
#: Waypoints between two solved for the arms' prediction (4 control steps at 60 Hz: the palms
#: move at most a centimetre or two in between).
PREDICTION_STRIDE = 4
#: Clearance from a move's obstacles asked of the robot holding the object where a turned
#: move's steps would stand (:func:`worlds.turn_choice.turn_places`), m: the shipped tree's
#: carries' margin.
TURN_PLACE_MARGIN_M = 0.01
#: Each such hold's arms solved to convergence (a lone pose, far from the measured joints):
#: most steps and the pose error the solve stops at, m and rad.
HOLD_SOLVE = (300, 1e-4)
#: Where a grasp's way in ends, m outside the held faces: the shipped trees' ``Approach``
#: stand-off (its ``standoff_m`` default), asked of such holds too.
APPROACH_STANDOFF_M = 0.04
#: The clearance a place other than the goal must leave, m: the object is set down there
#: within a few millimetres of where it was sent, then carried on from where it lies.
OTHER_PLACE_MARGIN_M = 0.02
#: Farthest a palm of such a hold may be left from its pose by that solve, m: beyond it, the
#: arm cannot reach the hold.
HOLD_REACH_M = 0.005


def forearm_doubt(palm_positions: Array, palm_orientations: Array) -> Array:
    """Extra clearance asked of the forearms at each waypoint (N,), m: grows with the palms'
    travel from the first waypoint (:data:`FOREARM_DOUBT_PER_M`), up to
    :data:`FOREARM_MARGIN_M`.

    Parameters
    ----------
    palm_positions : ndarray
        (N, 2, 3) left and right palm positions, world frame, m.
    palm_orientations : ndarray
        (N, 2, 4) their orientations, scalar-last.
    """
    p = np.asarray(palm_positions, dtype=float)
    q = np.asarray(palm_orientations, dtype=float)
    shift = np.linalg.norm(p - p[:1], axis=-1)  # (N, 2)
    turn = 2.0 * np.arccos(np.clip(np.abs(np.sum(q * q[:1], axis=-1)), 0.0, 1.0))
    travel = np.max(shift + FOREARM_LEVER_M * turn, axis=-1)
    return np.minimum(FOREARM_MARGIN_M, FOREARM_DOUBT_PER_M * travel)


class LinkHits(NamedTuple):
    """Where the arms' predicted links come too near (:meth:`PathChecks.predicted_links_collide`).

    Attributes
    ----------
    on_obstacles, on_objects : ndarray
        (N,) bool: within the margins of an active obstacle; of an object where it rests.
    end_on_obstacle : bool
        At the last waypoint, within the end's margin of an active obstacle.
    end_objects : tuple of str
        The objects a link comes within the objects' margin of at the last waypoint.
    """

    on_obstacles: NDArray[np.bool_]
    on_objects: NDArray[np.bool_]
    end_on_obstacle: bool = False
    end_objects: tuple[str, ...] = ()
    #: ``who(i, margin)``: the first arm link, and the active obstacle, that come within
    #: ``margin`` of each other at waypoint ``i`` (as its nearest solved waypoint poses the
    #: links), e.g. ("the right arm's lbr_iiwa_link_5", "ball_left"); None if no one link does
    #: alone.
    who: Callable[[int, float], tuple[str, str] | None] | None = None
    #: ``who_on_object(i)``: the first arm link, and the object where it rests, that come
    #: within the objects' margin of each other at waypoint ``i``; None if no one link does.
    who_on_object: Callable[[int], tuple[str, str] | None] | None = None


class PathChecks:
    """Path and hold checks of a scene's robot against its FCL mirror.

    Parameters
    ----------
    scene : Scene
        The PyBullet scene (its robot, objects and world spec).
    collision : CollisionWorld
        Its FCL mirror, kept in sync by the owner.
    extents : dict
        Each object's bounding-box extents (3,) in its own frame, m, by name.
    carried : sequence of str
        The objects the task moves (none of them rides loose on another).
    """

    def __init__(
        self,
        scene: Scene,
        collision: CollisionWorld,
        extents: dict[str, Array],
        carried: Sequence[str] = (),
    ) -> None:
        self.scene = scene
        self._carried = tuple(carried)
        self.collision = collision
        self._extents = extents
        self.palm_thickness = float(scene.spec.robot.palm_size[2])
        self._robot_yaw = math.radians(scene.spec.robot.base_rpy_deg[2])  # the grips' heading
        # Arms that share joints (a torso) are predicted by inverse kinematics on a copy of
        # the robot, built at the first path check (worlds.arm_prediction).
        self._arm_predictor: ArmPredictor | None = None

    def close(self) -> None:
        """Disconnect the kinematic copy, if one was built."""
        if self._arm_predictor is not None:
            self._arm_predictor.close()
            self._arm_predictor = None

    def predictor(self) -> ArmPredictor:
        """The arms' predictor on the robot's kinematic copy, made at its first use."""
        if self._arm_predictor is None:
            self._arm_predictor = ArmPredictor(self.scene)
        return self._arm_predictor

    def holds_clear(
        self, name: str, obstacles: tuple[str, ...], holds: Sequence[Hold], elsewhere: bool
    ) -> bool:
        """Whether the robot can hold object ``name`` in each of ``holds``: palms, object and
        the arms' links (solved to convergence) :data:`TURN_PLACE_MARGIN_M` from
        ``obstacles`` (with ``elsewhere``, :data:`OTHER_PLACE_MARGIN_M`, and its palms reached
        within :data:`HOLD_REACH_M`: the test of a place other than the goal);
        asked of the collision world and the kinematic copy alone: nothing moves in the
        physics. The arms' links are kept off the other objects standing on the table too
        (not those riding on ``name``): a hold that puts a wrist on one is no place to turn."""
        standing = self._standing(name)
        margin = OTHER_PLACE_MARGIN_M if elsewhere else TURN_PLACE_MARGIN_M
        with self.collision.obstacles_present(obstacles):
            for hold in holds:
                palms, palm_quats, object_quat = hold_poses(
                    hold, self._extents[name], self.palm_thickness, self._robot_yaw
                )
                check = self.check(
                    palms[None],
                    palm_quats[None],
                    margin,
                    (name, hold.position[None], object_quat[None]),
                    link_doubt=False,
                    solve=HOLD_SOLVE,
                )
                if not check.clear:
                    return False
                if elsewhere:
                    if not obstacles:  # the check had nothing to solve the arms for
                        no_links: dict[Arm, tuple[int, ...]] = {arm: () for arm in ARMS}
                        self.predictor().link_frames(
                            palms[None], palm_quats[None], no_links, *HOLD_SOLVE
                        )
                    if max(self.predictor().last_palm_errors().values()) > HOLD_REACH_M:
                        return False
                if standing and self._links_on(name, standing, hold, margin):
                    return False
        return True

    def _standing(self, name: str) -> tuple[str, ...]:
        """The objects other than ``name`` and those riding loose on it (a tray's balls)."""
        objects = self.scene.spec.objects
        loose = {o.name for o in riders(objects, name, self._carried)}
        return tuple(o.name for o in objects if o.name != name and o.name not in loose)

    def _links_on(self, name: str, objects: tuple[str, ...], hold: Hold, margin: float) -> bool:
        """Whether an arm link, solved to convergence, comes within ``margin`` m of one of
        ``objects`` where it rests, with the palms holding ``name`` in ``hold`` or where a
        grasp's way in to it ends (:data:`APPROACH_STANDOFF_M` outside the faces)."""
        links = {arm: self.collision.arm_moving_links(arm) for arm in ARMS}
        for gap in (0.0, APPROACH_STANDOFF_M):
            palms, quats, _ = hold_poses(
                hold, self._extents[name], self.palm_thickness, self._robot_yaw, gap
            )
            frames = self.predictor().link_frames(palms[None], quats[None], links, *HOLD_SOLVE)
            for arm, f in frames.items():
                if self.collision.check_link_frames(
                    arm, f.links, f.positions, f.quaternions, 0.0, objects, margin, False, False
                )[0]:
                    return True
        return False

    def hold_touches(self, name: str, obstacles: Sequence[str], hold: Hold) -> dict[str, str]:
        """What of the robot holding object ``name`` in ``hold`` touches each of ``obstacles``
        (active or not): "a palm", or an arm's links solved to convergence
        (:data:`HOLD_SOLVE`, once for all of them) on the kinematic copy; obstacles nothing
        touches are left out. Asked of the collision world and the copy alone: nothing moves
        in the physics."""
        palms, palm_quats, _ = hold_poses(
            hold, self._extents[name], self.palm_thickness, self._robot_yaw
        )
        links = {arm: self.collision.arm_moving_links(arm) for arm in ARMS}
        frames = self.predictor().link_frames(palms[None], palm_quats[None], links, *HOLD_SOLVE)
        touched: dict[str, str] = {}
        for obstacle in obstacles:
            with self.collision.obstacles_present((obstacle,)):
                if self.collision.check_trajectory(palms[None], palm_quats[None]).collides[0]:
                    touched[obstacle] = "a palm touches it"
                    continue
                for arm in ARMS:
                    f = frames[arm]
                    at = (arm, f.links, f.positions, f.quaternions)
                    if self.collision.check_link_frames(*at)[0]:
                        touched[obstacle] = f"the {arm.value} arm touches it"
                        break
        return touched

    def check(
        self,
        palm_positions: Array,
        palm_orientations: Array,
        margin_m: float,
        held: tuple[str, Array, Array] | None,
        object_margin_m: float = 0.0,
        link_doubt: bool = True,
        solve: tuple[int, float] = (WAYPOINT_ITERATIONS, WAYPOINT_TOLERANCE),
    ) -> PathCheck:
        """Check the palms' path (N, 2, 3) m and (N, 2, 4) scalar-last, world frame, and the
        arms' links solved along it, against the active obstacles with ``margin_m`` (the links
        with :func:`forearm_doubt` more unless ``link_doubt`` is False).

        ``held`` is (name, positions (N, 3), quaternions (N, 4)) of the object the palms carry;
        None for empty palms, which then keep ``object_margin_m`` from every object where it
        rests (one they touch where the path starts is free of it). ``solve`` is each
        waypoint's inverse kinematics: most steps and the pose error it stops at.
        """
        name, object_positions, object_orientations = held if held else (None, None, None)
        avoid = () if held else tuple(o.name for o in self.scene.spec.objects)
        check = self.collision.check_trajectory(
            palm_positions,
            palm_orientations,
            name,
            object_positions,
            object_orientations,
            margin_m,
            avoid,
            object_margin_m,
        )
        # The arms' links are solved for along the palms' path (predicted_links_collide):
        # carried rigidly with the palms instead, a forearm misses the elbow's swing (and a
        # torso's), centimetres over a carry. The solution is the controller's posture, not
        # the controller's motion: the links get extra clearance the further the palms go.
        doubt = (
            forearm_doubt(palm_positions, palm_orientations)
            if link_doubt
            else np.zeros(len(palm_positions))
        )
        hits = self.predicted_links_collide(
            palm_positions,
            palm_orientations,
            margin_m + doubt,
            avoid,
            object_margin_m,
            margin_m,
            solve,
        )
        arms, arms_on_objects = hits.on_obstacles, hits.on_objects
        pts = np.asarray(palm_positions).reshape(-1, 3)
        if object_positions is not None:
            pts = np.concatenate((object_positions, pts))
        d, _ = self.collision.query(pts)
        sure = check.collides | arms_on_objects
        hit = np.flatnonzero(sure | arms)
        first = int(hit[0]) if hit.size else None
        what = "clear"
        if first is not None:
            if check.collides[first] and check.first_pair is not None:
                near, far = check.first_pair
                resting = far in self.scene.object_ids
                what = f"{near} within {object_margin_m if resting else margin_m:g} m of {far}"
            elif check.collides[first]:
                what = f"{'palm or object' if held else 'a palm'} within {margin_m:g} m" + (
                    "" if held else f" of an obstacle, or {object_margin_m:g} m of an object"
                )
            elif arms_on_objects[first]:
                on = hits.who_on_object(first) if hits.who_on_object is not None else None
                what = (
                    f"{on[0]} within {object_margin_m:g} m of {on[1]}"
                    if on
                    else f"an arm link within {object_margin_m:g} m of an object"
                )
            else:
                margin = margin_m + doubt[first]
                who = hits.who(first, margin) if hits.who is not None else None
                what = (
                    f"{who[0]} within {margin:.3f} m of {who[1]}"
                    if who
                    else f"an arm link within {margin:.3f} m"
                )
            what += f" at step {first}"
        # The last pose alone, against the obstacles (the objects are the palms' to touch),
        # its links asked the margin without the doubt: a way that ends within the margin of
        # an obstacle cannot be made clear by another way to the same end.
        end_clear = not hits.end_on_obstacle
        # Asked again only when the whole way's check found the last pose within the margin
        # (of an obstacle or, with no allowance, an object): the obstacles asked alone.
        if end_clear and check.collides.size and check.collides[-1]:
            end = self.collision.check_trajectory(
                np.asarray(palm_positions)[-1:],
                np.asarray(palm_orientations)[-1:],
                name,
                None if object_positions is None else object_positions[-1:],
                None if object_orientations is None else object_orientations[-1:],
                margin_m,
            )
            end_clear = not end.collides[0]
        return PathCheck(
            first is None,
            float(d.min()) if d.size else math.inf,
            first,
            what,
            doubtful=link_doubt and first is not None and not sure.any(),
            end_clear=bool(end_clear),
            end_objects=hits.end_objects,
        )

    def predicted_links_collide(
        self,
        palm_positions: Array,
        palm_orientations: Array,
        margins: Array,
        avoid: Sequence[str] = (),
        avoid_margin: float = 0.0,
        end_margin: float | None = None,
        solve: tuple[int, float] = (WAYPOINT_ITERATIONS, WAYPOINT_TOLERANCE),
    ) -> LinkHits:
        """Where an arm link, posed by inverse kinematics of the palm path on a copy of the
        robot (:class:`worlds.arm_prediction.ArmPredictor`), comes within ``margins`` (N,) of
        an active obstacle, and where within ``avoid_margin`` of an object in ``avoid`` where
        it rests; and at the last waypoint, whether a link comes within ``end_margin`` of an
        obstacle (None: unasked) and which objects of ``avoid`` a link comes within
        ``avoid_margin`` of. Waypoints are solved every :data:`PREDICTION_STRIDE` (and the
        last), each with ``solve`` (most steps, tolerance: :meth:`ArmPredictor.link_frames`);
        one between two solved ones is judged by the nearer of them."""
        p = np.asarray(palm_positions, dtype=float)
        q = np.asarray(palm_orientations, dtype=float)
        n = p.shape[0]
        if n == 0 or not (self.collision.obstacles_active() or avoid):
            return LinkHits(np.zeros(n, dtype=bool), np.zeros(n, dtype=bool))
        solved = np.unique(np.append(np.arange(0, n, PREDICTION_STRIDE), n - 1))
        links = {arm: self.collision.arm_moving_links(arm) for arm in ARMS}
        frames = self.predictor().link_frames(p[solved], q[solved], links, *solve)
        on_obstacles = np.zeros(solved.size, dtype=bool)
        on_objects = np.zeros(solved.size, dtype=bool)
        at_end = False
        for arm in ARMS:
            f = frames[arm]
            at = (arm, f.links, f.positions, f.quaternions)
            hit = self.collision.check_link_frames(*at, np.asarray(margins)[solved])
            on_obstacles |= hit
            if avoid:
                on_objects |= self.collision.check_link_frames(
                    *at, avoid_margin, avoid, avoid_margin, obstacles=False
                )
            # The last pose alone touches only where the whole way, asked at least as much
            # from where it starts, already reached it.
            if end_margin is not None and hit[-1]:
                last = (arm, f.links, f.positions[-1:], f.quaternions[-1:])
                at_end |= bool(self.collision.check_link_frames(*last, end_margin)[0])
        end_objects: tuple[str, ...] = ()
        if on_objects[-1]:
            # Which of them, each checked over the whole way (a link that touched one where
            # the way starts is free of it there: it has just let it go).
            end_objects = tuple(
                o
                for o in avoid
                if any(
                    self.collision.check_link_frames(
                        arm,
                        f.links,
                        f.positions,
                        f.quaternions,
                        avoid_margin,
                        [o],
                        avoid_margin,
                        obstacles=False,
                    )[-1]
                    for arm, f in frames.items()
                )
            )
        nearest = np.clip(
            np.searchsorted(solved, np.arange(n) - PREDICTION_STRIDE // 2), 0, solved.size - 1
        )

        def who(i: int, margin: float) -> tuple[str, str] | None:
            return self._touching_link(frames, int(nearest[i]), margin)

        def who_on_object(i: int) -> tuple[str, str] | None:
            return self._link_on_object(frames, int(nearest[i]), avoid_margin, avoid)

        return LinkHits(
            on_obstacles[nearest], on_objects[nearest], at_end, end_objects, who, who_on_object
        )

    def _touching_link(
        self, frames: dict[Arm, LinkFrames], i: int, margin: float
    ) -> tuple[str, str] | None:
        """The first arm link (left arm first, base to palm) within ``margin`` of an active
        obstacle in solved pose ``i`` of ``frames``, named, with that obstacle (each link
        checked over the way up to there, as the path's check does: one that starts nearer than
        the margin may keep its gap); None when no one link is. Asked only to say why a path was
        refused."""
        for obstacle in self.collision.active_obstacle_names():
            with self.collision.obstacles_present((obstacle,)):
                link = self._first_link(
                    frames, i, partial(self.collision.check_link_frames, margin=margin)
                )
            if link is not None:
                return link, obstacle
        return None

    def _link_on_object(
        self, frames: dict[Arm, LinkFrames], i: int, margin: float, objects: Sequence[str]
    ) -> tuple[str, str] | None:
        """As :meth:`_touching_link`, for the objects where they rest: the first arm link
        within ``margin`` of one of ``objects`` in solved pose ``i``, named, with the object."""
        for obj in objects:
            near = partial(
                self.collision.check_link_frames,
                margin=margin,
                avoid=(obj,),
                avoid_margin=margin,
                obstacles=False,
            )
            link = self._first_link(frames, i, near)
            if link is not None:
                return link, obj
        return None

    def _first_link(
        self,
        frames: dict[Arm, LinkFrames],
        i: int,
        hits: Callable[[Arm, tuple[int, ...], Array, Array], NDArray[np.bool_]],
    ) -> str | None:
        """The first arm link (left arm first, base to palm) that ``hits`` (a link check over
        the way up to solved pose ``i``) finds near at ``i``, named; None if none."""
        for arm in ARMS:
            f = frames[arm]
            for k, link in enumerate(f.links):
                at = (f.positions[: i + 1, k : k + 1], f.quaternions[: i + 1, k : k + 1])
                if hits(arm, (link,), *at)[-1]:
                    return f"the {arm.value} arm's {self.collision.link_name(arm, link)}"
        return None


__all__ = [
    "FOREARM_DOUBT_PER_M",
    "FOREARM_LEVER_M",
    "FOREARM_MARGIN_M",
    "HOLD_REACH_M",
    "HOLD_SOLVE",
    "OTHER_PLACE_MARGIN_M",
    "PREDICTION_STRIDE",
    "TURN_PLACE_MARGIN_M",
    "LinkHits",
    "PathChecks",
    "forearm_doubt",
]
