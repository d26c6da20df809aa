"""Robot model types: what the scene and the controller need to know about a dual-arm robot.

A :class:`RobotModel` is a frozen description (URDF files, base poses, joint indices, palm links,
rest posture, limits). Builders such as :func:`worlds.robots.kuka.kuka_iiwa_model` write it; the
scene loads its bodies and the controller drives its arms. A robot may use one body per arm (the
KUKA pair) or one body for both arms and the joints they share (a humanoid such as iCub, whose
torso moves both shoulders: :class:`SharedJointsSpec`).

The types live below the builders (``kuka.py``, ``icub.py``) and the package's dispatch
(``worlds/robots/__init__.py``), so no builder imports the package that imports it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import numpy as np
from numpy.typing import NDArray

from skills.vocabulary import Arm, EndEffector
from worlds.actuators import TorqueLoop

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BodySpec:
    """One fixed-base multibody to load.

    Attributes
    ----------
    urdf_path : Path
        URDF file; mesh paths inside must resolve from its folder.
    base2world_position : tuple of float
        (3,) base frame origin in the world frame, m.
    base2world_quaternion : tuple of float
        (4,) base frame orientation in the world frame, scalar-last (x, y, z, w).
    """

    urdf_path: Path
    base2world_position: tuple[float, float, float]
    base2world_quaternion: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)


def _check_joint_vectors(owner: str, spec: ArmSpec | SharedJointsSpec) -> None:
    """One value per joint in each per-joint field of ``spec``, and lower < upper."""
    n = len(spec.joint_indices)
    for name in ("rest_posture", "lower", "upper", "max_torque"):
        got = len(getattr(spec, name))
        if got != n:
            raise ValueError(f"{owner}: expected {name} of length {n}, got {got}")
    if any(lo >= hi for lo, hi in zip(spec.lower, spec.upper, strict=True)):
        raise ValueError(f"{owner}: expected lower < upper, got {spec.lower} and {spec.upper}")


@dataclass(frozen=True)
class ArmSpec:
    """One arm of a robot: a chain of revolute joints ending in an end-effector link.

    Attributes
    ----------
    body : int
        Index into :attr:`RobotModel.bodies` of the body holding this arm.
    joint_indices : tuple of int
        (n,) PyBullet joint indices of the arm, base to tip.
    palm_link : int
        PyBullet link index of the palm; its frame sits at the palm box centre, z along the
        outward normal of the contact face.
    rest_posture : tuple of float
        (n,) joint positions the null-space term pulls towards, rad.
    lower, upper : tuple of float
        (n,) joint position limits, rad.
    max_torque : tuple of float
        (n,) joint torque limits, N m.
    palm_size : tuple of float
        (3,) palm box extent along the palm frame's x, y, z axes, m.
    end_effector : EndEffector
        What the arm ends in: it fixes the grasps the reasoner may offer
        (:data:`affordances.physics.GRASP_END_EFFECTOR`).
    palm_link_name : str
        The palm link's name in the URDF (two palms on one body need two names).
    """

    body: int
    joint_indices: tuple[int, ...]
    palm_link: int
    rest_posture: tuple[float, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    max_torque: tuple[float, ...]
    palm_size: tuple[float, float, float]
    end_effector: EndEffector
    palm_link_name: str = "palm"

    def __post_init__(self) -> None:
        _check_joint_vectors("ArmSpec", self)


@dataclass(frozen=True)
class SharedJointsSpec:
    """Joints that move both arms' palms (a humanoid's torso), on the body that carries both.

    Attributes
    ----------
    body : int
        Index into :attr:`RobotModel.bodies`; both arms must be on this body.
    joint_indices : tuple of int
        (s,) PyBullet joint indices, root first.
    rest_posture : tuple of float
        (s,) joint positions the null-space term pulls towards, rad (upright).
    lower, upper : tuple of float
        (s,) joint position limits, rad.
    max_torque : tuple of float
        (s,) joint torque limits, N m.
    posture_weight : float
        Null-space posture stiffness and damping of these joints relative to the arms' (the
        torso is held upright more firmly than the arms' natural posture).
    """

    body: int
    joint_indices: tuple[int, ...]
    rest_posture: tuple[float, ...]
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    max_torque: tuple[float, ...]
    posture_weight: float = 1.0

    def __post_init__(self) -> None:
        _check_joint_vectors("SharedJointsSpec", self)
        if not (np.isfinite(self.posture_weight) and self.posture_weight >= 0.0):
            raise ValueError(
                f"SharedJointsSpec: expected posture_weight >= 0, got {self.posture_weight}"
            )


@dataclass(frozen=True)
class DrivenJoint:
    """One joint the controller drives, in its joint order (:meth:`RobotModel.driven_joints`).

    Attributes
    ----------
    body : int
        Index into :attr:`RobotModel.bodies`.
    joint : int
        PyBullet joint index on that body.
    arm : Arm or None
        The arm it belongs to; None for a shared joint.
    lower, upper, max_torque, rest : float
        Limits (rad, N m) and rest posture (rad).
    """

    body: int
    joint: int
    arm: Arm | None
    lower: float
    upper: float
    max_torque: float
    rest: float


@dataclass(frozen=True)
class RobotModel:
    """A dual-arm robot: its bodies and its two arms.

    Attributes
    ----------
    name : str
        Model name as in world files (``"kuka_iiwa"``).
    bodies : tuple of BodySpec
        Bodies to load, in order; :attr:`ArmSpec.body` indexes this tuple.
    arms : Mapping[Arm, ArmSpec]
        Both arms, keyed by :class:`skills.vocabulary.Arm`.
    palm2flange_position : tuple of float
        (3,) palm frame origin in the last arm link's frame, m (documentation and collision use).
    collision_exclusions : tuple of (int, str, int, str)
        Link pairs of different bodies that must not collide, as (body, link name, body, link
        name); ``"base"`` names a body's base link. A robot split into several bodies (iCub)
        uses this to keep PyBullet's no-self-collision default across the split.
    rest_palms : tuple of float
        Where the palms wait: (inset from the table's near edge along the robot's forward
        axis, distance from the robot's midplane, height above the table top), m
        (:func:`worlds.palm_poses.rest_palm_poses`).
    gain_overrides : Mapping[str, float]
        :class:`worlds.control.ImpedanceGains` fields that differ from the defaults for this
        robot (a light arm wants less damping), applied when no gains are given.
    arm_link_names : Mapping[Arm, frozenset of str]
        The links that move with each arm, where the arm's body carries others too (iCub's
        trunk); empty when each arm is a body of its own.
    shoulder_at_first_joint : bool
        The reasoner's arm model starts at the first arm joint's link; otherwise 0.36 m above
        the arm's base (the iiwa's second joint).
    shared_joints : SharedJointsSpec, optional
        Joints both arms' palms use (iCub's torso); None when the arms share none.
    forearm_link_names : Mapping[Arm, frozenset of str]
        The links of each arm counted as its forearm (forearm, wrist, hand; the palm apart) in
        the trials' forearm-to-obstacle figures; empty: none counted.
    torque_loop : TorqueLoop, optional
        The loop the joints' torque sensors close around each motor
        (:class:`worlds.actuators.TorqueLoop`); None: the joints sense no torque.
    """

    name: str
    bodies: tuple[BodySpec, ...]
    arms: Mapping[Arm, ArmSpec] = field(default_factory=dict)
    palm2flange_position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    collision_exclusions: tuple[tuple[int, str, int, str], ...] = ()
    rest_palms: tuple[float, float, float] = (0.10, 0.38, 0.25)
    gain_overrides: Mapping[str, float] = field(default_factory=dict)
    arm_link_names: Mapping[Arm, frozenset[str]] = field(default_factory=dict)
    shoulder_at_first_joint: bool = False
    shared_joints: SharedJointsSpec | None = None
    forearm_link_names: Mapping[Arm, frozenset[str]] = field(default_factory=dict)
    torque_loop: TorqueLoop | None = None

    def __post_init__(self) -> None:
        if set(self.arms) != {Arm.LEFT, Arm.RIGHT}:
            raise ValueError(f"RobotModel: expected arms LEFT and RIGHT, got {sorted(self.arms)}")
        for arm, spec in self.arms.items():
            if not 0 <= spec.body < len(self.bodies):
                raise ValueError(
                    f"RobotModel: arm {arm} refers to body {spec.body}, "
                    f"but there are {len(self.bodies)} bodies"
                )
        shared = self.shared_joints
        if shared is not None:
            bodies = {spec.body for spec in self.arms.values()}
            if bodies != {shared.body}:
                raise ValueError(
                    f"RobotModel: expected both arms on the shared joints' body {shared.body}, "
                    f"got bodies {sorted(bodies)}"
                )
        object.__setattr__(self, "arms", MappingProxyType(dict(self.arms)))

    def ik_cost(self, joint: DrivenJoint) -> float:
        """What moving ``joint`` costs in a whole-body palm solve (the weights ``W`` of
        :func:`worlds.palm_ik.dls_step`): 1 for an arm's joint; for a shared one, the shared
        joints' posture weight (at least 1e-3), so they move only as much as the palms need."""
        if joint.arm is not None or self.shared_joints is None:
            return 1.0
        return max(self.shared_joints.posture_weight, 1e-3)

    def driven_joints(self) -> tuple[DrivenJoint, ...]:
        """Every joint the controller drives, in its order: body by body (in the order the
        arms name them, left first), each body's joints by PyBullet index. For the iiwa pair
        that is the left arm's joints, then the right's; for iCub the torso, then both arms."""
        joints: list[DrivenJoint] = []
        bodies = list(dict.fromkeys(self.arms[arm].body for arm in (Arm.LEFT, Arm.RIGHT)))
        for body in bodies:
            here: list[DrivenJoint] = []
            for arm in (Arm.LEFT, Arm.RIGHT):
                spec = self.arms[arm]
                if spec.body != body:
                    continue
                here.extend(
                    DrivenJoint(body, j, arm, lo, hi, t, r)
                    for j, lo, hi, t, r in zip(
                        spec.joint_indices,
                        spec.lower,
                        spec.upper,
                        spec.max_torque,
                        spec.rest_posture,
                        strict=True,
                    )
                )
            shared = self.shared_joints
            if shared is not None and shared.body == body:
                here.extend(
                    DrivenJoint(body, j, None, lo, hi, t, r)
                    for j, lo, hi, t, r in zip(
                        shared.joint_indices,
                        shared.lower,
                        shared.upper,
                        shared.max_torque,
                        shared.rest_posture,
                        strict=True,
                    )
                )
            joints.extend(sorted(here, key=lambda d: d.joint))
        return tuple(joints)

    @property
    def end_effectors(self) -> frozenset[EndEffector]:
        """The kinds of end-effector the arms end in."""
        return frozenset(spec.end_effector for spec in self.arms.values())


__all__ = [
    "ArmSpec",
    "BodySpec",
    "DrivenJoint",
    "FloatArray",
    "RobotModel",
    "SharedJointsSpec",
]
