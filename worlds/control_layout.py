"""Where the controller's joints are: the driven joints grouped by PyBullet body, each body's
palms (its tasks), and the bodies of one shape batched for one vectorised linearisation.

:func:`body_layout` is read once, when :class:`worlds.control.DualArmImpedanceController` is
made; the loop then indexes its arrays. Two iiwas are two bodies of one palm each, one batch;
the iCub is one body of two palms (its torso drives both), a batch of its own.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pybullet as pb
from numpy.typing import NDArray

from skills.vocabulary import Arm
from worlds.robots import ArmSpec
from worlds.robots.model import DrivenJoint

IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class BodyLayout:
    """The driven joints of a robot by body and batch (rows index the driven vector, in
    :meth:`worlds.robots.RobotModel.driven_joints` order; arms index ``arms``).

    Attributes
    ----------
    bodies : list of int
        PyBullet ids of the bodies with driven joints, in driven order.
    body_joints : list of list of int
        Per body, its joint indices: every movable joint, which PyBullet's Jacobian and
        inverse dynamics take.
    body_rows : list of slice
        Per body, its rows.
    body_arms : list of list of int
        Per body, the arms whose palms it carries.
    arm_rows : list of IntArray
        Per arm, its joints' rows (a shared joint belongs to no arm).
    batches : list of list of int
        Bodies of the same shape (joints, palms), by index into ``bodies``.
    batch_tasks : list of IntArray
        Per batch, (k, t) the arms of each of its bodies.
    batch_rows : list of IntArray
        Per batch, (k, n) each body's rows: a batch's joint values in one read.
    joint_arm : IntArray
        (N,) whose gains act on each joint: its arm's; a shared joint, its body's first arm's.
    """

    bodies: list[int]
    body_joints: list[list[int]]
    body_rows: list[slice]
    body_arms: list[list[int]]
    arm_rows: list[IntArray]
    batches: list[list[int]]
    batch_tasks: list[IntArray]
    batch_rows: list[IntArray]
    joint_arm: IntArray


def body_layout(
    driven: Sequence[DrivenJoint],
    specs: Sequence[ArmSpec],
    arms: Sequence[Arm],
    body_ids: Sequence[int],
    client: int,
    name: str,
) -> BodyLayout:
    """The :class:`BodyLayout` of ``driven`` joints, whose ``specs`` are those of ``arms``,
    on the loaded bodies ``body_ids`` (by the robot's body index).

    Raises
    ------
    ValueError
        Naming ``name``, if a body has a movable joint that no arm and no shared joint owns.
    """
    bodies: list[int] = []
    body_joints: list[list[int]] = []
    body_rows: list[slice] = []
    body_arms: list[list[int]] = []
    start = 0
    for index in dict.fromkeys(d.body for d in driven):
        body = int(body_ids[index])
        joints = [d.joint for d in driven if d.body == index]
        movable = [
            j
            for j in range(pb.getNumJoints(body, physicsClientId=client))
            if pb.getJointInfo(body, j, physicsClientId=client)[2] != pb.JOINT_FIXED
        ]
        if joints != movable:
            raise ValueError(
                f"{name}: expected the arms and shared joints to own all movable joints "
                f"{movable} of body {body}, got {joints}"
            )
        bodies.append(body)
        body_joints.append(joints)
        body_rows.append(slice(start, start + len(joints)))
        body_arms.append([i for i, spec in enumerate(specs) if spec.body == index])
        start += len(joints)
    arm_rows = [
        np.array([k for k, d in enumerate(driven) if d.arm is arm], dtype=np.intp) for arm in arms
    ]
    shapes: dict[tuple[int, int], list[int]] = {}
    for g, joints in enumerate(body_joints):
        shapes.setdefault((len(joints), len(body_arms[g])), []).append(g)
    batches = list(shapes.values())
    batch_tasks = [np.array([body_arms[g] for g in batch], dtype=np.intp) for batch in batches]
    batch_rows = [
        np.array([np.arange(body_rows[g].start, body_rows[g].stop) for g in batch], dtype=np.intp)
        for batch in batches
    ]
    first_arm = {specs[owned[0]].body: owned[0] for owned in body_arms}
    joint_arm = np.array(
        [list(arms).index(d.arm) if d.arm is not None else first_arm[d.body] for d in driven],
        dtype=np.intp,
    )
    return BodyLayout(
        bodies,
        body_joints,
        body_rows,
        body_arms,
        arm_rows,
        batches,
        batch_tasks,
        batch_rows,
        joint_arm,
    )


__all__ = ["BodyLayout", "body_layout"]
