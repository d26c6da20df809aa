"""The values the palm impedance law works with: a palm's command and measured state, the law's
gains, and those gains arranged per body for its kernel (:mod:`worlds.impedance`).

Quaternions are scalar-last (x, y, z, w); twists are (linear, angular) in the world frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat

FloatArray = NDArray[np.float64]


def checked_vector(value: ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
    """``value`` as a float array of ``shape``, finite; ``ValueError`` naming ``name`` if not."""
    array = np.asarray(value, dtype=float)
    if array.shape != shape:
        raise ValueError(f"{name}: expected shape {shape}, got {array.shape}")
    # Called for every palm command: the floats checked one by one cost less than a ufunc.
    if not all(map(math.isfinite, array.ravel().tolist())):
        raise ValueError(f"{name}: expected finite values, got {array}")
    return array


@dataclass(frozen=True)
class PalmCommand:
    """Target pose of one palm, with an optional feed-forward twist.

    Attributes
    ----------
    position : ndarray
        (3,) palm frame origin target in the world frame, m.
    quaternion : ndarray
        (4,) palm orientation target in the world frame, scalar-last (x, y, z, w).
    linear_velocity : ndarray
        (3,) feed-forward linear velocity of the target, world frame, m/s.
    angular_velocity : ndarray
        (3,) feed-forward angular velocity of the target, world frame, rad/s.
    squeeze_offset : float
        Shift of the target along the target palm's +z axis (into the grasped face), m; with the
        linear stiffness it sets the squeeze force (15 mm at 1000 N/m gives about 15 N).
    """

    position: FloatArray
    quaternion: FloatArray
    linear_velocity: FloatArray = field(default_factory=lambda: np.zeros(3))
    angular_velocity: FloatArray = field(default_factory=lambda: np.zeros(3))
    squeeze_offset: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "position", checked_vector(self.position, (3,), "PalmCommand.position")
        )
        quaternion = checked_vector(self.quaternion, (4,), "PalmCommand.quaternion")
        # np.linalg.norm of a vector is sqrt(q . q); called bare, without its wrapper's cost.
        norm = math.sqrt(float(quaternion.dot(quaternion)))
        if norm < 1e-9:
            raise ValueError(
                f"PalmCommand.quaternion: expected a unit quaternion, got {quaternion}"
            )
        object.__setattr__(self, "quaternion", quaternion / norm)
        object.__setattr__(
            self,
            "linear_velocity",
            checked_vector(self.linear_velocity, (3,), "PalmCommand.linear_velocity"),
        )
        object.__setattr__(
            self,
            "angular_velocity",
            checked_vector(self.angular_velocity, (3,), "PalmCommand.angular_velocity"),
        )

    def target_position(self) -> FloatArray:
        """Spring anchor: ``position`` shifted by ``squeeze_offset`` along the palm's z, m, (3,)."""
        if self.squeeze_offset == 0.0:
            return self.position
        normal = quat.to_matrix(self.quaternion)[:, 2]
        return self.position + self.squeeze_offset * normal

    def twist(self) -> FloatArray:
        """Feed-forward twist (linear m/s, angular rad/s), world frame, (6,)."""
        return np.concatenate([self.linear_velocity, self.angular_velocity])


@dataclass(frozen=True)
class ImpedanceGains:
    """Gains of the palm impedance law.

    Attributes
    ----------
    stiffness_linear, damping_linear : float
        Translational spring (N/m) and damper (N s/m).
    stiffness_angular, damping_angular : float
        Rotational spring (N m/rad) and damper (N m s/rad). The spring sets how fast a light
        wrist rings: the iiwa's last joint (0.002 kg m^2 with its palm) rang at 11-12 Hz on
        10 N m/rad, faster than a 30 ms actuator lag follows, and that ring grew under Hard
        mode's slowest actuators (joint rate 0.57 rad/s rms six seconds after a 3 cm step) and
        turned held parcels about the grip axis; at 5 (50 rad/s) it dies out up to 30 ms
        (tests/worlds/test_torque_loop.py). The iCub's wrist sang the same way at 25-30
        degree orientation errors. Hard, first 60 trials of seed 0: iiwas 56, was 51; Easy,
        first 100: 100 on both robots, median placement 1.3 and 0.2 deg.
    stiffness_null, damping_null : float
        Rest-posture spring (N m/rad) and damper (N m s/rad), projected into the null space.
    joint_damping : float
        Extra damping on every joint, N m s/rad.
    limit_margin : float
        Distance from a joint limit where the repulsive torque starts, rad. Narrow on purpose:
        the repulsion acts on the joint, not in the null space, so inside the band it turns
        the palm away from its command (at 200 N m/rad against the palm's 5 N m/rad). A wrist
        a turned grip holds 5-9 degrees from its limit was twisted 6-8 degrees with a 0.15 rad
        band: the palm met the face on an edge and the held box rolled out of the grip.
    limit_stiffness : float
        Repulsive torque per radian inside the margin, N m/rad.
    posture_limit_band : float
        Width of a band inside each joint limit where the null-space posture also pulls the
        joint back to the band's edge, rad (:func:`limit_posture`); 0: off. Unlike the
        repulsion it moves the joint only along the palms' null space (a torso turning to
        spare a shoulder at its limit), so it may start far inside the limit.
    posture_limit_weight : float
        That pull's posture weight at the limit, growing from 0 at the band's edge.
    """

    stiffness_linear: float = 1000.0
    damping_linear: float = 60.0
    stiffness_angular: float = 5.0
    damping_angular: float = 1.0
    stiffness_null: float = 5.0
    damping_null: float = 1.0
    joint_damping: float = 0.5
    limit_margin: float = 0.05
    limit_stiffness: float = 200.0
    posture_limit_band: float = 0.0
    posture_limit_weight: float = 0.0

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not np.isfinite(value) or value < 0.0:
                raise ValueError(f"ImpedanceGains.{name}: expected finite >= 0, got {value}")

    def stiffness_matrix(self) -> FloatArray:
        """Task-space stiffness, (6, 6): linear block N/m, angular block N m/rad."""
        return np.diag([self.stiffness_linear] * 3 + [self.stiffness_angular] * 3)

    def damping_matrix(self) -> FloatArray:
        """Task-space damping, (6, 6): linear block N s/m, angular block N m s/rad."""
        return np.diag([self.damping_linear] * 3 + [self.damping_angular] * 3)


