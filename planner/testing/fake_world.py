"""An in-memory world that satisfies :class:`planner.port.WorldPort`, for testing leaves.

Kinematic, deterministic and fast:

- palms go exactly where they are commanded at the next :meth:`FakeWorld.advance`;
- a box object touches a palm when the palm's face reaches its +y or -y face; the normal force
  is a stiff spring on the penetration (``contact_stiffness`` N/m), as a commanded squeeze
  offset produces in the real controller;
- an object is held while Coulomb friction on both palms carries its weight
  (``2 * mu * min(F_L, F_R) >= m g``); a held object moves with the palms, centred between
  them;
  a released object rests on the table under its centre;
- obstacles are spheres; the arms are segments from fixed shoulders to the palms.

Test hooks: :meth:`FakeWorld.drop` makes the grip fail from now on (as a slip would), and
:attr:`FakeWorld.commands` records every palm command.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from affordances import (
    ObjectContext,
    RobotCapabilities,
    SceneQuery,
    grip_friction_n,
    make_object_context,
)
from affordances.context import PAPER_ROBOT
from affordances.scene import GeometricSceneQuery
from planner.port import (
    FixtureInfo,
    Move,
    ObstacleGap,
    ObstacleInfo,
    PathCheck,
    Pose,
    stepped_moves,
)
from skills import quaternion as quat
from skills.dual_arm import GraspGeometry
from skills.level_carry import LooseBall
from skills.turns import yaw_of
from skills.types import Array
from skills.vocabulary import ARMS, Arm

GRAVITY = 9.81


@dataclass
class FakeObject:
    """A box on the table."""

    name: str
    extents: Array
    mass: float = 1.0
    friction: float = 0.8
    category: str = "parcel"
    material: str = "cardboard"
    pose: Pose = field(default_factory=lambda: Pose.of([0.55, 0.0, 0.675]))


@dataclass(frozen=True)
class Recorded:
    """A palm command as the fake received it."""

    time: float
    arm: Arm
    pose: Pose
    twist: Array


class FakeWorld:
    """A kinematic dual-arm world with one table, box objects and sphere obstacles."""

    def __init__(
        self,
        objects: Iterable[FakeObject] = (),
        obstacles: Iterable[ObstacleInfo] = (),
        moves: dict[str, tuple[Move, ...]] | None = None,
        table_height: float = 0.6,
        palm_thickness: float = 0.02,
        contact_stiffness: float = 1000.0,
        palm_friction: float = 0.8,
        shoulders: dict[Arm, Array] | None = None,
        fixtures: Iterable[FixtureInfo] = (),
    ) -> None:
        objs = list(objects) or [FakeObject("parcel", np.array([0.20, 0.30, 0.15]))]
        self._objects = {o.name: o for o in objs}
        self._all_obstacles = {o.name: o for o in obstacles}
        self._fixtures = tuple(fixtures)
        self._active: set[str] = set()
        # As a world shows them: turns beyond the paper robot's grip split into steps.
        self._moves = {
            name: stepped_moves(
                task,
                yaw_of(self._objects[name].pose.orientation) if name in self._objects else 0.0,
                PAPER_ROBOT.max_turn_rad,
            )
            for name, task in (moves or {}).items()
        }
        self.table_height = table_height
        self._palm_thickness = palm_thickness
        self.contact_stiffness = contact_stiffness
        self.palm_friction = palm_friction
        self.shoulders = shoulders or {
            Arm.LEFT: np.array([0.0, 0.35, 0.95]),
            Arm.RIGHT: np.array([0.0, -0.35, 0.95]),
        }
        self._t = 0.0
        g = GraspGeometry.lateral(0.30, palm_thickness)
        self._rest = {
            arm: Pose.of(
                np.array([0.35, 0.45 if arm is Arm.LEFT else -0.45, 0.85]), g.orientation(arm)
            )
            for arm in ARMS
        }
        self._palms = dict(self._rest)
        self._palm_twists = {arm: np.zeros(6) for arm in ARMS}
        self._targets = dict(self._rest)
        self._target_twists = {arm: np.zeros(6) for arm in ARMS}
        #: Where each palm settles from its target, m: none but under :meth:`bias_palm`.
        self._bias: dict[Arm, Array | None] = {arm: None for arm in ARMS}
        self._held: dict[str, Array | None] = {name: None for name in self._objects}  # (2, 7)
        self._dropped: set[str] = set()
        self.commands: list[Recorded] = []
        self.holds = 0

    # -- test hooks ------------------------------------------------------------------------
    def drop(self, name: str = "parcel") -> None:
        """Make the grip on ``name`` fail from now on (forces read zero, the object falls)."""
        self._dropped.add(name)

    def restore_grip(self, name: str = "parcel") -> None:
        """Undo :meth:`drop`."""
        self._dropped.discard(name)

    def bias_palm(self, arm: Arm, offset: ArrayLike) -> None:
        """From the next advance on, the palm settles ``offset`` (3,) m off its target, as a
        biased actuator holds it (Hard mode's torque bias, :mod:`worlds.actuators`)."""
        self._bias[arm] = np.asarray(offset, dtype=float)

    def place_palms(self, poses: dict[Arm, Pose]) -> None:
        """Put the palms somewhere directly (test set-up)."""
        for arm, pose in poses.items():
            self._palms[arm] = self._targets[arm] = pose

    # -- WorldPort: time -------------------------------------------------------------------
    def time(self) -> float:
        """Simulated time, s."""
        return self._t

    def advance(self, dt: float) -> None:
        """Move palms to their targets; carry, hold or drop objects."""
        before = dict(self._palms)
        for arm in ARMS:
            target, bias = self._targets[arm], self._bias[arm]
            self._palms[arm] = (
                target if bias is None else Pose(target.position + bias, target.orientation)
            )
            self._palm_twists[arm] = self._target_twists[arm]
        for name, obj in self._objects.items():
            grip = self._held[name]
            if self._can_hold(name):
                if grip is None:  # grip starts: remember the object in each palm's frame
                    grip = np.stack([self._object_in_palm(obj.pose, before[a]) for a in ARMS])
                    self._held[name] = grip
                # Squeezed between both palms, the object sits where both grips put it, on
                # average (a rigid grip would follow one palm and squeeze off-centre).
                guesses = [
                    (
                        self._palms[a].position + quat.rotate(self._palms[a].orientation, g[:3]),
                        quat.multiply(self._palms[a].orientation, g[3:]),
                    )
                    for a, g in zip(ARMS, grip, strict=True)
                ]
                obj.pose = Pose(0.5 * (guesses[0][0] + guesses[1][0]), guesses[0][1])
            else:
                self._held[name] = None
                rest_z = self.table_height + obj.extents[2] / 2.0
                obj.pose = Pose(np.array([*obj.pose.position[:2], rest_z]), obj.pose.orientation)
        self._t += dt

    @staticmethod
    def _object_in_palm(obj: Pose, palm: Pose) -> Array:
        inv = quat.conjugate(palm.orientation)
        p = quat.rotate(inv, obj.position - palm.position)
        q = quat.multiply(inv, obj.orientation)
        return np.concatenate((p, q))

    def _penetration(self, arm: Arm, name: str) -> float:
        obj = self._objects[name]
        palm = self._palms[arm]
        inv = quat.conjugate(obj.pose.orientation)
        p = quat.rotate(inv, palm.position - obj.pose.position)
        half = obj.extents / 2.0
        if abs(p[0]) > half[0] or abs(p[2]) > half[2]:
            return 0.0
        side = 1.0 if arm is Arm.LEFT else -1.0
        return float(half[1] + self._palm_thickness / 2.0 - side * p[1])

    def _can_hold(self, name: str) -> bool:
        if name in self._dropped:
            return False
        obj = self._objects[name]
        f = min(self.contact_force(arm, name) for arm in ARMS)
        mu = obj.friction * self.palm_friction
        return f > 0.0 and grip_friction_n(mu, f) >= obj.mass * GRAVITY

    # -- WorldPort: objects and task ---------------------------------------------------------
    def object_pose(self, name: str) -> Pose:
        """Pose of an object's centre."""
        return self._objects[name].pose

    def object_twist(self, name: str) -> Array:
        """Twist of a held object: the palms' mean; a resting one is still."""
        if self._held[name] is None:
            return np.zeros(6)
        return 0.5 * (self._palm_twists[Arm.LEFT] + self._palm_twists[Arm.RIGHT])

    def loose_balls(self, name: str) -> tuple[LooseBall, ...]:
        """None: the fake world's objects carry nothing loose."""
        return ()

    def object_extents(self, name: str) -> Array:
        """Box extents (3,), m."""
        return self._objects[name].extents.copy()

    def workspace_bounds(self, name: str) -> tuple[Array, Array]:
        """Above the table by half the object's height; a generous box otherwise."""
        half = self._objects[name].extents[2] / 2.0
        return (
            np.array([0.3, -0.5, self.table_height + half]),
            np.array([1.0, 0.5, self.table_height + 0.5]),
        )

    def object_context(self, name: str) -> ObjectContext:
        """Affordance context of a box object with the present obstacles and task goals."""
        obj = self._objects[name]
        return make_object_context(
            name=name,
            category=obj.category,
            shape="box",
            dimensions=tuple(obj.extents.tolist()),
            mass_kg=obj.mass,
            material=obj.material,
            friction=obj.friction,
            fragility="robust",
            position=obj.pose.position.tolist(),
            obstacles=[
                {"name": o.name, "position": o.position.tolist(), "radius": o.radius}
                for o in self._all_obstacles.values()
            ],
            goals=[m.goal.position.tolist() for m in self._moves.get(name, ())],
        )

    def task_moves(self, name: str) -> tuple[Move, ...]:
        """Moves of ``name``."""
        return self._moves.get(name, ())

    def gravity(self) -> float:
        """m/s^2."""
        return GRAVITY

    def fixtures(self) -> tuple[FixtureInfo, ...]:
        """The fixtures given."""
        return self._fixtures

    def fixture_force(self, name: str) -> Array:
        """Spring force (contact stiffness) of each wall the object's footprint overlaps
        below the walls' tops, pushing it back inside, N; the object taken as turned with the
        fixture."""
        obj = self._objects[name]
        total = np.zeros(3)
        for f in self._fixtures:
            bottom = obj.pose.position[2] - obj.extents[2] / 2.0
            if bottom >= f.position[2] + f.wall_height:
                continue
            c, s = np.cos(f.yaw), np.sin(f.yaw)
            d = obj.pose.position[:2] - f.position[:2]
            local = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
            depth = np.abs(local) + obj.extents[:2] / 2.0 - f.inner / 2.0
            push = -np.sign(local) * self.contact_stiffness * np.maximum(depth, 0.0)
            total[:2] += np.array([c * push[0] - s * push[1], s * push[0] + c * push[1]])
        return total

    def fixture_torque(self, name: str) -> Array:
        """Zeros, N m: the fake walls' springs push through the object's centre."""
        return np.zeros(3)

    # -- WorldPort: palms --------------------------------------------------------------------
    def palm_pose(self, arm: Arm) -> Pose:
        """Where the palm is."""
        return self._palms[arm]

    def palm_twist(self, arm: Arm) -> Array:
        """The palm's twist, (6,)."""
        return self._palm_twists[arm].copy()

    def palm_target(self, arm: Arm) -> Pose:
        """The last commanded pose (reached at the next advance)."""
        return self._targets[arm]

    def rest_palm_pose(self, arm: Arm) -> Pose:
        """Parking pose."""
        return self._rest[arm]

    def palm_thickness(self) -> float:
        """m."""
        return self._palm_thickness

    def robot_capabilities(self) -> RobotCapabilities:
        """The paper's robot."""
        return PAPER_ROBOT

    def squeeze_depth(self, force_n: float) -> float:
        """m: the contact spring stands in for the controller's."""
        return force_n / self.contact_stiffness

    def command_palm(self, arm: Arm, pose: Pose, twist: Array | None = None) -> None:
        """Target for the next advance."""
        tw = np.zeros(6) if twist is None else np.asarray(twist, dtype=float)
        self._targets[arm] = pose
        self._target_twists[arm] = tw
        self.commands.append(Recorded(self._t, arm, pose, tw))

    def hold_palms(self) -> None:
        """Stop: keep the targets, zero the twists."""
        self.holds += 1
        for arm in ARMS:
            self.command_palm(arm, self._targets[arm], np.zeros(6))

    def contact_force(self, arm: Arm, name: str) -> float:
        """Spring force on the penetration of the palm into the object's face, N."""
        if name in self._dropped:
            return 0.0
        return self.contact_stiffness * max(self._penetration(arm, name), 0.0)

    def palm_load(self, arm: Arm, name: str) -> float:
        """Half the object's weight while held above its rest on the table; else 0."""
        obj = self._objects[name]
        rest_z = self.table_height + obj.extents[2] / 2.0
        if self._held[name] is None or obj.pose.position[2] <= rest_z + 1e-3:
            return 0.0
        return obj.mass * GRAVITY / 2.0

    # -- WorldPort: obstacles and collision -----------------------------------------------------
    def set_active_obstacles(self, names: Iterable[str]) -> None:
        """Exactly these obstacles are present."""
        wanted = set(names)
        unknown = wanted - set(self._all_obstacles)
        if unknown:
            raise KeyError(
                f"obstacles: expected names from {sorted(self._all_obstacles)}, "
                f"got {sorted(unknown)}"
            )
        self._active = wanted

    def obstacles(self) -> tuple[ObstacleInfo, ...]:
        """Present obstacles, by name."""
        return tuple(self._all_obstacles[n] for n in sorted(self._active))

    def _sphere_distance(self, points: Array, radius: float = 0.0) -> tuple[Array, Array]:
        obs = self.obstacles()
        if not obs:
            n = points.shape[0]
            return np.full(n, np.inf), np.zeros((n, 3))
        centres = np.array([o.position for o in obs])
        radii = np.array([o.radius for o in obs])
        diff = points[:, None, :] - centres[None]
        dist = np.linalg.norm(diff, axis=2) - radii[None] - radius
        k = np.argmin(dist, axis=1)
        rows = np.arange(points.shape[0])
        direction = (
            diff[rows, k] / np.maximum(np.linalg.norm(diff[rows, k], axis=1), 1e-12)[:, None]
        )
        closest = centres[k] + direction * radii[k][:, None]
        return dist[rows, k], closest

    def check_trajectory(
        self,
        name: str,
        object_positions: Array,
        object_orientations: Array,
        palm_positions: Array,
        palm_orientations: Array,
        margin_m: float = 0.0,
        link_doubt: bool = True,
    ) -> PathCheck:
        """The object as the box it is, the palms' bounding spheres and segments of the arms,
        vs the spheres (the arms' segments are known as surely as the palms: ``link_doubt``
        changes nothing)."""
        d_obj = self._box_distance(
            np.asarray(object_positions, dtype=float),
            np.asarray(object_orientations, dtype=float),
            self._objects[name].extents / 2.0,
        )
        return self._check_path(d_obj, np.asarray(palm_positions, dtype=float), margin_m)

    def _box_distance(self, positions: Array, orientations: Array, half: Array) -> Array:
        """(N,) least distance of a box of half extents ``half`` posed at each waypoint from
        the present obstacles' spheres, m (negative: a sphere's centre inside the box, or
        the sphere overlapping it)."""
        n = positions.shape[0]
        obs = self.obstacles()
        if not obs or n == 0:
            return np.full(n, np.inf)
        centres = np.array([o.position for o in obs])  # (K, 3)
        radii = np.array([o.radius for o in obs])
        rotation = quat.to_matrix(orientations).reshape(n, 3, 3)
        # Each sphere's centre in each waypoint's box frame: R^T (c - p), (N, K, 3).
        local = np.einsum("nji,nkj->nki", rotation, centres[None] - positions[:, None])
        outside = np.linalg.norm(np.maximum(np.abs(local) - half, 0.0), axis=-1)
        depth = np.min(half - np.abs(local), axis=-1)  # > 0 for a centre inside the box
        gap = np.where(outside > 0.0, outside, -depth) - radii[None]
        return np.asarray(gap.min(axis=1))

    def check_palm_path(
        self,
        palm_positions: Array,
        palm_orientations: Array,
        margin_m: float = 0.0,
        object_margin_m: float | None = None,
    ) -> PathCheck:
        """Segments of the arms, out to the palms, vs spheres (the obstacles only: unlike the
        simulator's, this check does not keep off the objects)."""
        n = np.asarray(palm_positions).shape[0]
        return self._check_path(
            np.full(n, np.inf), np.asarray(palm_positions, dtype=float), margin_m
        )

    def _check_path(self, d_obj: Array, palm_positions: Array, margin_m: float) -> PathCheck:
        n = palm_positions.shape[0]
        arm_pts = self._arm_points(palm_positions.reshape(n * 2, 3), np.tile([0, 1], n))
        d_arm, _ = self._sphere_distance(arm_pts.reshape(-1, 3), 0.04)
        d_arm = d_arm.reshape(n, -1).min(axis=1)
        d = np.minimum(d_obj, d_arm)
        hits = np.flatnonzero(d < margin_m)
        worst = int(np.argmin(d)) if n else 0
        what = "object" if n and d_obj[worst] <= d_arm[worst] else "arm"
        return PathCheck(
            hits.size == 0,
            float(d.min()) if n else float("inf"),
            int(hits[0]) if hits.size else None,
            f"{what} closest at waypoint {worst}: {d[worst] if n else np.inf:.3f} m",
            end_clear=bool(d[-1] >= margin_m) if n else True,
        )

    def _arm_points(self, palms: Array, arm_index: Array, per_arm: int = 4) -> Array:
        shoulders = np.array([self.shoulders[Arm.LEFT], self.shoulders[Arm.RIGHT]])[arm_index]
        s = np.linspace(0.25, 1.0, per_arm)[None, :, None]
        return shoulders[:, None, :] + s * (palms - shoulders)[:, None, :]

    def other_objects(self, name: str) -> tuple[ObstacleInfo, ...]:
        """Bounding spheres of the objects other than ``name`` where they are now."""
        return tuple(
            ObstacleInfo(n, o.pose.position.copy(), float(np.linalg.norm(o.extents) / 2.0))
            for n, o in self._objects.items()
            if n != name
        )

    def link_points(self) -> Array:
        """Four points on each arm's shoulder-palm segment, (8, 3)."""
        palms = np.array([self._palms[Arm.LEFT].position, self._palms[Arm.RIGHT].position])
        return self._arm_points(palms, np.array([0, 1])).reshape(-1, 3)

    def welded_spheres(self, arm: Arm) -> tuple[Array, Array]:
        """None: the fake arms are segments ending at their palms."""
        return np.zeros((0, 3)), np.zeros(0)

    def obstacle_gap(self, name: str, within_m: float) -> ObstacleGap | None:
        """The object box's exact gap to the nearest present obstacle sphere."""
        o = self._objects[name]
        best: ObstacleGap | None = None
        for b in self.obstacles():
            # The sphere's centre in the box frame, and the box's point nearest it.
            local = quat.rotate(quat.conjugate(o.pose.orientation), b.position - o.pose.position)
            nearest = np.clip(local, -o.extents / 2.0, o.extents / 2.0)
            out = quat.rotate(o.pose.orientation, nearest - local)
            gap = float(np.linalg.norm(out)) - b.radius
            if float(np.linalg.norm(out)) < 1e-9:  # the centre inside the box
                out = o.pose.position - b.position
            if gap < within_m and (best is None or gap < best.distance_m):
                best = ObstacleGap(gap, out / max(float(np.linalg.norm(out)), 1e-12), b.name)
        return best

    def distance_query(self, points: Array) -> tuple[Array, Array]:
        """Distance to the nearest present obstacle surface and the closest point on it."""
        return self._sphere_distance(np.asarray(points, dtype=float))

    def scene_query(self) -> SceneQuery:
        """The geometric scene query with this world's shoulders."""
        return GeometricSceneQuery(
            shoulders={arm: tuple(self.shoulders[arm].tolist()) for arm in ARMS}
        )
