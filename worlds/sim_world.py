"""The simulated world behind the planner's port: PyBullet scene, FCL mirror, safety monitor.

:class:`SimWorld` satisfies :class:`planner.port.WorldPort`. Between control ticks it steps
physics at the world file's rate and has a :class:`worlds.safety_monitor.SafetyMonitor` watch
what a trial is judged on: contacts between any robot link or the parcel and an obstacle
(PyBullet, every physics step), the arms touching each other, the smallest FCL distance to an
obstacle, and the parcel falling.

Given a :class:`worlds.truth.PhysicalTruth`, the physics follows it while the port still
answers from the world file (masses, frictions, the table), and :meth:`SimWorld.object_pose`
reports each object where the robot senses it: off by the truth's perception error until the
object is first held in both palms (:data:`LOCATED_BY_GRASP_N`), where it is from then on.
The safety monitor and the judge read the physics.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence
from dataclasses import replace

import numpy as np
import pybullet as pb

from affordances import ObjectContext, RobotCapabilities, SceneQuery
from affordances.scene import GeometricSceneQuery
from duet_robot.closing import Closing
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
from skills.level_carry import LooseBall
from skills.turns import Hold
from skills.types import Array
from skills.vocabulary import ARMS, Arm
from worlds.adapters import object_contexts, robot_capabilities
from worlds.collision import CollisionWorld
from worlds.control import ImpedanceGains, PalmCommand
from worlds.fixtures import FixtureLog
from worlds.palm_poses import rest_palm_poses
from worlds.path_checks import PathChecks
from worlds.safety_monitor import SafetyMonitor, SafetyRecord
from worlds.scene import Scene
from worlds.spec import WorldSpec
from worlds.trays import TrayFrame, riders
from worlds.truth import PhysicalTruth, sensed_pose
from worlds.turn_choice import turn_places
from worlds.world_file import World, as_world_spec

#: Highest an object's centre may be carried above the table top, m.
MAX_LIFT_M = 0.30
#: Contact force each palm must press an object with, N, for the grasp to locate it: from the
#: first control tick it does, the object is sensed where it is.
LOCATED_BY_GRASP_N = 0.5


def task_moves(
    spec: WorldSpec, name: str, places: Sequence[Array | None] | None = None
) -> tuple[Move, ...]:
    """The world's moves for object ``name``, each turn split into the steps the robot's grip
    can make (:func:`planner.port.stepped_moves`; ``Move.task_move`` names the file's move of
    each, and ``Move.final`` its last step), each move's turn made at its place in ``places``
    (default: every one at its goal)."""
    obj = next(o for o in spec.scene.objects if o.name == name)
    return stepped_moves(
        (
            Move(
                Pose.of(m.goal_position, m.goal_quaternion),
                m.obstacles,
                skill=m.skill,
                fixture=m.fixture,
            )
            for m in spec.moves_of(name)
        ),
        obj.yaw,
        robot_capabilities(spec).max_turn_rad,
        math.radians(spec.scene.robot.base_rpy_deg[2]),
        places,
    )


class SimWorld(Closing):
    """A world file brought to life in PyBullet, behind the planner's port.

    Parameters
    ----------
    world : WorldSpec or World
        The world; a validated world file is converted here, once.
    object_name : str, optional
        The one object the monitor watches for drops; default: every object of the task.
    gains : ImpedanceGains, optional
        Palm impedance gains.
    gui : bool
        Show PyBullet's window.
    truth : PhysicalTruth, optional
        How the physics differs from the world (:mod:`worlds.truth`); None: in nothing.
    """

    def __init__(
        self,
        world: World | WorldSpec,
        object_name: str | None = None,
        gains: ImpedanceGains | None = None,
        gui: bool = False,
        truth: PhysicalTruth | None = None,
    ) -> None:
        self.spec = spec = as_world_spec(world)
        self.scene = Scene(spec.scene, gains=gains, gui=gui, truth=truth)
        #: The objects still sensed off where they are (none are held yet).
        self._unlocated: tuple[str, ...] = tuple(
            o.name for o in spec.scene.objects if self.scene.truth.of(o.name).sensed_offset
        )
        self.gains = self.scene.controller.gains(Arm.LEFT)
        #: Wall time spent advancing, s: the physics steps, the control law before each
        #: (the scene's ``physics_wall_s`` and ``control_wall_s``) and the safety watch.
        self.advance_wall_s = 0.0
        self.collision = CollisionWorld(self.scene)
        # What is welded to each palm, in the palm frame: constant, so read once, here.
        self._welded = {
            arm: self.collision.welded_spheres(
                arm, self.scene.palm_state(arm).position, self.scene.palm_state(arm).quaternion
            )
            for arm in ARMS
        }
        self._task_moves: dict[str, tuple[Move, ...]] = {}
        task_objects = tuple(dict.fromkeys(step.object for step in spec.task))
        self.watched: tuple[str, ...] = (
            (object_name,) if object_name else task_objects or (spec.scene.objects[0].name,)
        )
        self._rest = self._rest_poses()
        self.scene.place_palms({a: (p.position, p.orientation) for a, p in self._rest.items()})
        self._commands: dict[Arm, Pose] = dict(self._rest)
        self._contexts = {c.name: self._sensed_context(c) for c in object_contexts(spec)}
        self._extents = {
            o.name: np.asarray(o.shape.extents(), dtype=float) for o in self.scene.spec.objects
        }
        #: Predicted paths and holds checked against the obstacles (:mod:`worlds.path_checks`).
        self.paths = PathChecks(self.scene, self.collision, self._extents, task_objects)
        self._obstacle_info = {
            o.name: ObstacleInfo(o.name, np.asarray(o.position, float), o.shape.bounding_radius())
            for o in self.scene.spec.obstacles
        }
        self._substeps = max(1, round(spec.scene.physics_hz / spec.scene.control_hz))
        #: What the run is judged on, watched as the physics runs (:mod:`worlds.safety_monitor`).
        self.monitor = SafetyMonitor(self.scene, self.collision, self.watched)
        self.safety: SafetyRecord = self.monitor.record
        self.fixture_log: FixtureLog = self.monitor.fixture_log
        self._fixture_info = tuple(
            FixtureInfo(
                f.name,
                f.for_object,
                np.asarray(f.position, float),
                float(f.yaw),
                np.asarray(f.inner, float),
                float(f.wall_height),
            )
            for f in spec.scene.fixtures
        )
        self.collision.sync()

    def _sensed_context(self, context: ObjectContext) -> ObjectContext:
        """The reasoner's context with the object's start pose as the robot senses it (its
        mass, friction and the rest as the world file says)."""
        if context.name not in self._unlocated:
            return context
        pose = self.object_pose(context.name)
        truth = self.scene.truth.of(context.name)
        x, y, z = (float(v) for v in pose.position)
        return replace(context, position=(x, y, z), yaw=context.yaw + truth.sensed_yaw_offset_rad)

    def _rest_poses(self) -> dict[Arm, Pose]:
        """Palms waiting above the table's near edge, outside the objects, facing inwards
        (:func:`worlds.palm_poses.rest_palm_poses`, in the robot's frame)."""
        poses = rest_palm_poses(self.spec.scene, self.scene.robot.rest_palms)
        return {arm: Pose.of(position, q) for arm, (position, q) in poses.items()}

    def close(self) -> None:
        """Disconnect PyBullet (and the arms' kinematic copy, if one was built)."""
        self.paths.close()
        self.scene.close()

    # -- time --------------------------------------------------------------------------------
    def time(self) -> float:
        """Simulated time, s."""
        return self.scene.time

    def advance(self, dt: float) -> None:
        """Step physics for ``dt`` (whole physics steps), watching contacts every step."""
        began = time.perf_counter()
        steps = max(1, round(dt / self.scene.physics_dt))
        for _ in range(steps):
            self.scene.step(1)
            self.monitor.after_physics_step()
        self.collision.sync()
        self.monitor.after_control_step()
        if self._unlocated:
            self._locate_held()
        self.advance_wall_s += time.perf_counter() - began

    def watch_wall_s(self) -> float:
        """Wall time spent watching the contacts, clearances and drops while advancing, s:
        :attr:`advance_wall_s` less the physics and the control law."""
        scene = self.scene
        return max(0.0, self.advance_wall_s - scene.physics_wall_s - scene.control_wall_s)

    def _locate_held(self) -> None:
        """Sense where they are the objects both palms now press (:data:`LOCATED_BY_GRASP_N`)."""
        self._unlocated = tuple(
            name for name in self._unlocated if not self.scene.is_held(name, LOCATED_BY_GRASP_N)
        )

    # -- objects and task --------------------------------------------------------------------
    def object_pose(self, name: str) -> Pose:
        """Sensed pose of an object's centre: measured, off by the truth's perception error
        until the object is first held."""
        p, q = self.scene.object_pose(name)
        if name in self._unlocated:
            p, q = sensed_pose(p, q, self.scene.truth.of(name))
        return Pose(p, q)

    def object_twist(self, name: str) -> Array:
        """Measured twist of an object's centre, (6,)."""
        v, w = self.scene.object_velocity(name)
        return np.concatenate((v, w))

    def loose_balls(self, name: str) -> tuple[LooseBall, ...]:
        """The balls riding loose on ``name`` at the start (:func:`worlds.trays.riders`)."""
        objects = self.scene.spec.objects
        on = riders(objects, name, self.watched)
        if not on:
            return ()
        inside = TrayFrame.of(next(o for o in objects if o.name == name).shape)
        return tuple(inside.loose_ball(o.shape.radius) for o in on)

    def object_extents(self, name: str) -> Array:
        """Bounding-box extents (3,), m."""
        return self._extents[name].copy()

    def workspace_bounds(self, name: str) -> tuple[Array, Array]:
        """Centre bounds: over the table top by half the object's height, over its footprint,
        at most ``MAX_LIFT_M`` above the table (higher lifts bring the forearms up to the
        obstacles the object avoids)."""
        t = self.spec.scene.table
        half = self._extents[name] / 2.0
        top = t.position[2]
        lower = np.array(
            [t.position[0] - t.size[0] / 2.0, t.position[1] - t.size[1] / 2.0, top + half[2]]
        )
        upper = np.array(
            [t.position[0] + t.size[0] / 2.0, t.position[1] + t.size[1] / 2.0, top + MAX_LIFT_M]
        )
        return lower, upper

    def object_context(self, name: str) -> ObjectContext:
        """The object's affordance context (from the world file)."""
        return self._contexts[name]

    def robot_capabilities(self) -> RobotCapabilities:
        """The world's robot for the reasoner."""
        return robot_capabilities(self.spec)

    def task_moves(self, name: str) -> tuple[Move, ...]:
        """The world file's moves for ``name`` as the robot makes them (:func:`task_moves`),
        each turn made where the robot holding the object keeps clear of the move's obstacles
        (:func:`worlds.turn_choice.turn_places`); chosen at the first call, kept after."""
        moves = self._task_moves.get(name)
        if moves is None:
            places = turn_places(self.spec, name, self.paths.holds_clear)
            moves = self._task_moves[name] = task_moves(self.spec, name, places)
        return moves

    def hold_touches(self, name: str, obstacles: Sequence[str], hold: Hold) -> dict[str, str]:
        """What of the robot holding ``name`` in ``hold`` touches each of ``obstacles``
        (:meth:`worlds.path_checks.PathChecks.hold_touches`)."""
        return self.paths.hold_touches(name, obstacles, hold)

    def gravity(self) -> float:
        """Magnitude of the scene's gravity, m/s^2."""
        return abs(float(self.scene.spec.gravity))

    def fixtures(self) -> tuple[FixtureInfo, ...]:
        """The world's fixtures, each with the object its task moves seat in it."""
        return self._fixture_info

    def fixture_force(self, name: str) -> Array:
        """Force (3,) of all fixtures on object ``name``, N, world frame."""
        total = np.zeros(3)
        for fixture in self.scene.fixture_ids:
            total += self.scene.fixture_force(fixture, name)
        return total

    def fixture_torque(self, name: str) -> Array:
        """Torque (3,) of all fixtures on object ``name`` about its centre, N m, world frame."""
        total = np.zeros(3)
        for fixture in self.scene.fixture_ids:
            total += self.scene.fixture_torque(fixture, name)
        return total

    # -- palms -------------------------------------------------------------------------------
    def palm_pose(self, arm: Arm) -> Pose:
        """Measured palm pose."""
        st = self.scene.palm_state(arm)
        return Pose(st.position, st.quaternion)

    def palm_twist(self, arm: Arm) -> Array:
        """Measured palm twist, (6,)."""
        st = self.scene.palm_state(arm)
        return np.concatenate((st.linear_velocity, st.angular_velocity))

    def rest_palm_pose(self, arm: Arm) -> Pose:
        """Where the palm started and returns to."""
        return self._rest[arm]

    def palm_thickness(self) -> float:
        """m."""
        return float(self.spec.scene.robot.palm_size[2])

    def squeeze_depth(self, force_n: float) -> float:
        """Depth inside a face that the impedance controller's translational stiffness turns
        into ``force_n`` N of squeeze, m."""
        return force_n / float(self.gains.stiffness_linear)

    def palm_target(self, arm: Arm) -> Pose:
        """The pose the palm's impedance controller tracks (the last command)."""
        return self._commands[arm]

    def command_palm(self, arm: Arm, pose: Pose, twist: Array | None = None) -> None:
        """Track ``pose`` with feed-forward ``twist`` (impedance control)."""
        tw = np.zeros(6) if twist is None else np.asarray(twist, dtype=float)
        self._commands[arm] = pose
        self.scene.set_palm_command(
            arm,
            PalmCommand(
                np.asarray(pose.position, dtype=np.float64),
                np.asarray(pose.orientation, dtype=np.float64),
                np.asarray(tw[:3], dtype=np.float64),
                np.asarray(tw[3:], dtype=np.float64),
            ),
        )

    def arm_joints(self, arm: Arm) -> Array:
        """Measured joint positions of ``arm``, rad, (n,)."""
        return self.scene.controller.arm_joint_positions(arm)

    def rest_joints(self, arm: Arm) -> Array:
        """``arm``'s joints with its palm at its rest pose (its posture target), rad."""
        return self.scene.controller.arm_rest_posture(arm)

    def command_joints(self, arm: Arm, q: Array) -> None:
        """Hold ``arm``'s joints at ``q`` in joint space until its next :meth:`command_palm`
        (:meth:`worlds.control.DualArmImpedanceController.set_joint_target`)."""
        self.scene.controller.set_joint_target(arm, q)

    def hold_palms(self) -> None:
        """Hold the last commanded poses with zero twist."""
        for arm in ARMS:
            self.command_palm(arm, self._commands[arm], np.zeros(6))

    def contact_force(self, arm: Arm, name: str) -> float:
        """Palm-object normal force, N."""
        return self.scene.palm_contact_force(arm, name)

    def palm_load(self, arm: Arm, name: str) -> float:
        """Upward force of a palm on an object, N (:meth:`worlds.scene.Scene.palm_load`)."""
        return self.scene.palm_load(arm, name)

    # -- obstacles and collision -------------------------------------------------------------
    def set_active_obstacles(self, names: Iterable[str]) -> None:
        """Exactly these obstacles are present (placed between moves, while nothing touches).

        One switched on inside an object or an arm is recorded in
        ``safety.spawned_inside``: the run's verdict names it, instead of what it causes.
        """
        wanted = set(names)
        new = wanted - self.scene.active_obstacles
        self.scene.set_active_obstacles(wanted)
        self.collision.sync()
        if new:
            for obstacle, bodies in self.scene.obstacle_overlaps().items():
                inside = [b for b in bodies if b != "table"]
                if obstacle in new and inside:
                    self.safety.spawned_inside.setdefault(obstacle, inside)

    def obstacles(self) -> tuple[ObstacleInfo, ...]:
        """The active obstacles."""
        return tuple(self._obstacle_info[n] for n in sorted(self.scene.active_obstacles))

    def other_objects(self, name: str) -> tuple[ObstacleInfo, ...]:
        """Bounding spheres of the objects other than ``name`` where they are sensed now."""
        return tuple(
            ObstacleInfo(
                o.name,
                self.object_pose(o.name).position,
                float(np.linalg.norm(self._extents[o.name]) / 2.0),
            )
            for o in self.scene.spec.objects
            if o.name != name
        )

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
        """FCL check of predicted palm and held-object poses, and of the arm links posed by
        inverse kinematics of the palms' path (:mod:`worlds.arm_prediction`), against the
        active obstacles; the links are asked :func:`forearm_doubt` beyond ``margin_m`` unless
        ``link_doubt`` is False. The other objects are not checked against: a carry refused for
        touching one would fall back to the careful carry, which steers around the obstacles
        alone and shoves the object harder (``bench/worlds/two_parcels_turned.yaml``, move 0:
        10 cm against 6 mm)."""
        return self.paths.check(
            palm_positions,
            palm_orientations,
            margin_m,
            (name, np.asarray(object_positions), np.asarray(object_orientations)),
            link_doubt=link_doubt,
        )

    def check_palm_path(
        self,
        palm_positions: Array,
        palm_orientations: Array,
        margin_m: float = 0.0,
        object_margin_m: float | None = None,
    ) -> PathCheck:
        """FCL check of predicted poses of empty palms and of the arm links that follow them,
        against the active obstacles and the objects where they rest (as
        :meth:`check_trajectory`, without a held object).

        The palms and links keep ``object_margin_m`` (``margin_m`` when None) from the objects
        too (the forearms' doubt is for the obstacles): a way back passing 3 mm over a corner
        of the object just placed, followed by a palm slowed by Hard mode's actuator lag, slid
        it 2.7 cm (iiwas, Hard trial 10); a way in to a grasp, which must come near its object,
        asks only that they do not touch it (0): one sweeping a hand through the object
        knocked it off the table (iCub, Hard trial 114). One touching an object at the path's
        start (it has just let it go) is free of it, and one starting nearer than the margin
        may keep that gap (:meth:`worlds.collision.CollisionWorld.check_trajectory`)."""
        objects_m = margin_m if object_margin_m is None else object_margin_m
        return self.paths.check(palm_positions, palm_orientations, margin_m, None, objects_m)

    def link_points(self) -> Array:
        """For each arm link, its point closest to an active obstacle, (M, 3) (none if none)."""
        pts = []
        for arm in ARMS:
            ld = self.collision.link_distances(arm)
            ok = np.isfinite(ld.distances)
            moving = self.scene.robot.arm_link_names.get(arm)
            if moving is not None:
                # A body that carries more than the arm (iCub's trunk with the left arm): the
                # trunk's links are not the arm's to move away, so they are left out of
                # avoidance (the palm's element is "palm", whatever its link's name).
                ok &= np.array(
                    [name.split("/", 1)[-1] in moving | {"palm"} for name in ld.links],
                    dtype=bool,
                )
            pts.append(ld.link_points[ok])
        return np.concatenate(pts) if pts else np.zeros((0, 3))

    def welded_spheres(self, arm: Arm) -> tuple[Array, Array]:
        """Bounding spheres of the links welded to ``arm``'s palm, palm frame (constant)."""
        centres, radii = self._welded[arm]
        return centres.copy(), radii.copy()

    def obstacle_gap(self, name: str, within_m: float) -> ObstacleGap | None:
        """Object ``name``'s FCL gap to the nearest active obstacle, where the collision world
        last synced it (every control step), when under ``within_m`` m."""
        prox = self.collision.object_closer_than(name, within_m)
        if prox is None:
            return None
        away = prox.point_a - prox.point_b
        norm = float(np.linalg.norm(away))
        if prox.distance <= 0.0 or norm < 1e-6:
            # Touching or inside: FCL's witness points say little; from the obstacle's centre.
            away = self.object_pose(name).position - self._obstacle_info[prox.element_b].position
            norm = float(np.linalg.norm(away))
        return ObstacleGap(prox.distance, away / max(norm, 1e-12), prox.element_b)

    def distance_query(self, points: Array) -> tuple[Array, Array]:
        """Distance (N,) from points (N, 3) to the nearest active obstacle, closest points."""
        return self.collision.query(points)

    def scene_query(self) -> SceneQuery:
        """Arms as shoulder-to-palm segments for the reasoner's scene rules."""
        shoulders = {}
        for arm in ARMS:
            spec = self.scene.robot.arms[arm]
            if self.scene.robot.shoulder_at_first_joint:
                # The first arm joint's link (the shoulder) of each arm's body.
                body_id = self.scene.robot_ids[spec.body]
                link = pb.getLinkState(
                    body_id, spec.joint_indices[0], physicsClientId=self.scene.client
                )
                x, y, z = (float(v) for v in link[4])
                shoulders[arm] = (x, y, z)
                continue
            body = self.scene.robot.bodies[spec.body]
            base = np.asarray(body.base2world_position, dtype=float)
            shoulders[arm] = tuple((base + np.array([0.0, 0.0, 0.36])).tolist())
        return GeometricSceneQuery(shoulders=shoulders, hands=dict(self._welded))

    # -- reporting ---------------------------------------------------------------------------
    def palm_quaternion(self, arm: Arm) -> Array:
        """Measured palm orientation (4,)."""
        return self.scene.palm_state(arm).quaternion

    def object_tilt_deg(self, name: str) -> float:
        """Angle between the object's z axis and the world's, degrees."""
        _, q = self.scene.object_pose(name)
        return float(np.degrees(quat.tilt(q)))