@dataclass(frozen=True)
class PalmState:
    """Measured state of one arm and its palm.

    Attributes
    ----------
    position : ndarray
        (3,) palm frame origin in the world frame, m.
    quaternion : ndarray
        (4,) palm orientation in the world frame, scalar-last.
    linear_velocity, angular_velocity : ndarray
        (3,) palm twist in the world frame, m/s and rad/s.
    joint_positions, joint_velocities : ndarray
        (n,) arm joint positions (rad) and velocities (rad/s).
    joint_torques : ndarray
        (n,) torques commanded at the last step, N m.
    """

    position: FloatArray
    quaternion: FloatArray
    linear_velocity: FloatArray
    angular_velocity: FloatArray
    joint_positions: FloatArray
    joint_velocities: FloatArray
    joint_torques: FloatArray


@dataclass(frozen=True)
class GainArrays:
    """Gains of ``k`` bodies with ``t`` palms each, as arrays, for :func:`impedance_terms`.

    Attributes
    ----------
    stiffness : ndarray
        (k, 6t) task-space spring diagonal, palm by palm: N/m (3), N m/rad (3).
    damping : ndarray
        (k, 6t) task-space damper diagonal: N s/m, N m s/rad.
    null_stiffness, null_damping, joint_damping : ndarray
        (k,) posture spring (N m/rad), posture damper and joint damper (N m s/rad).
    posture_weight : ndarray, optional
        (k, n) factor of the posture spring and damper per joint; None: 1 on every joint.
    """

    stiffness: FloatArray
    damping: FloatArray
    null_stiffness: FloatArray
    null_damping: FloatArray
    joint_damping: FloatArray
    posture_weight: FloatArray | None = None

    @staticmethod
    def of(gains: Sequence[ImpedanceGains]) -> GainArrays:
        """Stack the gains of several bodies with one palm each."""
        return GainArrays.of_tasks([[g] for g in gains])

    @staticmethod
    def of_tasks(
        gains: Sequence[Sequence[ImpedanceGains]], posture_weight: FloatArray | None = None
    ) -> GainArrays:
        """Stack the gains of several bodies, each with the same number of palms.

        Each palm's spring and damper are its own; the posture and joint damping of a body
        are its first palm's (they act on the body's joints, which its palms may share).

        Parameters
        ----------
        gains : sequence of sequence of ImpedanceGains
            (k, t) per body, its palms' gains.
        posture_weight : ndarray, optional
            (k, n) posture factor per joint; None: 1.
        """
        return GainArrays(
            stiffness=np.array(
                [
                    [v for g in body for v in [g.stiffness_linear] * 3 + [g.stiffness_angular] * 3]
                    for body in gains
                ]
            ),
            damping=np.array(
                [
                    [v for g in body for v in [g.damping_linear] * 3 + [g.damping_angular] * 3]
                    for body in gains
                ]
            ),
            null_stiffness=np.array([body[0].stiffness_null for body in gains]),
            null_damping=np.array([body[0].damping_null for body in gains]),
            joint_damping=np.array([body[0].joint_damping for body in gains]),
            posture_weight=posture_weight,
        )


__all__ = ["GainArrays", "ImpedanceGains", "PalmCommand", "PalmState", "checked_vector"]
