"""Where the palms stand, world frame: on a pair of an object's side faces (a lateral grasp),
and at rest above the table's near edge. Poses are (position (3,), quaternion (4,)
scalar-last) pairs; palm z is the contact normal, pointing at the object.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from skills import quaternion as quat
from skills.vocabulary import Arm
from worlds.spec import Quat, SceneSpec

FloatArray = NDArray[np.float64]


def _lateral_palm_quaternions() -> dict[Arm, Quat]:
    # Palm z (the contact normal) points at the object along -+y; palm x points down.
    left = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])
    right = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
    quaternions: dict[Arm, Quat] = {}
    for arm, rotation in ((Arm.LEFT, left), (Arm.RIGHT, right)):
        x, y, z, w = quat.from_matrix(rotation).tolist()
        quaternions[arm] = (x, y, z, w)
    return quaternions


#: Palm orientations (scalar-last, world frame) of a lateral grasp on an object's +-y faces.
LATERAL_PALM_QUATERNIONS: Mapping[Arm, Quat] = _lateral_palm_quaternions()


def lateral_grasp_palm_poses(
    object_position: ArrayLike,
    half_span: float,
    palm_thickness: float,
    gap: float = 0.0,
    grip_yaw: float = 0.0,
) -> dict[Arm, tuple[FloatArray, FloatArray]]:
    """Palm poses touching (or ``gap`` outside) an object's +-y faces, object unrotated, or
    a pair of faces turned by ``grip_yaw`` about z (the palms turned with them).

    Parameters
    ----------
    object_position : array_like
        (3,) object centre, world frame, m.
    half_span : float
        Half the object's extent along y, m.
    palm_thickness : float
        Palm box thickness along its z axis, m.
    gap : float
        Distance between each palm's contact face and the object's face, m.
    grip_yaw : float
        Turn of the held faces and the palms about world z from the +-y faces, rad.

    Returns
    -------
    dict of Arm to (position (3,), quaternion (4,))
        Palm frame poses in the world frame.
    """
    centre = np.asarray(object_position, dtype=float).reshape(3)
    offset = half_span + palm_thickness / 2.0 + gap
    turn = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), float(grip_yaw))
    return {
        arm: (
            centre + quat.rotate(turn, np.array([0.0, side * offset, 0.0])),
            np.asarray(quat.multiply(turn, np.array(LATERAL_PALM_QUATERNIONS[arm])), dtype=float),
        )
        for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0))
    }


def rest_palm_poses(
    spec: SceneSpec, rest_palms: tuple[float, float, float]
) -> dict[Arm, tuple[FloatArray, FloatArray]]:
    """Where the palms wait, world frame: above the table's edge nearest the robot, facing
    inwards, in the robot's frame (:attr:`worlds.robots.model.RobotModel.rest_palms`).

    ``rest_palms`` is ``(inset, half_width, height)``: the palms stand ``inset`` m beyond the
    table's near edge along the robot's forward axis, ``half_width`` m either side of the
    robot's centre line, ``height`` m above the table top. The near edge is the table top's
    footprint's nearest point along the robot's forward axis (the robot may face the table
    from any side). Returns per arm (position (3,), quaternion (4,)); the palms' lateral
    orientation turned with the robot's heading.
    """
    table = spec.table
    yaw = math.radians(spec.robot.base_rpy_deg[2])
    forward = np.array([math.cos(yaw), math.sin(yaw)])
    left = np.array([-math.sin(yaw), math.cos(yaw)])
    base = np.asarray(spec.robot.base_position, dtype=float)[:2]
    centre = np.asarray(table.position, dtype=float)[:2]
    half = np.asarray(table.size, dtype=float)[:2] / 2.0
    corners = centre + half * np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, -1.0], [1.0, 1.0]])
    near = float(np.min((corners - base) @ forward))
    inset, half_width, height = rest_palms
    turn = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), yaw)
    z = float(table.position[2]) + height
    poses: dict[Arm, tuple[FloatArray, FloatArray]] = {}
    for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0)):
        xy = base + (near + inset) * forward + side * half_width * left
        orientation = np.asarray(
            quat.multiply(turn, np.array(LATERAL_PALM_QUATERNIONS[arm])), dtype=float
        )
        position = np.array([xy[0], xy[1], _above_objects(spec, xy, z, orientation)])
        poses[arm] = (position, orientation)
    return poses


#: Clearance a waiting palm keeps from the objects, m: nearer, it waits above them.
REST_CLEARANCE_M = 0.01


def _above_objects(spec: SceneSpec, xy: FloatArray, z: float, orientation: FloatArray) -> float:
    """The height a palm turned ``orientation`` waits at over ``xy``: ``z``, or, where its box
    would come within :data:`REST_CLEARANCE_M` of an object's bounding box, that much above the
    highest such object: an object put where a robot's palm waits (the iCub's, 14 cm to the
    side and 10 cm over the table) had been knocked off the table by the palm placed in it."""
    palm = 0.5 * np.abs(quat.to_matrix(orientation)) @ np.asarray(spec.robot.palm_size, float)
    for obj in spec.objects:
        rotation = np.abs(quat.to_matrix(np.asarray(obj.quaternion, dtype=float)))
        half = 0.5 * rotation @ np.asarray(obj.shape.extents(), dtype=float)
        centre = np.asarray(obj.position, dtype=float)
        gap = np.maximum(np.abs(np.array([*xy, z]) - centre) - half - palm, 0.0)
        if float(np.linalg.norm(gap)) < REST_CLEARANCE_M:
            z = max(z, float(centre[2] + half[2] + palm[2]) + REST_CLEARANCE_M)
    return z


__all__ = ["LATERAL_PALM_QUATERNIONS", "lateral_grasp_palm_poses", "rest_palm_poses"]
