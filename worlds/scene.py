"""The PyBullet scene: two palm arms behind a table, objects on it, static obstacles.

A :class:`Scene` is built from a :class:`worlds.spec.SceneSpec` (plain parameters) or from a
world (:meth:`Scene.from_world`). It owns one PyBullet client in DIRECT mode and the
:class:`worlds.control.DualArmImpedanceController` that drives the palms; :meth:`Scene.step`
applies the control torques and advances physics by one step.

Rules kept here: objects are held by friction and squeeze only (no constraints to the palms, no
teleporting or mass changes once the scene runs); obstacles are static (mass 0) and are switched
on or off per move by parking them far below the floor. A :class:`worlds.truth.PhysicalTruth`
changes the bodies as they are built (masses, frictions, the table's height) and the
actuators; :attr:`Scene.spec` stays as the world file says, :attr:`Scene.physical` is what was
built.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from duet_robot.closing import Closing
from skills.vocabulary import Arm
from worlds.bodies import (
    NoDisplayError,
    arm_link_indices,
    build_robot,
    connect,
    create_object,
    create_obstacle,
    create_table,
    load_robot,
)
from worlds.control import DualArmImpedanceController, ImpedanceGains, PalmCommand, PalmState
from worlds.disturbances import Disturbances
from worlds.fixtures import create_fixture, fixture_force, fixture_torque
from worlds.palm_ik import solve_palms
from worlds.spec import ObstacleSpec, SceneSpec, WorldSpec
from worlds.truth import PhysicalTruth, physical_scene
from worlds.world_file import World, as_world_spec

FloatArray = NDArray[np.float64]


#: Slowest rate of re-linearising the control law (Jacobian, gravity, inertia), Hz. The
#: spring and damper still act on the measured joint state at every physics step; the grasp
#: tests hold the parcel the same with these defaults and with the exact law at every step.
RELINEARISE_HZ = 10.0
#: Re-linearise sooner once a joint has moved this far from the linearisation point, rad.
RELINEARISE_TOLERANCE = 0.01

#: Where inactive obstacles wait: far below the floor, out of every contact.
PARKING_OFFSET = (0.0, 0.0, -100.0)


#: Least contact force of each palm for an object to count as held, N (the planner's IsHeld
#: default): a ``while_held`` disturbance pushes only an object held so, off its support.
HELD_FORCE_N = 2.0


class Scene(Closing):
    """A running PyBullet scene with two impedance-controlled palms.

    Parameters
    ----------
    spec : SceneSpec, optional
        What to build; default: the default robot, table and parcel, no obstacles.
    gains : ImpedanceGains, optional
        Palm impedance gains for both arms.
    refresh_every : int, optional
        Physics steps between re-linearisations of the control law (see
        :mod:`worlds.control`) at most; 1 is the exact law; default physics_hz / RELINEARISE_HZ.
    relinearise_tolerance : float
        Re-linearise sooner once a joint has moved this far, rad (0: only by the clock).
    gui : bool
        Open PyBullet's window (needs a display); DIRECT otherwise.
    truth : PhysicalTruth, optional
        How the physics differs from ``spec`` (:mod:`worlds.truth`); None: in nothing.
    """

    def __init__(
        self,
        spec: SceneSpec | None = None,
        gains: ImpedanceGains | None = None,
        refresh_every: int | None = None,
        relinearise_tolerance: float = RELINEARISE_TOLERANCE,
        gui: bool = False,
        truth: PhysicalTruth | None = None,
    ) -> None:
        self.spec = spec if spec is not None else SceneSpec()
        #: How the physics differs from :attr:`spec`.
        self.truth = truth if truth is not None else PhysicalTruth()
        #: The scene as built: :attr:`spec` with the truth's masses, frictions and heights.
        self.physical = physical_scene(self.spec, truth) if truth is not None else self.spec
        if refresh_every is None:
            refresh_every = max(1, round(self.spec.physics_hz / RELINEARISE_HZ))
        self.physics_dt = 1.0 / self.spec.physics_hz
        self.client = connect(gui)
        try:
            self._build(gains, refresh_every, relinearise_tolerance)
        except Exception:
            pb.disconnect(self.client)
            raise
        self.step_count = 0
        #: Wall time spent inside PyBullet's stepSimulation, s: the physics alone.
        self.physics_wall_s = 0.0
        #: Wall time spent computing and sending the torques (and the world's disturbances)
        #: before each step, s: the control law.
        self.control_wall_s = 0.0

    @classmethod
    def from_world(
        cls,
        world: World | WorldSpec,
        gains: ImpedanceGains | None = None,
        refresh_every: int | None = None,
        relinearise_tolerance: float = RELINEARISE_TOLERANCE,
        gui: bool = False,
        truth: PhysicalTruth | None = None,
    ) -> Scene:
        """Build the scene of a world: a :class:`worlds.spec.WorldSpec`, or a validated
        :class:`worlds.world_file.World`, converted here."""
        return cls(
            as_world_spec(world).scene,
            gains=gains,
            refresh_every=refresh_every,
            relinearise_tolerance=relinearise_tolerance,
            gui=gui,
            truth=truth,
        )

    def _build(
        self, gains: ImpedanceGains | None, refresh_every: int, relinearise_tolerance: float
    ) -> None:
        c = self.client
        pb.resetSimulation(physicsClientId=c)
        pb.setPhysicsEngineParameter(
            fixedTimeStep=self.physics_dt,
            numSubSteps=0,
            deterministicOverlappingPairs=1,
            physicsClientId=c,
        )
        pb.setGravity(0.0, 0.0, self.spec.gravity, physicsClientId=c)
        floor = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=c)
        self.floor_id = pb.createMultiBody(0.0, floor, physicsClientId=c)

        self.robot = build_robot(self.spec.robot)
        self.robot_ids = load_robot(c, self.robot)
        #: Each arm's links on its body, None where the arm has its body to itself
        #: (:func:`worlds.bodies.arm_link_indices`).
        self.arm_links = arm_link_indices(c, self.robot, self.robot_ids)
        if self.truth.palm_friction_scale != 1.0:
            self._scale_palm_friction(self.truth.palm_friction_scale)
        self.table_id = create_table(c, self.physical.table)
        self.object_ids = {obj.name: create_object(c, obj) for obj in self.physical.objects}
        self.obstacle_ids = {
            o.name: create_obstacle(c, o, self._parking(o)) for o in self.spec.obstacles
        }
        self._active_obstacles: set[str] = set()
        #: The fixtures' bodies, by name (always present: :mod:`worlds.fixtures`).
        self.fixture_ids = {f.name: create_fixture(c, f) for f in self.physical.fixtures}
        self.disturbances = Disturbances(
            c, self.spec.disturbances, self.object_ids, self.spec.physics_hz, self.is_carried
        )

        self.controller = DualArmImpedanceController(
            self.robot,
            self.robot_ids,
            self.physics_dt,
            client=c,
            gains=gains
            if gains is not None
            else replace(ImpedanceGains(), **self.robot.gain_overrides),
            refresh_every=refresh_every,
            relinearise_tolerance=relinearise_tolerance,
            faults=self.truth.actuators,
        )
        self.controller.enable()

    def _scale_palm_friction(self, scale: float) -> None:
        """Multiply each palm's friction coefficient, as its robot model gives it, by ``scale``."""
        for arm in (Arm.LEFT, Arm.RIGHT):
            spec = self.robot.arms[arm]
            body = self.robot_ids[spec.body]
            model = pb.getDynamicsInfo(body, spec.palm_link, physicsClientId=self.client)[1]
            pb.changeDynamics(
                body, spec.palm_link, lateralFriction=model * scale, physicsClientId=self.client
            )

    # -- setup -------------------------------------------------------------------------------

    @staticmethod
    def _parking(obstacle: ObstacleSpec) -> list[float]:
        return [p + o for p, o in zip(obstacle.position, PARKING_OFFSET, strict=True)]

    @property
    def active_obstacles(self) -> frozenset[str]:
        """Names of the obstacles present now."""
        return frozenset(self._active_obstacles)

    def set_active_obstacles(self, names: Iterable[str]) -> None:
        """Make exactly ``names`` present (scene setup between moves; they are static).

        Raises
        ------
        ValueError
            If a name is not an obstacle of the scene.
        """
        wanted = set(names)
        unknown = sorted(wanted - set(self.obstacle_ids))
        if unknown:
            raise ValueError(
                "set_active_obstacles: expected names in "
                f"{sorted(self.obstacle_ids)}, got {unknown}"
            )
        for obstacle in self.spec.obstacles:
            active = obstacle.name in wanted
            if active == (obstacle.name in self._active_obstacles):
                continue
            position = list(obstacle.position) if active else self._parking(obstacle)
            pb.resetBasePositionAndOrientation(
                self.obstacle_ids[obstacle.name],
                position,
                [0, 0, 0, 1],
                physicsClientId=self.client,
            )
        self._active_obstacles = wanted

    def obstacle_overlaps(self, clearance: float = 0.0) -> dict[str, list[str]]:
        """Bodies within ``clearance`` of each active obstacle (m); empty lists when clear.

        An obstacle switched on while it overlaps the robot or an object would push them out
        violently on the next step; check this after :meth:`set_active_obstacles`.

        Returns
        -------
        dict of str to list of str
            For each active obstacle, the names of the objects, ``"table"``, ``"left_arm"`` or
            ``"right_arm"`` it overlaps or comes within ``clearance`` of.
        """
        others: dict[str, tuple[int, frozenset[int] | None]] = {
            name: (body, None) for name, body in self.object_ids.items()
        }
        others["table"] = (self.table_id, None)
        for arm in (Arm.LEFT, Arm.RIGHT):
            others[f"{arm.value}_arm"] = (
                self.robot_ids[self.robot.arms[arm].body],
                self.arm_links[arm],
            )
        overlaps: dict[str, list[str]] = {}
        for name in sorted(self._active_obstacles):
            body = self.obstacle_ids[name]
            overlaps[name] = [
                other
                for other, (other_body, links) in others.items()
                if any(
                    links is None or p[4] in links
                    for p in pb.getClosestPoints(
                        body, other_body, clearance, physicsClientId=self.client
                    )
                )
            ]
        return overlaps

    def place_palms(
        self, palm2world: Mapping[Arm, tuple[ArrayLike, ArrayLike]]
    ) -> dict[Arm, FloatArray]:
        """Set the start posture: one inverse-kinematics solve per arm, before the run starts
        (one for both where they share a body: :func:`worlds.palm_ik.solve_palms`).

        The arms are reset to the solutions, which also become the arms' null-space rest
        postures (shared joints keep theirs: a torso stays pulled upright), and the palm
        commands are set to the requested poses.

        Parameters
        ----------
        palm2world : mapping of Arm to (position (3,), quaternion (4,))
            Start palm poses in the world frame (m, scalar-last quaternion).

        Returns
        -------
        dict of Arm to ndarray
            (n,) joint positions of each arm, rad.

        Raises
        ------
        RuntimeError
            If the scene has already been stepped.
        """
        if self.step_count:
            raise RuntimeError("place_palms: the start posture can only be set before stepping")
        solutions: dict[Arm, FloatArray] = {}
        wanted = {Arm(arm): pose for arm, pose in palm2world.items()}
        for arm in [a for a in wanted if self._shares_body(a)]:
            if arm not in solutions:
                solutions.update(self._place_palms_on_shared_body(arm, wanted))
        for arm, (position, quaternion) in wanted.items():
            if arm in solutions:
                continue
            spec = self.robot.arms[arm]
            body = self.robot_ids[spec.body]
            ranges = [hi - lo for lo, hi in zip(spec.lower, spec.upper, strict=True)]
            q_all = pb.calculateInverseKinematics(
                body,
                spec.palm_link,
                list(np.asarray(position, dtype=float)),
                list(np.asarray(quaternion, dtype=float)),
                lowerLimits=list(spec.lower),
                upperLimits=list(spec.upper),
                jointRanges=ranges,
                restPoses=list(spec.rest_posture),
                maxNumIterations=200,
                residualThreshold=1e-6,
                physicsClientId=self.client,
            )
            movable = [
                j
                for j in range(pb.getNumJoints(body, physicsClientId=self.client))
                if pb.getJointInfo(body, j, physicsClientId=self.client)[2] != pb.JOINT_FIXED
            ]
            q = np.array([q_all[movable.index(j)] for j in spec.joint_indices])
            for joint, value in zip(spec.joint_indices, q, strict=True):
                pb.resetJointState(body, joint, float(value), 0.0, physicsClientId=self.client)
            solutions[arm] = q
        for arm, (position, quaternion) in wanted.items():
            self.controller.set_rest_posture(arm, solutions[arm])
            self.controller.set_command(
                arm, PalmCommand(np.asarray(position, float), np.asarray(quaternion, float))
            )
        self.controller.refresh()
        return solutions

    def _shares_body(self, arm: Arm) -> bool:
        body = self.robot.arms[arm].body
        return sum(spec.body == body for spec in self.robot.arms.values()) > 1

    def _place_palms_on_shared_body(
        self, arm: Arm, wanted: Mapping[Arm, tuple[ArrayLike, ArrayLike]]
    ) -> dict[Arm, FloatArray]:
        """Solve every palm on ``arm``'s body at once (:func:`worlds.palm_ik.solve_palms`): the
        palms asked for go to their poses, the others stay where they are; returns the arm
        joints (n,) of each arm on the body."""
        index = self.robot.arms[arm].body
        body = self.robot_ids[index]
        driven = [d for d in self.robot.driven_joints() if d.body == index]
        arms = [a for a in Arm if self.robot.arms[a].body == index]
        c = self.client
        joints = [d.joint for d in driven]
        q0 = np.array([s[0] for s in pb.getJointStates(body, joints, physicsClientId=c)])
        targets = []
        for a in arms:
            if a in wanted:
                position, quaternion = wanted[a]
                targets.append((np.asarray(position, float), np.asarray(quaternion, float)))
            else:
                state = self.controller.palm_state(a)
                targets.append((state.position, state.quaternion))
        q = solve_palms(
            c,
            body,
            joints,
            [self.robot.arms[a].palm_link for a in arms],
            targets,
            q0,
            np.array([d.lower for d in driven]),
            np.array([d.upper for d in driven]),
            np.array([d.rest for d in driven]),
            np.array([self.robot.ik_cost(d) for d in driven]),
        )
        return {
            a: np.array([v for v, d in zip(q, driven, strict=True) if d.arm is a]) for a in arms
        }

    # -- running -----------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulated time since the start, s."""
        return self.step_count * self.physics_dt

    def step(self, steps: int = 1) -> None:
        """Apply the palm control torques and the world's disturbances
        (:class:`worlds.disturbances.Disturbances`), and advance physics, ``steps`` times."""
        apply = self.controller.apply
        disturb = self.disturbances.apply if self.disturbances else None
        step = pb.stepSimulation
        clock = time.perf_counter
        c = self.client
        spent = control = 0.0
        for i in range(steps):
            began = clock()
            apply()
            if disturb is not None:
                disturb(self.step_count + i)
            started = clock()
            step(physicsClientId=c)
            ended = clock()
            control += started - began
            spent += ended - started
        self.step_count += steps
        self.physics_wall_s += spent
        self.control_wall_s += control

    def set_palm_command(self, arm: Arm, command: PalmCommand) -> None:
        """Set the target pose (and feed-forward twist, squeeze offset) of ``arm``'s palm."""
        self.controller.set_command(arm, command)

    def palm_state(self, arm: Arm) -> PalmState:
        """Measured palm pose, twist and joint state of ``arm``, world frame."""
        return self.controller.palm_state(arm)

    def palm_motion(self, arm: Arm) -> tuple[FloatArray, FloatArray]:
        """Measured palm position (3,) m and linear velocity (3,) m/s of ``arm``, world frame."""
        return self.controller.palm_motion(arm)

    def object_pose(self, name: str) -> tuple[FloatArray, FloatArray]:
        """Pose of object ``name``: position (3,) m and quaternion (4,) scalar-last, world frame."""
        position, quaternion = pb.getBasePositionAndOrientation(
            self._object(name), physicsClientId=self.client
        )
        return np.asarray(position), np.asarray(quaternion)

    def object_velocity(self, name: str) -> tuple[FloatArray, FloatArray]:
        """Linear (3,) m/s and angular (3,) rad/s velocity of object ``name``, world frame."""
        linear, angular = pb.getBaseVelocity(self._object(name), physicsClientId=self.client)
        return np.asarray(linear), np.asarray(angular)

    def is_held(self, name: str, min_force_n: float = HELD_FORCE_N) -> bool:
        """Both palms press on object ``name`` with at least ``min_force_n`` N each."""
        return all(self.palm_contact_force(arm, name) >= min_force_n for arm in Arm)

    def is_carried(self, name: str, min_force_n: float = HELD_FORCE_N) -> bool:
        """Object ``name`` is held (:meth:`is_held`) and off its support: it touches nothing
        but the robot and other objects (no table, obstacle or fixture). A box the palms have
        just set down and are letting go of is held, not carried."""
        if not self.is_held(name, min_force_n):
            return False
        ours = {*self.robot_ids, *self.object_ids.values()}
        contacts = pb.getContactPoints(bodyA=self._object(name), physicsClientId=self.client)
        return all(c[2] in ours for c in contacts)

    def palm_contact_force(self, arm: Arm, name: str) -> float:
        """Sum of contact normal forces between ``arm``'s palm and object ``name``, N.

        The scene runs without physics substeps, so these are the full forces (with substeps
        PyBullet reports about 1/N of them).
        """
        return float(sum(c[9] for c in self._palm_contacts(arm, name)))

    def palm_load(self, arm: Arm, name: str) -> float:
        """Upward (world +z) force of ``arm``'s palm on object ``name``, normal and friction,
        N."""
        contacts = self._palm_contacts(arm, name)
        # PyBullet's normal points from the object (B) to the palm (A): the solver pushes A
        # along it and along the friction directions, and the object the opposite way
        # (checked: a lifted box's two loads sum to its weight). With a compound object (a
        # tray's floor and walls) PyBullet turns the normal to the asked order but leaves the
        # friction in the order Bullet's compound algorithm swapped the pair into (checked: a
        # lifted tray's two loads summed to minus its weight), so the friction's sign flips.
        friction_sign = -1.0 if self._compound(name) else 1.0
        return -float(
            sum(
                c[9] * c[7][2] + friction_sign * (c[10] * c[11][2] + c[12] * c[13][2])
                for c in contacts
            )
        )

    def _compound(self, name: str) -> bool:
        """Whether object ``name``'s collision shape is a compound of several shapes."""
        body = self._object(name)
        return len(pb.getCollisionShapeData(body, -1, physicsClientId=self.client)) > 1

    def _palm_contacts(self, arm: Arm, name: str) -> tuple[Any, ...]:
        """PyBullet's contact points of ``arm``'s palm (body A) with object ``name`` (body B)."""
        spec = self.robot.arms[Arm(arm)]
        return tuple(
            pb.getContactPoints(
                bodyA=self.robot_ids[spec.body],
                bodyB=self._object(name),
                linkIndexA=spec.palm_link,
                physicsClientId=self.client,
            )
        )

    def fixture_force(self, fixture: str, name: str) -> FloatArray:
        """Force (3,) N, world frame, that fixture ``fixture`` exerts on object ``name``."""
        force = fixture_force(self.client, self.fixture_ids[fixture], self._object(name))
        return np.asarray(force, dtype=np.float64)

    def fixture_torque(self, fixture: str, name: str) -> FloatArray:
        """Torque (3,) N m, world frame, that fixture ``fixture`` exerts on object ``name``
        about the object's centre."""
        body = self._object(name)
        centre = self.object_pose(name)[0]
        torque = fixture_torque(self.client, self.fixture_ids[fixture], body, centre)
        return np.asarray(torque, dtype=np.float64)

    def arm_contact_force(self, arm: Arm, body_id: int) -> float:
        """Sum of contact normal forces between any link of ``arm``'s body and a body, N."""
        spec = self.robot.arms[Arm(arm)]
        contacts = pb.getContactPoints(
            bodyA=self.robot_ids[spec.body], bodyB=body_id, physicsClientId=self.client
        )
        return float(sum(c[9] for c in contacts))

    def _object(self, name: str) -> int:
        try:
            return self.object_ids[name]
        except KeyError:
            raise ValueError(
                f"Scene: expected an object name in {sorted(self.object_ids)}, got {name!r}"
            ) from None

    def state_vector(self) -> FloatArray:
        """Every joint position and velocity and every object's pose and twist, flat (k,)."""
        parts: list[FloatArray] = []
        for body in self.robot_ids:
            n = pb.getNumJoints(body, physicsClientId=self.client)
            states = pb.getJointStates(body, list(range(n)), physicsClientId=self.client)
            parts.append(np.array([[s[0], s[1]] for s in states]).ravel())
        for name in self.object_ids:
            position, quaternion = self.object_pose(name)
            linear, angular = self.object_velocity(name)
            parts.extend([position, quaternion, linear, angular])
        return np.concatenate(parts)

    def close(self) -> None:
        """Disconnect the PyBullet client."""
        if self.client >= 0 and pb.isConnected(self.client):
            pb.disconnect(self.client)
        self.client = -1


# NoDisplayError is re-exported: the command line catches it from here.
__all__ = [
    "RELINEARISE_HZ",
    "RELINEARISE_TOLERANCE",
    "NoDisplayError",
    "Scene",
]
