"""Which faces of a box the two palms hold: the robot's heading, the face pair for a turn and
the others that make it, the pair the palms stand beside, and its lateral grasp geometry.

The face pairs are :mod:`skills.turns`'s quarter turns, here read off the world: the object's
measured yaw, the robot's heading from its palms' rest poses, the arms' largest grip turn.
"""

from __future__ import annotations

import math

import numpy as np

from planner.fixture_moves import fixture_grasp_height
from planner.port import ObjectSensing, PalmControl, WorldPort
from skills import quaternion as quat
from skills.composer import relative_from_world
from skills.dual_arm import GraspGeometry
from skills.turns import (
    GRIP_TURN_TOLERANCE_DEG,
    grip_options,
    held_quarter_turns,
    lateral_quarter_turns,
    wrap_angle,
    yaw_of,
)
from skills.vocabulary import ARMS, Arm


def robot_yaw(world: PalmControl) -> float:
    """The robot's heading about world z, rad: its y axis runs from the right palm's rest
    pose to the left's."""
    left = world.rest_palm_pose(Arm.LEFT).position
    right = world.rest_palm_pose(Arm.RIGHT).position
    return float(np.arctan2(left[1] - right[1], left[0] - right[0]) - np.pi / 2.0)


def grasp_quarter_turns(world: WorldPort, name: str, turn: float = 0.0) -> int:
    """The face pair to grasp an object on for a turn of ``turn`` rad about z
    (:func:`skills.turns.lateral_quarter_turns`, from its measured yaw and the robot's)."""
    yaw = yaw_of(world.object_pose(name).orientation)
    return lateral_quarter_turns(yaw, turn, robot_yaw(world))


def grasp_options(world: WorldPort, name: str, turn: float = 0.0) -> list[int]:
    """The face pairs that can make a turn of ``turn`` rad about z, the usual one first
    (:func:`grasp_quarter_turns`), then any other the arms hold over the whole turn, within
    :data:`skills.turns.GRIP_TURN_TOLERANCE_DEG` (:func:`skills.turns.grip_options`)."""
    yaw = yaw_of(world.object_pose(name).orientation)
    limit = world.robot_capabilities().max_turn_rad + math.radians(GRIP_TURN_TOLERANCE_DEG)
    return grip_options(yaw, turn, limit, robot_yaw(world))


#: How far each palm may stand from its face's grasp position for :func:`facing_quarter_turns`
#: to take the palms as beside that face pair, m: an approach's stand-off, with room.
FACING_M = 0.10


def left_palm_quarter_turns(world: WorldPort, name: str) -> int:
    """The face pair whose left face lies towards the left palm, from where the palm stands in
    the object's frame (:func:`skills.turns.held_quarter_turns`): the pair held, when held."""
    pose = world.object_pose(name)
    palm = world.palm_pose(Arm.LEFT).position
    left, _ = relative_from_world(pose.position, pose.orientation, palm, quat.IDENTITY)
    return held_quarter_turns(left)


def facing_quarter_turns(world: WorldPort, name: str) -> int | None:
    """The face pair the palms stand beside (each palm within :data:`FACING_M` of its face's
    grasp position: where an approach left them), or None."""
    pose = world.object_pose(name)
    k = left_palm_quarter_turns(world, name)
    g = lateral_geometry(world, name, k)
    for arm in ARMS:
        at = pose.position + quat.rotate(pose.orientation, g.position(arm))
        if float(np.linalg.norm(world.palm_pose(arm).position - at)) > FACING_M:
            return None
    return k


def move_turn(world: ObjectSensing, name: str, index: int | None) -> float:
    """The turn about z (rad, in [-pi, pi)) from the object's measured yaw to the goal of move
    ``index`` of ``world.task_moves(name)``; 0 for ``None`` or an index out of range."""
    moves = world.task_moves(name)
    if index is None or not 0 <= index < len(moves):
        return 0.0
    now = yaw_of(world.object_pose(name).orientation)
    return wrap_angle(yaw_of(moves[index].goal.orientation) - now)


def lateral_geometry(
    world: WorldPort, name: str, quarter_turns: int | None = None
) -> GraspGeometry:
    """The two-palm lateral grasp geometry of an object's box, palms flat on a pair of side
    faces: face pair ``quarter_turns`` (:mod:`skills.turns`), by default the pair whose normals
    lie closest to the robot's y axis as the object stands now. The width is the box's extent
    between those faces."""
    k = grasp_quarter_turns(world, name) if quarter_turns is None else quarter_turns
    extents = world.object_extents(name)
    width = float(extents[1] if k % 2 == 0 else extents[0])
    # Up the faces, over the walls of a fixture the object goes into (0 in most worlds).
    height = fixture_grasp_height(world, world, name)
    return GraspGeometry.lateral(width, world.palm_thickness(), quarter_turns=k, height=height)


__all__ = [
    "FACING_M",
    "facing_quarter_turns",
    "grasp_options",
    "grasp_quarter_turns",
    "lateral_geometry",
    "left_palm_quarter_turns",
    "move_turn",
    "robot_yaw",
]
