"""The impedance controller: torque control of both palms of a robot loaded in PyBullet.

:class:`DualArmImpedanceController` reads the joint state, re-linearises the law of
:mod:`worlds.impedance` (Jacobian, gravity, inertia from PyBullet), adds the joint-limit
repulsion, clips to the torque limits and sends the torques with TORQUE_CONTROL, through the
actuators' faults (:mod:`worlds.actuators`) when it is given any, and then through the loop
each joint closes on its sensed torque (:class:`worlds.actuators.TorqueLoop`).

Quaternions are scalar-last (x, y, z, w); twists are (linear, angular) in the world frame.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import pybullet as pb
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from skills.kernel import kernel
from skills.types import Array
from skills.vocabulary import Arm
from worlds.actuators import (
    ActuatorFaults,
    ActuatorState,
    TorqueLoop,
    actuator_start,
    actuator_step,
    lag_gain,
    torque_loop_start,
    torque_loop_step,
)
from worlds.control_layout import body_layout
from worlds.impedance import ImpedanceTerms, affine_law, impedance_terms, limit_posture
from worlds.impedance_values import (
    GainArrays,
    ImpedanceGains,
    PalmCommand,
    PalmState,
    checked_vector,
)
from worlds.robots import ArmSpec, RobotModel

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Posture weight of the joints of an arm held in joint space
#: (:meth:`DualArmImpedanceController.set_joint_target`): with the default gains' posture
#: spring and damper (5 N m/rad, 1 N m s/rad), 60 N m/rad and 12 N m s/rad on every joint.
#: On the iiwa it took an arm folded against two limits, its forearm pressed on the table,
#: to its rest posture (the default world's 1000-trial record, trial 516).
JOINT_HOLD_WEIGHT = 12.0


@kernel
def _torques(
    a: FloatArray,
    a_rate: FloatArray,
    elapsed: float,
    b: FloatArray,
    c: FloatArray,
    q: FloatArray,
    qd: FloatArray,
    limit_k: FloatArray,
    soft_lower: FloatArray,
    soft_upper: FloatArray,
    max_torque: FloatArray,
) -> FloatArray:
    """One physics step's torques (N,): the affine law (:mod:`worlds.impedance`)
    ``a + a_rate * elapsed + B q + C qd``, the joint-limit repulsion inside the soft limits,
    clipped to the torque limits."""
    n = q.size
    tau = np.empty(n)
    for i in range(n):
        t = a[i] + elapsed * a_rate[i]
        for j in range(n):
            t += b[i, j] * q[j] + c[i, j] * qd[j]
        t += limit_k[i] * (min(max(q[i], soft_lower[i]), soft_upper[i]) - q[i])
        tau[i] = min(max(t, -max_torque[i]), max_torque[i])
    return tau


@kernel
def _strays(q: FloatArray, q_lin: FloatArray, tolerance: float) -> bool:
    """Whether a joint of ``q`` is more than ``tolerance`` from where the law was linearised."""
    for i in range(q.size):
        if abs(q[i] - q_lin[i]) > tolerance:
            return True
    return False


# ---------------------------------------------------------------------------------------------
# Stateful controller


class DualArmImpedanceController:
    """Torque-controls both palms of a robot loaded in PyBullet.

    Call :meth:`apply` once before every ``stepSimulation``. Until an arm has a command it holds
    its palm where it was when the controller was enabled. Every movable joint of the robot's
    bodies must belong to an arm or to the robot's shared joints
    (:attr:`worlds.robots.RobotModel.shared_joints`).

    The law (:mod:`worlds.impedance`) is linearised body by body: a body's palms are its tasks,
    over all its joints. Two iiwas are two bodies of one palm each, two independent laws; the
    iCub is one body whose torso moves both palms, one coupled law over torso and both arms.

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
        How the actuators differ from ideal torque sources (one entry per driven joint, in
        :meth:`worlds.robots.RobotModel.driven_joints` order); None: the computed torques are
        applied as they are.
    torque_loop : TorqueLoop, optional
        The loop each joint closes on its sensed torque (:class:`worlds.actuators.TorqueLoop`);
        default: the robot's (:attr:`worlds.robots.RobotModel.torque_loop`). With ideal
        actuators the sensed torque is the one sent, the loop would add exactly nothing, and it
        is not run.
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
        torque_loop: TorqueLoop | None = None,
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
        driven = robot.driven_joints()
        self._driven = driven
        total = len(driven)
        if faults is not None and faults.joints != total:
            raise ValueError(
                f"{name}: expected actuator faults for {total} joints, got {faults.joints}"
            )
        self.faults = faults
        self._lag_gain = lag_gain(faults.lag_s, physics_dt) if faults is not None else 1.0
        self._actuators: ActuatorState | None = None
        self.torque_loop = torque_loop if torque_loop is not None else robot.torque_loop
        self._loop = torque_loop_start(total)
        self._arm_body = [int(body_ids[spec.body]) for spec in self._specs]
        # One law per body, bodies of one shape linearised in one vectorised call.
        layout = body_layout(driven, self._specs, self.ARMS, body_ids, client, name)
        self._bodies = layout.bodies
        self._body_joints = layout.body_joints
        self._body_rows = layout.body_rows
        self._body_arms = layout.body_arms
        self._arm_rows = layout.arm_rows
        self._batches = layout.batches
        self._batch_tasks = layout.batch_tasks
        self._batch_rows = layout.batch_rows
        self._joint_arm = layout.joint_arm
        self._lower = np.array([d.lower for d in driven], dtype=float)
        self._upper = np.array([d.upper for d in driven], dtype=float)
        self._max_torque = np.array([d.max_torque for d in driven], dtype=float)
        self._rest = np.array([d.rest for d in driven], dtype=float)  # (N,)
        # The posture factor per joint (shared joints held more firmly); None where every
        # joint has 1, as the law then takes its unweighted form.
        shared = robot.shared_joints
        self._posture_weight: FloatArray | None = None
        if shared is not None:
            self._posture_weight = np.array(
                [1.0 if d.arm is not None else shared.posture_weight for d in driven]
            )
        self._gains: list[ImpedanceGains] = [gains or ImpedanceGains()] * 2
        self._commands: list[PalmCommand | None] = [None, None]
        #: Per arm: its palm's task left out of the law, its joints held at
        #: :attr:`_joint_target` over the whole joint space (:meth:`set_joint_target`).
        self._joint_space = [False, False]
        self._target_position = np.zeros((2, 3))
        self._target_quaternion = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1))
        self._target_twist = np.zeros((2, 6))
        self._update_gains()
        self._a = np.zeros(total)
        self._a_rate = np.zeros(total)
        self._b = np.zeros((total, total))
        self._c = np.zeros((total, total))
        self._q = np.zeros(total)
        self._qd = np.zeros(total)
        self._tau = np.zeros(total)
        self._applied = self._tau
        self._q_lin = np.zeros(total)
        self._joint_target = np.zeros(total)
        self._terms: list[ImpedanceTerms] = []
        self._jacobians: list[FloatArray] = []  # per batch, (k, 6t, n), as last linearised
        self._targets_changed = True
        self._gravity_world = np.array([0.0, 0.0, -9.81])
        self._gravity_world_xyz = self._gravity_world.tolist()
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

    @property
    def driven_joint_count(self) -> int:
        """Number of joints driven: both arms' and the shared ones."""
        return len(self._driven)

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
        self._gravity_world_xyz = self._gravity_world.tolist()
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
        """Set the palm target of ``arm``; acts from the next step, on the current linearisation
        (re-linearised first for an arm :meth:`set_joint_target` had held in joint space)."""
        i = self.ARMS.index(Arm(arm))
        if self._joint_space[i]:
            self._leave_joint_space(i)
        self._commands[i] = command
        self._target_position[i] = command.target_position()
        self._target_quaternion[i] = command.quaternion
        self._target_twist[i] = command.twist()
        self._targets_changed = True

    def _update_targets(self) -> None:
        for terms, batch, tasks in zip(self._terms, self._batches, self._batch_tasks, strict=True):
            law = affine_law(
                terms,
                self._target_position[tasks],
                self._target_quaternion[tasks],
                self._target_twist[tasks],
            )
            for j, g in enumerate(batch):
                rows = self._body_rows[g]
                self._a[rows] = law.a[j]
                self._a_rate[rows] = law.a_rate[j]
        self._steps_since_target = 0
        self._targets_changed = False

    def set_joint_target(self, arm: Arm, q: ArrayLike) -> None:
        """Hold ``arm``'s joints at ``q`` (rad, (n,)) in joint space, with
        :data:`JOINT_HOLD_WEIGHT` times the posture spring and damper on each: its palm's task
        leaves the law (no palm spring, and the posture no longer projected away from the
        palm's directions) until the next :meth:`set_command` of the arm. Gravity and the
        joint-limit repulsion stay; a posture band's pull off the limits
        (``posture_limit_band``) gives way to the hold on the arm's joints. A way out for an
        arm the palm law cannot move: folded against its limits with a link pressed on the
        table, it pushes that link harder into the table the higher it is asked to lift its
        palm."""
        i = self.ARMS.index(Arm(arm))
        rows = self._arm_rows[i]
        self._joint_target[rows] = checked_vector(q, (self._n,), "set_joint_target")
        self._joint_space[i] = True
        self._steps_since_refresh = self.refresh_every

    def _leave_joint_space(self, i: int) -> None:
        self._joint_space[i] = False
        self._steps_since_refresh = self.refresh_every

    def in_joint_space(self, arm: Arm) -> bool:
        """Whether :meth:`set_joint_target` holds ``arm`` in joint space now."""
        return self._joint_space[self.ARMS.index(Arm(arm))]

    def arm_joint_positions(self, arm: Arm) -> FloatArray:
        """Joint positions of ``arm`` now, rad, (n,)."""
        self._read_joints()
        return self._q[self._arm_rows[self.ARMS.index(Arm(arm))]].copy()

    def arm_rest_posture(self, arm: Arm) -> FloatArray:
        """The posture target of ``arm``'s joints, rad, (n,) (:meth:`set_rest_posture`)."""
        return self._rest[self._arm_rows[self.ARMS.index(Arm(arm))]].copy()

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
        rows = self._arm_rows[self.ARMS.index(Arm(arm))]
        self._rest[rows] = checked_vector(q, (self._n,), "set_rest_posture")
        self._steps_since_refresh = self.refresh_every

    def rest_posture(self) -> FloatArray:
        """Null-space posture targets of every driven joint, rad, (N,) in driven order."""
        return self._rest.copy()

    def _update_gains(self) -> None:
        self._gain_arrays = [
            GainArrays.of_tasks(
                [[self._gains[i] for i in self._body_arms[g]] for g in batch],
                None
                if self._posture_weight is None
                else np.array([self._posture_weight[self._body_rows[g]] for g in batch]),
            )
            for batch in self._batches
        ]
        margin = np.array([self._gains[i].limit_margin for i in self._joint_arm])
        self._avoid_band = np.array([self._gains[i].posture_limit_band for i in self._joint_arm])
        self._avoids_limits = bool(self._avoid_band.any())
        self._avoid_weight = np.array(
            [self._gains[i].posture_limit_weight for i in self._joint_arm]
        )
        self._limit_k = np.array([self._gains[i].limit_stiffness for i in self._joint_arm])
        # The joint-limit repulsion band starts this far inside the limits.
        self._soft_lower = self._lower + margin
        self._soft_upper = self._upper - margin

    # -- the loop ----------------------------------------------------------------------------

    def _read_joints(self) -> None:
        for body, joints, rows in zip(
            self._bodies, self._body_joints, self._body_rows, strict=True
        ):
            positions, velocities, _, _ = zip(
                *pb.getJointStates(body, joints, physicsClientId=self.client), strict=True
            )
            self._q[rows] = positions
            self._qd[rows] = velocities

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
        c = self.client
        self._terms = []
        self._jacobians = []
        for batch, tasks, gains, batch_rows in zip(
            self._batches, self._batch_tasks, self._gain_arrays, self._batch_rows, strict=True
        ):
            k, t = tasks.shape
            nb = len(self._body_joints[batch[0]])
            jacobian = np.empty((k, 6 * t, nb))
            gravity = np.empty((k, nb))
            mass = np.empty((k, nb, nb))
            q = self._q[batch_rows]
            position = np.empty((k, t, 3))
            quaternion = np.empty((k, t, 4))
            zeros = [0.0] * nb
            for j, g in enumerate(batch):
                body = self._bodies[g]
                q_body = q[j].tolist()
                # PyBullet's inverse dynamics works in the base frame with the world's gravity
                # vector: hand it gravity in the base frame for a turned base, then restore it.
                gravity_in_base = self._gravity_in_base[body]
                if gravity_in_base is not None:
                    pb.setGravity(*gravity_in_base, physicsClientId=c)
                gravity[j] = pb.calculateInverseDynamics(
                    body, q_body, zeros, zeros, physicsClientId=c
                )
                if gravity_in_base is not None:
                    pb.setGravity(*self._gravity_world_xyz, physicsClientId=c)
                mass[j] = pb.calculateMassMatrix(body, q_body, physicsClientId=c)
                base2world = self._base_rotation[body]
                body_jacobian = jacobian[j]
                for s, i in enumerate(tasks[j]):
                    palm = self._specs[i].palm_link
                    row = 6 * s
                    if self._joint_space[i]:
                        # No palm task: no spring, no null-space projection for this palm.
                        linear = angular = ((0.0,) * nb,) * 3
                    else:
                        linear, angular = pb.calculateJacobian(
                            body, palm, [0.0, 0.0, 0.0], q_body, zeros, zeros, physicsClientId=c
                        )
                    body_jacobian[row : row + 3] = linear
                    body_jacobian[row + 3 : row + 6] = angular
                    # PyBullet's Jacobian is in the base frame; the law works in the world's.
                    if base2world is not None:
                        body_jacobian[row : row + 3] = base2world @ body_jacobian[row : row + 3]
                        body_jacobian[row + 3 : row + 6] = (
                            base2world @ body_jacobian[row + 3 : row + 6]
                        )
                    link = pb.getLinkState(
                        body, palm, computeForwardKinematics=1, physicsClientId=c
                    )
                    position[j, s] = link[4]
                    quaternion[j, s] = link[5]
            terms = impedance_terms(
                jacobian,
                position,
                quaternion,
                q,
                gravity,
                *self._posture(gains, batch_rows),
                mass_matrix=mass,
                dt=self.physics_dt,
            )
            for j, g in enumerate(batch):
                rows = self._body_rows[g]
                self._b[rows, rows] = terms.b[j]
                self._c[rows, rows] = terms.c[j]
            self._terms.append(terms)
            self._jacobians.append(jacobian)
        # The anchor has moved along the feed-forward twist since the last target update.
        if self._steps_since_target:
            elapsed = self._steps_since_target * self.physics_dt
            self._target_position += elapsed * self._target_twist[:, :3]
        self._update_targets()
        self._steps_since_refresh = 0

    def _posture(self, gains: GainArrays, rows: IntArray) -> tuple[GainArrays, FloatArray]:
        """A batch's posture gains and targets (k, n) at the joint state read, its ``rows``
        (k, n) of the driven vector (:func:`worlds.impedance.limit_posture` where a band is
        set)."""
        rest = self._rest[rows]
        if self._avoids_limits:
            gains, rest = self._limit_posture(gains, rows, rest)
        if True in self._joint_space:
            held = np.zeros(len(self._driven), dtype=bool)
            for i, on in enumerate(self._joint_space):
                held[self._arm_rows[i]] = on
            held = held[rows]
            rest = np.where(held, self._joint_target[rows], rest)
            weight = gains.posture_weight
            weight = np.ones_like(rest) if weight is None else weight
            gains = replace(gains, posture_weight=np.where(held, JOINT_HOLD_WEIGHT, weight))
        return gains, rest

    def _limit_posture(
        self, gains: GainArrays, rows: IntArray, rest: FloatArray
    ) -> tuple[GainArrays, FloatArray]:
        weight, rest = limit_posture(
            self._q[rows],
            self._lower[rows],
            self._upper[rows],
            rest,
            gains.posture_weight if gains.posture_weight is not None else np.ones_like(rest),
            self._avoid_band[rows],
            self._avoid_weight[rows],
        )
        return replace(gains, posture_weight=weight), rest

    def apply(self) -> None:
        """Compute and send the torques of the next physics step (one read, one write a body)."""
        if not self._enabled:
            raise RuntimeError("DualArmImpedanceController.apply: call enable() first")
        self._read_joints()
        q = self._q
        if self._steps_since_refresh >= self.refresh_every or (
            self.relinearise_tolerance > 0.0 and _strays(q, self._q_lin, self.relinearise_tolerance)
        ):
            self._relinearise()
        elif self._targets_changed:
            self._update_targets()
        tau = _torques(
            self._a,
            self._a_rate,
            self._steps_since_target * self.physics_dt,
            self._b,
            self._c,
            q,
            self._qd,
            self._limit_k,
            self._soft_lower,
            self._soft_upper,
            self._max_torque,
        )
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
        """The torques the faulty actuators apply this tick for the computed ``tau`` (N,),
        through the torque loop where the robot has one."""
        assert self.faults is not None
        if self.torque_loop is not None:
            # The joints' torque sensors read what the actuators applied over the last tick.
            sensed = None if self._actuators is None else self._applied
            self._loop, tau = torque_loop_step(
                self._loop,
                sensed,
                tau,
                self.torque_loop,
                self.physics_dt,
                self._max_torque,
            )
        if self._actuators is None:
            self._actuators = actuator_start(tau, self.faults)
        self._actuators, applied = actuator_step(
            self._actuators, tau, self.faults, self._lag_gain, self._max_torque
        )
        return applied

    # -- outputs -----------------------------------------------------------------------------

    def applied_torques(self) -> FloatArray:
        """Torques sent to PyBullet at the last tick, (N,) N m in
        :meth:`worlds.robots.RobotModel.driven_joints` order: the computed ones
        (:attr:`PalmState.joint_torques`, :meth:`computed_torques`) through the actuators'
        faults."""
        return self._applied.copy()

    def palm_motion(self, arm: Arm) -> tuple[FloatArray, FloatArray]:
        """Measured palm position (3,) m and linear velocity (3,) m/s of ``arm``, world frame:
        :meth:`palm_state`'s first and third, read alone (one link read, no joint read)."""
        i = self.ARMS.index(Arm(arm))
        link = pb.getLinkState(
            self._arm_body[i],
            self._specs[i].palm_link,
            computeLinkVelocity=1,
            computeForwardKinematics=1,
            physicsClientId=self.client,
        )
        return np.asarray(link[4]), np.asarray(link[6])

    def static_palm_stiffness(self) -> dict[Arm, FloatArray]:
        """Each palm's translational stiffness against a load that holds it still, (3, 3) N/m,
        world frame, as the law linearised last applies it (the other palms free).

        It is not the gains' ``stiffness_linear``: the implicit damping
        (:func:`worlds.impedance.impedance_terms`) multiplies the spring's torques by
        ``G = M (M + dt D_q)^-1`` too, which assumes the joints free to accelerate; a load that
        holds the palm still (an object's weight in the grip, a table under it) then meets
        ``G``'s share of the spring. From the joint stiffness ``B`` of the law and the palm's
        Jacobian ``J_p``: ``(J_p (-B)^-1 J_p^T)^-1``.
        """
        out: dict[Arm, FloatArray] = {}
        for terms, jacobian, batch, tasks in zip(
            self._terms, self._jacobians, self._batches, self._batch_tasks, strict=True
        ):
            for j in range(len(batch)):
                for s, i in enumerate(tasks[j]):
                    rows = jacobian[j, 6 * s : 6 * s + 3]
                    compliance = rows @ np.linalg.solve(-terms.b[j], rows.T)
                    out[self.ARMS[int(i)]] = np.asarray(np.linalg.inv(compliance), dtype=float)
        return out

    def computed_torques(self) -> FloatArray:
        """Torques the law computed at the last tick, (N,) N m, in driven order."""
        return self._tau.copy()

    def joint_positions(self) -> FloatArray:
        """Positions of every driven joint at the last tick, (N,) rad, in driven order."""
        return self._q.copy()

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
            joint_torques=self._tau[self._arm_rows[i]],
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
