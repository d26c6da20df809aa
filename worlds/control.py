"""The impedance controller: torque control of both palms of a robot loaded in PyBullet.

:class:`DualArmImpedanceController` reads the joint state, re-linearises the law of
:mod:`worlds.impedance` (Jacobian, gravity, inertia from PyBullet), adds the joint-limit
repulsion, clips to the torque limits and sends the torques with TORQUE_CONTROL, through the
actuators' faults (:mod:`worlds.actuators`) when it is given any.

Quaternions are scalar-last (x, y, z, w); twists are (linear, angular) in the world frame.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from skills.types import Array
from skills.vocabulary import Arm
from worlds.actuators import (
    ActuatorFaults,
    ActuatorState,
    actuator_start,
    actuator_step,
    lag_gain,
)
from worlds.impedance import (
    GainArrays,
    ImpedanceGains,
    ImpedanceTerms,
    PalmCommand,
    PalmState,
    affine_law,
    checked_vector,
    impedance_terms,
)
from worlds.robots import ArmSpec, RobotModel

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------------------------
# Stateful controller


class DualArmImpedanceController:
    """Torque-controls both palms of a robot loaded in a PyBullet client.

    Call :meth:`apply` once before every ``stepSimulation``. Until an arm has a command it holds
    its palm where it was when the controller was enabled. Both arms must have the same number
    of joints; every movable joint of the robot's bodies must belong to an arm.

    Parameters
    ----------
    robot : RobotModel
        The robot description.
    body_ids : sequence of int
        PyBullet body ids of ``robot.bodies``, same order.
    physics_dt : float
        Physics time step, s.
    client : int
        PyBullet physics client id.
    gains : ImpedanceGains, optional
        Gains for both arms (change per arm with :meth:`set_gains`).
    refresh_every : int
        Most physics steps between re-linearisations (Jacobian, gravity, inertia, palm pose);
        1 is exact. New commands act at once on the current linearisation.
    relinearise_tolerance : float
        Also re-linearise as soon as a joint has moved this far from the linearisation point,
        rad; 0 switches this off. The linearisation error grows with the joint displacement,
        not with time, so this keeps moving arms accurate and lets a still arm skip refreshes.
    faults : ActuatorFaults, optional
        How the actuators differ from ideal torque sources (one entry per joint, the left
        arm's first); None: the computed torques are applied as they are.
    """

    ARMS = (Arm.LEFT, Arm.RIGHT)

    def __init__(
        self,
        robot: RobotModel,
        body_ids: Sequence[int],
        physics_dt: float,
        client: int = 0,
        gains: ImpedanceGains | None = None,
        refresh_every: int = 1,
        relinearise_tolerance: float = 0.0,
        faults: ActuatorFaults | None = None,
    ) -> None:
        name = "DualArmImpedanceController"
        if len(body_ids) != len(robot.bodies):
            raise ValueError(f"{name}: expected {len(robot.bodies)} body ids, got {len(body_ids)}")
        if refresh_every < 1:
            raise ValueError(f"{name}: expected refresh_every >= 1, got {refresh_every}")
        if physics_dt <= 0.0:
            raise ValueError(f"{name}: expected physics_dt > 0, got {physics_dt}")
        self.robot = robot
        self.client = client
        self.physics_dt = physics_dt
        self.refresh_every = refresh_every
        if relinearise_tolerance < 0.0:
            raise ValueError(
                f"{name}: expected relinearise_tolerance >= 0, got {relinearise_tolerance}"
            )
        self.relinearise_tolerance = relinearise_tolerance
        self._specs: list[ArmSpec] = [robot.arms[arm] for arm in self.ARMS]
        n = len(self._specs[0].joint_indices)
        if any(len(spec.joint_indices) != n for spec in self._specs):
            raise ValueError(f"{name}: expected arms with equal joint counts")
        self._n = n
        if faults is not None and faults.joints != 2 * n:
            raise ValueError(
                f"{name}: expected actuator faults for {2 * n} joints, got {faults.joints}"
            )
        self.faults = faults
        self._lag_gain = lag_gain(faults.lag_s, physics_dt) if faults is not None else 1.0
        self._actuators: ActuatorState | None = None
        self._arm_body = [int(body_ids[spec.body]) for spec in self._specs]
        # One body per arm, or one body for both; every movable joint must belong to an arm,
        # because PyBullet's Jacobian and inverse dynamics take all of a body's movable joints.
        self._bodies: list[int] = sorted(set(self._arm_body), key=self._arm_body.index)
        self._body_joints: list[list[int]] = []
        # Rows of the (2n,) stacked vector per body: a slice when contiguous (cheaper to index).
        self._body_rows: list[NDArray[np.intp] | slice] = []
        self._arm_columns: list[NDArray[np.intp]] = []  # arm joints within its body's DOFs
        for body in self._bodies:
            movable = [
                j
                for j in range(pb.getNumJoints(body, physicsClientId=client))
                if pb.getJointInfo(body, j, physicsClientId=client)[2] != pb.JOINT_FIXED
            ]
            arms_here = [i for i, b in enumerate(self._arm_body) if b == body]
            owned = [j for i in arms_here for j in self._specs[i].joint_indices]
            if sorted(owned) != movable:
                raise ValueError(
                    f"{name}: expected the arms to own all movable joints {movable} of body "
                    f"{body}, got {sorted(owned)}"
                )
            self._body_joints.append(movable)
            rows = np.empty(len(movable), dtype=np.intp)
            for i in arms_here:
                for k, j in enumerate(self._specs[i].joint_indices):
                    rows[movable.index(j)] = i * n + k
            contiguous = bool(np.all(np.diff(rows) == 1))
            self._body_rows.append(slice(int(rows[0]), int(rows[-1]) + 1) if contiguous else rows)
        for i, spec in enumerate(self._specs):
            movable = self._body_joints[self._bodies.index(self._arm_body[i])]
            self._arm_columns.append(
                np.array([movable.index(j) for j in spec.joint_indices], dtype=np.intp)
            )
        # Arms alone on their body (the KUKA pair) skip the column selection.
        self._arm_owns_body = [
            len(self._body_joints[self._bodies.index(b)]) == n for b in self._arm_body
        ]
        self._lower = np.concatenate([np.asarray(s.lower, dtype=float) for s in self._specs])
        self._upper = np.concatenate([np.asarray(s.upper, dtype=float) for s in self._specs])
        self._max_torque = np.concatenate(
            [np.asarray(s.max_torque, dtype=float) for s in self._specs]
        )
        self._min_torque = -self._max_torque
        self._rest = np.array([s.rest_posture for s in self._specs], dtype=float)  # (2, n)
        self._gains: list[ImpedanceGains] = [gains or ImpedanceGains()] * 2
        self._commands: list[PalmCommand | None] = [None, None]
        self._target_position = np.zeros((2, 3))
        self._target_quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1))
        self._target_twist = np.zeros((2, 6))
        self._update_gains()
        self._a = np.zeros(2 * n)
        self._a_rate = np.zeros(2 * n)
        self._b = np.zeros((2 * n, 2 * n))
        self._c = np.zeros((2 * n, 2 * n))
        self._q = np.zeros(2 * n)
        self._qd = np.zeros(2 * n)
        self._tau = np.zeros(2 * n)
        self._applied = self._tau
        self._q_lin = np.zeros(2 * n)
        self._terms: ImpedanceTerms | None = None
        self._targets_changed = True
        self._gravity_world = np.array([0.0, 0.0, -9.81])
        self._base_rotation: dict[int, Array | None] = {}
        self._gravity_in_base: dict[int, list[float] | None] = {}
        self._steps_since_refresh = 0
        self._steps_since_target = 0
        self._enabled = False

    # -- configuration -----------------------------------------------------------------------

    @property
    def joint_count(self) -> int:
        """Number of joints per arm."""
        return self._n

    def enable(self) -> None:
        """Switch off PyBullet's default velocity motors and hold the palms where they are."""
        for body, joints in zip(self._bodies, self._body_joints, strict=True):
            pb.setJointMotorControlArray(
                body,
                joints,
                pb.VELOCITY_CONTROL,
                forces=[0.0] * len(joints),
                physicsClientId=self.client,
            )
        self._enabled = True
        # Fixed bases: their orientation and the gravity vector are read once.
        params = pb.getPhysicsEngineParameters(physicsClientId=self.client)
        self._gravity_world = np.array(
            [params[f"gravityAcceleration{axis}"] for axis in "XYZ"], dtype=float
        )
        for body in self._bodies:
            _, base_q = pb.getBasePositionAndOrientation(body, physicsClientId=self.client)
            rotation = quat.to_matrix(base_q)
            turned = not np.allclose(rotation, np.eye(3), atol=1e-12)
            self._base_rotation[body] = rotation if turned else None
            self._gravity_in_base[body] = (
                (rotation.T @ self._gravity_world).tolist() if turned else None
            )
        for i, arm in enumerate(self.ARMS):
            if self._commands[i] is None:
                position, quaternion = self._palm_pose(i)
                self.set_command(arm, PalmCommand(position, quaternion))
        self.refresh()

    def set_command(self, arm: Arm, command: PalmCommand) -> None:
        """Set the palm target of ``arm``; acts from the next step, on the current linearisation."""
        i = self.ARMS.index(Arm(arm))
        self._commands[i] = command
        self._target_position[i] = command.target_position()
        self._target_quaternion[i] = command.quaternion
        self._target_twist[i] = command.twist()
        self._targets_changed = True

    def _update_targets(self) -> None:
        assert self._terms is not None
        law = affine_law(
            self._terms, self._target_position, self._target_quaternion, self._target_twist
        )
        self._a = law.a.reshape(-1)
        self._a_rate = law.a_rate.reshape(-1)
        self._steps_since_target = 0
        self._targets_changed = False

    def command(self, arm: Arm) -> PalmCommand | None:
        """Current palm target of ``arm``."""
        return self._commands[self.ARMS.index(Arm(arm))]

    def set_gains(self, arm: Arm, gains: ImpedanceGains) -> None:
        """Set the impedance gains of ``arm``."""
        self._gains[self.ARMS.index(Arm(arm))] = gains
        self._update_gains()
        self._steps_since_refresh = self.refresh_every

    def gains(self, arm: Arm) -> ImpedanceGains:
        """Impedance gains of ``arm``."""
        return self._gains[self.ARMS.index(Arm(arm))]

    def set_squeeze_offset(self, arm: Arm, offset: float) -> None:
        """Change only the squeeze offset of ``arm``'s current command, m."""
        command = self.command(arm)
        if command is None:
            raise RuntimeError(f"set_squeeze_offset: {arm} has no command yet; call enable()")
        self.set_command(arm, replace(command, squeeze_offset=float(offset)))

    def set_rest_posture(self, arm: Arm, q: ArrayLike) -> None:
        """Set the null-space posture target of ``arm``, rad, shape (n,)."""
        self._rest[self.ARMS.index(Arm(arm))] = checked_vector(q, (self._n,), "set_rest_posture")
        self._steps_since_refresh = self.refresh_every

    def _update_gains(self) -> None:
        self._gain_arrays = GainArrays.of(self._gains)
        margin = np.repeat([g.limit_margin for g in self._gains], self._n)
        self._limit_k = np.repeat([g.limit_stiffness for g in self._gains], self._n)
        # The joint-limit repulsion band starts this far inside the limits.
        self._soft_lower = self._lower + margin
        self._soft_upper = self._upper - margin

    # -- the loop ----------------------------------------------------------------------------

    def _read_joints(self) -> None:
        for body, joints, rows in zip(
            self._bodies, self._body_joints, self._body_rows, strict=True
        ):
            states = pb.getJointStates(body, joints, physicsClientId=self.client)
            self._q[rows] = [s[0] for s in states]
            self._qd[rows] = [s[1] for s in states]

    def _palm_pose(self, i: int) -> tuple[FloatArray, FloatArray]:
        link = pb.getLinkState(
            self._arm_body[i],
            self._specs[i].palm_link,
            computeForwardKinematics=1,
            physicsClientId=self.client,
        )
        return np.asarray(link[4]), np.asarray(link[5])

    def refresh(self) -> None:
        """Re-linearise the law at the current joint state (Jacobian, gravity, inertia, pose)."""
        self._read_joints()
        self._relinearise()

    def _relinearise(self) -> None:
        """:meth:`refresh` on the joint state already read."""
        self._q_lin = self._q.copy()
        n = self._n
        q_arm = self._q.reshape(2, n)
        c = self.client
        body_terms: dict[int, tuple[list[float], FloatArray, FloatArray]] = {}
        for body, rows in zip(self._bodies, self._body_rows, strict=True):
            q_body = self._q[rows].tolist()
            zeros = [0.0] * len(q_body)
            # PyBullet's inverse dynamics works in the base frame with the world's gravity
            # vector: hand it gravity in the base frame for a turned base, then restore it.
            gravity_in_base = self._gravity_in_base[body]
            if gravity_in_base is not None:
                pb.setGravity(*gravity_in_base, physicsClientId=c)
            gravity = np.asarray(
                pb.calculateInverseDynamics(body, q_body, zeros, zeros, physicsClientId=c)
            )
            if gravity_in_base is not None:
                pb.setGravity(*self._gravity_world, physicsClientId=c)
            mass = np.asarray(pb.calculateMassMatrix(body, q_body, physicsClientId=c))
            body_terms[body] = (q_body, gravity, mass)
        jacobian = np.empty((2, 6, n))
        gravity_arm = np.empty((2, n))
        mass_arm = np.empty((2, n, n))
        position = np.empty((2, 3))
        quaternion = np.empty((2, 4))
        for i, spec in enumerate(self._specs):
            body = self._arm_body[i]
            q_body, gravity, mass = body_terms[body]
            zeros = [0.0] * len(q_body)
            linear, angular = pb.calculateJacobian(
                body, spec.palm_link, [0.0, 0.0, 0.0], q_body, zeros, zeros, physicsClientId=c
            )
            if self._arm_owns_body[i]:
                jacobian[i, :3] = linear
                jacobian[i, 3:] = angular
                gravity_arm[i] = gravity
                mass_arm[i] = mass
            else:
                cols = self._arm_columns[i]
                jacobian[i, :3] = np.asarray(linear)[:, cols]
                jacobian[i, 3:] = np.asarray(angular)[:, cols]
                gravity_arm[i] = gravity[cols]
                mass_arm[i] = mass[np.ix_(cols, cols)]
            # PyBullet's Jacobian is in the base frame; the law works in the world frame.
            base2world = self._base_rotation[body]
            if base2world is not None:
                jacobian[i, :3] = base2world @ jacobian[i, :3]
                jacobian[i, 3:] = base2world @ jacobian[i, 3:]
            link = pb.getLinkState(
                body, spec.palm_link, computeForwardKinematics=1, physicsClientId=c
            )
            position[i] = link[4]
            quaternion[i] = link[5]
        terms = impedance_terms(
            jacobian,
            position,
            quaternion,
            q_arm,
            gravity_arm,
            self._gain_arrays,
            self._rest,
            mass_matrix=mass_arm,
            dt=self.physics_dt,
        )
        self._b[:n, :n] = terms.b[0]
        self._b[n:, n:] = terms.b[1]
        self._c[:n, :n] = terms.c[0]
        self._c[n:, n:] = terms.c[1]
        # The anchor has moved along the feed-forward twist since the last target update.
        if self._steps_since_target:
            elapsed = self._steps_since_target * self.physics_dt
            self._target_position += elapsed * self._target_twist[:, :3]
        self._terms = terms
        self._update_targets()
        self._steps_since_refresh = 0

    def apply(self) -> None:
        """Compute and send the torques of the next physics step (one read, one write a body)."""
        if not self._enabled:
            raise RuntimeError("DualArmImpedanceController.apply: call enable() first")
        self._read_joints()
        q = self._q
        # Per physics step, numpy's ufuncs are called bare (np.max, np.clip without their
        # Python wrappers: the same reductions and the same min(max(x, lo), hi)).
        if self._steps_since_refresh >= self.refresh_every or (
            self.relinearise_tolerance > 0.0
            and np.abs(q - self._q_lin).max() > self.relinearise_tolerance
        ):
            self._relinearise()
        elif self._targets_changed:
            self._update_targets()
        tau = self._a + self._b @ q + self._c @ self._qd
        if self._steps_since_target:
            tau += (self._steps_since_target * self.physics_dt) * self._a_rate
        tau += self._limit_k * (np.minimum(np.maximum(q, self._soft_lower), self._soft_upper) - q)
        np.maximum(tau, self._min_torque, out=tau)
        np.minimum(tau, self._max_torque, out=tau)
        self._tau = tau
        if self.faults is not None:
            tau = self._actuate(tau)
        self._applied = tau
        for body, joints, rows in zip(
            self._bodies, self._body_joints, self._body_rows, strict=True
        ):
            pb.setJointMotorControlArray(
                body,
                joints,
                pb.TORQUE_CONTROL,
                forces=tau[rows].tolist(),
                physicsClientId=self.client,
            )
        self._steps_since_refresh += 1
        self._steps_since_target += 1

    def _actuate(self, tau: FloatArray) -> FloatArray:
        """The torques the faulty actuators apply this tick for the computed ``tau`` (2n,)."""
        assert self.faults is not None
        if self._actuators is None:
            self._actuators = actuator_start(tau, self.faults)
        self._actuators, applied = actuator_step(
            self._actuators, tau, self.faults, self._lag_gain, self._max_torque
        )
        return applied

    # -- outputs -----------------------------------------------------------------------------

    def applied_torques(self) -> FloatArray:
        """Torques sent to PyBullet at the last tick, (2n,) N m, the left arm's first: the
        computed ones (:attr:`PalmState.joint_torques`) through the actuators' faults."""
        return self._applied.copy()

    def palm_motion(self, arm: Arm) -> tuple[FloatArray, FloatArray]:
        """Measured palm position (3,) m and linear velocity (3,) m/s of ``arm``, world frame:
        :meth:`palm_state`'s first and third, read alone (one link read, no joint read)."""
        link = pb.getLinkState(
            self._arm_body[self.ARMS.index(Arm(arm))],
            self._specs[self.ARMS.index(Arm(arm))].palm_link,
            computeLinkVelocity=1,
            computeForwardKinematics=1,
            physicsClientId=self.client,
        )
        return np.asarray(link[4]), np.asarray(link[6])

    def palm_state(self, arm: Arm) -> PalmState:
        """Measured palm pose and twist (world frame) and joint state of ``arm``."""
        i = self.ARMS.index(Arm(arm))
        spec = self._specs[i]
        link = pb.getLinkState(
            self._arm_body[i],
            spec.palm_link,
            computeLinkVelocity=1,
            computeForwardKinematics=1,
            physicsClientId=self.client,
        )
        states = pb.getJointStates(
            self._arm_body[i], list(spec.joint_indices), physicsClientId=self.client
        )
        return PalmState(
            position=np.asarray(link[4]),
            quaternion=np.asarray(link[5]),
            linear_velocity=np.asarray(link[6]),
            angular_velocity=np.asarray(link[7]),
            joint_positions=np.array([s[0] for s in states]),
            joint_velocities=np.array([s[1] for s in states]),
            joint_torques=self._tau[i * self._n : (i + 1) * self._n].copy(),
        )

    def palm_states(self) -> Mapping[Arm, PalmState]:
        """:meth:`palm_state` of both arms."""
        return {arm: self.palm_state(arm) for arm in self.ARMS}


# The values callers hand the controller are re-exported: ``from worlds.control import
# PalmCommand`` is how the scene, the simulated world and the benches name them.
__all__ = [
    "DualArmImpedanceController",
    "ImpedanceGains",
    "PalmCommand",
    "PalmState",
]
